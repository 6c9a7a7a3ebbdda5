// Target mode's input (paper sec. 6.6: the user moves the target and the boxer goes
// after it): the target sphere dragged over the floor with the mouse, its height set by
// the wheel over it or by a slider. Sends `move_target` at most ~30 times a second.
import * as THREE from 'three';
import {throttled} from './protocol.js';

export const kHeightMin = 0.5;   // m, the slider's range
export const kHeightMax = 2.2;
const kReach = 100;              // |x|, |z| the server accepts, m
const kPickRadius = 0.25;        // how near the sphere's centre a click counts, m
const kWheelStep = 0.05;         // m per wheel notch

const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));

export class TargetDrag {
  /**
   * @param options.container  element around the canvas (its capture listeners run
   *                           before OrbitControls' on the canvas)
   * @param options.canvas     the renderer's canvas
   * @param options.camera     the camera rays are cast from
   * @param options.controls   OrbitControls, disabled while dragging
   * @param options.scene      for the floor marker
   * @param options.send       sends one page message
   * @param options.heightInput  <input type=range> for the height
   * @param options.onHeight   called with the height shown (m) when it changes
   */
  constructor(options) {
    Object.assign(this, options);
    this.enabled = false;      // target mode only
    this.frame = null;         // the newest PoseFrame
    this.base = null;          // {x, z}: where the target's base was last put, m
    this.moved = false;        // by this page; until then the server moves it every few s
    this.height = 1.4;         // m
    this.dragging = false;
    this.pointerId = null;
    this.raycaster = new THREE.Raycaster();
    this.floor = new THREE.Plane(new THREE.Vector3(0, 1, 0), 0);
    this.sendMove = throttled((message) => this.send(message), 33);

    this.marker = new THREE.Mesh(new THREE.RingGeometry(0.16, 0.22, 32),
                                 new THREE.MeshBasicMaterial({color: 0xffd23f, side: THREE.DoubleSide}));
    this.marker.rotation.x = -Math.PI / 2;
    this.marker.position.y = 0.005;
    this.marker.visible = false;
    this.scene.add(this.marker);

    const capture = {capture: true};
    this.container.addEventListener('pointerdown', (e) => this.pointerDown(e), capture);
    this.container.addEventListener('pointermove', (e) => this.pointerMove(e), capture);
    this.container.addEventListener('pointerup', (e) => this.pointerUp(e), capture);
    this.container.addEventListener('pointercancel', (e) => this.pointerUp(e), capture);
    this.container.addEventListener('wheel', (e) => this.wheel(e), {capture: true, passive: false});
    this.heightInput.min = kHeightMin;
    this.heightInput.max = kHeightMax;
    this.heightInput.step = 0.01;
    this.heightInput.addEventListener('input', () => this.setHeight(Number(this.heightInput.value)));
  }

  /** A new world (scene): the next frame tells where its target is. */
  reset(enabled) {
    this.enabled = enabled;
    this.base = null;
    this.moved = false;
    this.endDrag();
  }

  /**
   * The newest frame. Until this page moves the target, the server moves it now and then
   * (world mode `targets`): the frames say where it is, and the height shown follows.
   */
  setFrame(frame) {
    this.frame = frame;
    if (!this.enabled || this.moved) return;
    const centre = frame.targetOf(0);
    if (centre === null) return;
    this.base = {x: centre[0], z: centre[2]};
    this.showHeight(clamp(centre[1], kHeightMin, kHeightMax));
  }

  showHeight(height) {
    this.height = height;
    this.heightInput.value = height.toFixed(2);
    this.onHeight?.(height);
  }

  setHeight(height) {
    this.showHeight(clamp(height, kHeightMin, kHeightMax));
    this.move();
  }

  move() {
    if (!this.enabled || this.base === null) return;
    this.moved = true;
    this.sendMove({type: 'move_target', position: [this.base.x, this.height, this.base.z]});
  }

  ray(event) {
    const rect = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2((event.clientX - rect.left) / rect.width * 2 - 1,
                                  -(event.clientY - rect.top) / rect.height * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    return this.raycaster.ray;
  }

  overTarget(event) {
    if (!this.enabled || this.frame === null) return false;
    const centre = this.frame.targetOf(0);
    if (centre === null) return false;
    return this.ray(event).distanceToPoint(new THREE.Vector3(...centre)) < kPickRadius;
  }

  pointerDown(event) {
    if (event.button !== 0 || !this.overTarget(event)) return;
    // Ours, not the orbit's: it must not turn the camera while the target moves.
    event.stopPropagation();
    event.preventDefault();
    this.dragging = true;
    this.pointerId = event.pointerId;
    this.controls.enabled = false;
    this.canvas.setPointerCapture?.(event.pointerId);
    this.canvas.style.cursor = 'grabbing';
  }

  pointerMove(event) {
    if (!this.dragging) {
      if (this.enabled) this.canvas.style.cursor = this.overTarget(event) ? 'grab' : '';
      return;
    }
    if (event.pointerId !== this.pointerId) return;
    event.stopPropagation();
    const point = new THREE.Vector3();
    if (this.ray(event).intersectPlane(this.floor, point) === null) return;  // above the horizon
    this.base = {x: clamp(point.x, -kReach, kReach), z: clamp(point.z, -kReach, kReach)};
    this.marker.position.set(this.base.x, 0.005, this.base.z);
    this.marker.visible = true;
    this.move();
  }

  pointerUp(event) {
    if (!this.dragging || event.pointerId !== this.pointerId) return;
    event.stopPropagation();
    this.sendMove.flush();
    this.endDrag();
  }

  endDrag() {
    if (this.dragging && this.pointerId !== null) this.canvas.releasePointerCapture?.(this.pointerId);
    this.dragging = false;
    this.pointerId = null;
    this.controls.enabled = true;
    this.marker.visible = false;
    this.canvas.style.cursor = '';
  }

  wheel(event) {
    if (!this.overTarget(event)) return;
    event.stopPropagation();
    event.preventDefault();
    this.setHeight(this.height - Math.sign(event.deltaY) * kWheelStep);
  }
}
