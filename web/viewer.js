// The page of `mgrl serve` (docs/viewer-protocol.md): the three.js scene, the socket, and
// the glue between them. The pieces live in their own modules: protocol.js (frames and
// messages), avatars.js (bodies, targets, hit flashes), target_drag.js (target mode's
// mouse input), panel.js (controls), hud.js (read-outs), stage.js (background and
// lights), floor.js (the grid), teach.js and values_view.js (the learned values around
// avatar 0, the learning curves), learn.js (Q-learning step by step, live retraining).
import * as THREE from 'three';
import {OrbitControls} from 'three/addons/controls/OrbitControls.js';
import {Connection, PoseFrame} from './protocol.js';
import {Avatars, HitFlashes, Targets} from './avatars.js';
import {TargetDrag} from './target_drag.js';
import {makeStage} from './stage.js';
import {makeFloor} from './floor.js';
import {Panel} from './panel.js';
import {Hud} from './hud.js';
import {ValuesView} from './values_view.js';
import {Teach} from './teach.js';
import {Learn} from './learn.js';

const kKeptTimestamps = 20000;   // frame arrival times kept for window.mgrl (about 10 min)
const kKeptHits = 10000;
const kFollowHeight = 1.0;       // m, where the camera looks on the followed boxer

// ---- the three.js scene ----------------------------------------------------------

// True when WebGL runs on the CPU (SwiftShader, llvmpipe: headless browsers, machines
// without a GPU), where every pixel counts: no antialiasing there.
function softwareRendering() {
  const gl = document.createElement('canvas').getContext('webgl2');
  if (gl === null) return false;
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  gl.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

const container = document.getElementById('view');
const software = softwareRendering();
// preserveDrawingBuffer: pixelStats() and screenshots read the canvas after drawing.
const renderer = new THREE.WebGLRenderer({antialias: !software, preserveDrawingBuffer: true});
renderer.setPixelRatio(software ? 1 : Math.min(window.devicePixelRatio, 2));
container.append(renderer.domElement);

const scene3d = makeStage({background: 0x1b1f27, sky: 0xdfe8ff, ground: 0x30343c, skyIntensity: 1.6,
                           sunIntensity: 1.6, sunAt: [4, 10, 6]});

scene3d.add(makeFloor());
// Far grid lines shimmer (a software renderer draws them without antialiasing): they
// fade into the background beyond the fog's range, set by fit().
scene3d.fog = new THREE.Fog(scene3d.background, 10, 40);

const camera = new THREE.PerspectiveCamera(50, 1, 0.05, 600);
camera.position.set(2.5, 2.2, 4.5);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0, 1, 0);
controls.enableDamping = true;
controls.maxPolarAngle = Math.PI * 0.495;   // stay above the floor

const avatars = new Avatars(scene3d);
// Bodies by default; bones only for teaching (every joint visible).
document.getElementById('bones-look').addEventListener('change', (event) => {
  avatars.setLook(event.target.checked ? 'bones' : 'body');
  if (drawn !== null) avatars.update(drawn);
  dirty = true;
});
const targets = new Targets(scene3d);
const flashes = new HitFlashes(scene3d);
const valuesView = new ValuesView(scene3d);

// ---- what the page knows (also window.mgrl.state, for tests) -----------------------

const state = {
  scene: null,
  stats: null,
  hits: [],
  errors: [],
  lastError: null,
  connected: false,
  frames: {count: 0, bad: 0, times: [], last: null},
  // The page's own cost, ms (moving averages): writing the instances, the draw call,
  // and from a draw to the next animation frame (what the page waits for the picture).
  draw: {updateMs: 0, renderMs: 0, cycleMs: 0, count: 0, software: false},
  values: null,            // the teaching view's record (teach.js), set below
  learn: null,             // the learn panel's record (learn.js), set below
};
state.draw.software = software;
let latest = null;       // the newest PoseFrame
let drawn = null;        // the one on screen
let dirty = true;        // something to draw
let fitAfter = 0;        // frame the camera on the first frame received after this many
                         // (the frames that follow a scene message are of its world)
let flashesLive = false;

const hud = new Hud();
let connection = null;
const send = (message) => connection.send(message);
const panel = new Panel(send);
const teach = new Teach(send, valuesView, () => { dirty = true; });
state.values = teach.record;
const learn = new Learn(send);
state.learn = learn.record;
const drag = new TargetDrag({
  container, canvas: renderer.domElement, camera, controls, scene: scene3d, send,
  heightInput: document.getElementById('height'),
  onHeight: (h) => { document.getElementById('height-value').textContent = `${h.toFixed(2)} m`; },
});

// ---- messages --------------------------------------------------------------------

function onScene(message) {
  const previous = state.scene;
  if (!Array.isArray(message.joints) || !message.joints.every((j) => Number.isInteger(j?.parent))) {
    console.warn('mgrl: scene without a valid "joints" list; kept the previous skeleton');
  } else if (previous === null || previous.joints?.length !== message.joints.length ||
             previous.joints.some((j, k) => j.name !== message.joints[k].name || j.parent !== message.joints[k].parent)) {
    avatars.setSkeleton(message.joints);
  }
  avatars.setPartners(message.partners);
  state.scene = message;
  // A mode change (or a new crowd size) is a new world: frame it, forget its flashes.
  const newWorld = previous === null || previous.mode !== message.mode || previous.avatars !== message.avatars;
  if (newWorld) {
    fitAfter = state.frames.count;
    flashes.removeAll();
    drag.reset(message.mode === 'target');
    state.hits.length = 0;   // the old world's hits; its times restart at 0
  }
  panel.setScene(message);
  teach.setScene(message, newWorld && previous !== null);
  learn.setScene(message);
  hud.setScene(message, newWorld);
  dirty = true;
}

function onStats(message) {
  state.stats = message;
  hud.setStats(message);
  panel.setStats(message);
}

function onHit(message) {
  if (state.hits.length >= kKeptHits) state.hits.splice(0, kKeptHits / 2);
  state.hits.push(message);
  flashes.add(message, performance.now());
  avatars.strike(message, performance.now());
  hud.addHit(message);
  if (performance.now() - hudAt > 100) renderHud();   // the line shows with its flash
}

function onError(message) {
  state.lastError = String(message.message);
  state.errors.push(state.lastError);
  hud.setError(state.lastError);
}

// Each message type the server sends (docs/viewer-protocol.md) and what takes it. A Map,
// not an object: a type such as "constructor" must not find Object's.
const kHandlers = new Map([
  ['scene', onScene],
  ['stats', onStats],
  ['hit', onHit],
  ['values', (message) => teach.onValues(message)],
  ['lesson', (message) => learn.onLesson(message)],
  ['learn_step', (message) => learn.onStep(message)],
  ['retrain', (message) => learn.onRetrain(message)],
  ['error', onError],
]);

function onMessage(message) {
  const handle = kHandlers.get(message.type);
  if (handle === undefined) {
    console.warn(`mgrl: ignored a message of unknown type "${message.type}"`);
    return;
  }
  handle(message);
}

function onFrame(buffer) {
  let frame;
  try {
    frame = new PoseFrame(buffer, state.scene?.joints?.length);
  } catch (e) {
    state.frames.bad += 1;
    console.warn(`mgrl: ignored a bad frame: ${e.message}`);
    return;
  }
  const frames = state.frames;
  frames.count += 1;
  if (frames.times.length >= kKeptTimestamps) frames.times.splice(0, kKeptTimestamps / 2);
  frames.times.push(performance.now());
  frames.last = {frame: frame.frame, time: frame.time, avatars: frame.avatars, targets: frame.targets,
                 bytes: frame.byteLength};
  frame.sequence = frames.count;
  latest = frame;
  drag.setFrame(frame);
  // At once, not at the next draw: the page may be resting, and the camera must be where
  // it will be before the user (or a test) aims at anything.
  if (fitAfter !== null && frame.sequence > fitAfter) {
    fitAfter = null;
    fit(frame);
  }
}

// ---- camera ----------------------------------------------------------------------

/** Points the camera at every avatar and target of `frame`, from its current side. */
function fit(frame) {
  const box = new THREE.Box3();
  for (let i = 0; i < frame.avatars; ++i) box.expandByPoint(new THREE.Vector3(...frame.root(i)));
  for (let r = 0; r < frame.targets; ++r) box.expandByPoint(new THREE.Vector3(...frame.targetRecord(r).centre));
  if (box.isEmpty()) return;
  const centre = box.getCenter(new THREE.Vector3());
  centre.y = kFollowHeight;
  const size = box.getSize(new THREE.Vector3());
  const radius = Math.max(Math.hypot(size.x, size.z) / 2, 1.2) + 1;
  const direction = camera.position.clone().sub(controls.target).normalize();
  if (direction.y < 0.3) direction.setY(0.3).normalize();
  // A crowd fills the middle of the view; one or two boxers leave room around them to
  // drag the target to.
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * (frame.avatars > 2 ? 0.75 : 0.9);
  aim(centre, direction.multiplyScalar(distance), [1.2, 2.5]);
}

/** Looks down on avatar 0 from 60 degrees up, near enough to read the teaching view's grids. */
function lookDown(frame) {
  const root = frame.root(0);
  if (root === null) return;
  const direction = camera.position.clone().sub(controls.target).setY(0);
  if (direction.lengthSq() < 1e-8) direction.set(0, 0, 1);
  direction.normalize();
  const elevation = THREE.MathUtils.degToRad(60), distance = 6;
  const offset = direction.multiplyScalar(distance * Math.cos(elevation)).setY(distance * Math.sin(elevation));
  aim(new THREE.Vector3(root[0], 0.5, root[2]), offset, [1.5, 3]);
}

/** Looks at `target` from `target + offset`; the fog starts and ends at `fog` times that distance. */
function aim(target, offset, fog) {
  controls.target.copy(target);
  camera.position.copy(target).add(offset);
  scene3d.fog.near = offset.length() * fog[0];
  scene3d.fog.far = offset.length() * fog[1];
  controls.update();
  dirty = true;
}

function follow(frame) {
  const root = frame.root(0);
  if (root === null) return;
  const delta = new THREE.Vector3(root[0], kFollowHeight, root[2]).sub(controls.target);
  if (delta.lengthSq() < 1e-8) return;
  controls.target.add(delta);
  camera.position.add(delta);
  dirty = true;
}

document.getElementById('fit').addEventListener('click', () => { if (latest) fit(latest); });
document.getElementById('look-down').addEventListener('click', () => { if (latest) lookDown(latest); });
controls.addEventListener('change', () => { dirty = true; });

function resize() {
  renderer.setSize(container.clientWidth, container.clientHeight, false);
  camera.aspect = container.clientWidth / Math.max(container.clientHeight, 1);
  camera.updateProjectionMatrix();
  dirty = true;
}
window.addEventListener('resize', resize);
resize();

// Draws only when something changed: the server sends 30 frames a second, the screen
// may refresh faster, and a software renderer has no time to spare. When a draw keeps
// the page busy past the next animation frame (a big crowd on a software renderer
// blocks the page until the frame is out), the page rests as long before the next draw,
// so it still reads the socket and the server need not drop frames.
let drewAt = null;       // when the last draw started, until the next animation frame
let drawCost = 0;        // ms from a draw to the next animation frame
let restUntil = 0;
function tick(now) {
  requestAnimationFrame(tick);
  if (drewAt !== null) {
    drawCost = now - drewAt;
    average('cycleMs', drawCost);
    drewAt = null;
    restUntil = drawCost > 50 ? now + drawCost : 0;
  }
  if (now < restUntil) return;
  if (latest !== null && latest !== drawn) {
    const start = performance.now();
    avatars.update(latest);
    targets.update(latest);
    average('updateMs', performance.now() - start);
    drawn = latest;
    dirty = true;
  }
  if (drawn !== null && document.getElementById('follow').checked) follow(drawn);
  const live = flashes.update(now);
  if (live || flashesLive) dirty = true;
  flashesLive = live;
  controls.update();
  if (dirty) {
    const start = performance.now();
    drewAt = now;
    renderer.render(scene3d, camera);
    average('renderMs', performance.now() - start);
    state.draw.count += 1;
    dirty = false;
  }
}

function average(name, ms) {
  state.draw[name] += (ms - state.draw[name]) * 0.1;
}
requestAnimationFrame(tick);

function framesPerSecond() {
  const times = state.frames.times;
  const since = performance.now() - 1000;
  let n = 0;
  for (let k = times.length - 1; k >= 0 && times[k] > since; --k) ++n;
  return n;
}
let drawsBefore = 0, drawsAt = performance.now(), drawsPerSecond = 0;
let hudAt = 0;
function renderHud() {
  const now = performance.now();
  if (now - drawsAt >= 1000) {
    drawsPerSecond = (state.draw.count - drawsBefore) / ((now - drawsAt) / 1000);
    drawsBefore = state.draw.count;
    drawsAt = now;
  }
  hud.render(framesPerSecond(), drawsPerSecond, latest?.time, latest?.avatars, state.draw);
  hudAt = now;
}
setInterval(renderHud, 250);

// ---- the socket ------------------------------------------------------------------

connection = new Connection(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`, {
  message: onMessage,
  frame: onFrame,
  // A new connection is a new world (the server starts each page in target mode).
  open: () => { state.connected = true; state.scene = null; teach.reset(); learn.reset(); hud.setConnection('connected'); },
  close: (reason) => { state.connected = false; hud.setConnection(reason); },
});

// ---- for tests (tests/web/browser_test.mjs) --------------------------------------

window.mgrl = {
  state,
  /** Redraws the HUD now (it is otherwise redrawn a few times a second). */
  renderHud: () => renderHud(),
  /** Page pixel coordinates {x, y} of a world point [x, y, z] (m), as the camera is now. */
  project([x, y, z]) {
    camera.updateMatrixWorld();
    const v = new THREE.Vector3(x, y, z).project(camera);
    const rect = renderer.domElement.getBoundingClientRect();
    return {x: rect.left + (v.x + 1) / 2 * rect.width, y: rect.top + (1 - v.y) / 2 * rect.height};
  },
  /**
   * The bodies as drawn: the look ('body' or 'bones'), bone and joint-sphere instances, and
   * how many avatars have a struck part flashing now.
   */
  bodies: () => ({
    look: avatars.look,
    bones: avatars.bones.mesh.count,
    joints: avatars.joints.mesh.count,
    heads: avatars.heads.mesh.count,
    struck: avatars.struck.filter((s) => s.until > performance.now()).length
  }),
  /** Avatar i's root joint [x, y, z] (m) in the newest frame, or null. */
  rootOf: (i) => latest?.root(i) ?? null,
  /** The centre [x, y, z] (m) of avatar i's own target in the newest frame, or null. */
  targetOf: (i) => latest?.targetOf(i) ?? null,
  /** Sends a raw page message (an object). */
  send: (message) => connection.send(message),
  /**
   * Mean and variance of the canvas's luminance (0..255): a blank canvas has variance 0.
   * `withoutValues`: drawn once without the teaching view's heat map and path (then
   * drawn again as it was), so a test can tell what the heat map adds.
   */
  pixelStats({withoutValues = false} = {}) {
    const shown = valuesView.group.visible;
    if (withoutValues) valuesView.group.visible = false;
    renderer.render(scene3d, camera);
    valuesView.group.visible = shown;
    const source = renderer.domElement;
    const canvas = document.createElement('canvas');
    canvas.width = source.width;
    canvas.height = source.height;
    const context = canvas.getContext('2d', {willReadFrequently: true});
    context.drawImage(source, 0, 0);
    const data = context.getImageData(0, 0, canvas.width, canvas.height).data;
    let sum = 0, sumSquares = 0;
    const n = data.length / 4;
    for (let k = 0; k < data.length; k += 4) {
      const l = 0.2126 * data[k] + 0.7152 * data[k + 1] + 0.0722 * data[k + 2];
      sum += l;
      sumSquares += l * l;
    }
    const mean = sum / n;
    if (withoutValues) dirty = true;
    return {mean, variance: sumSquares / n - mean * mean};
  },
  /**
   * The teaching view now: the behaviour shown, heat-map cells and chosen-action rings
   * drawn, the last `values` message's point count, and the legend's and read-outs' text.
   */
  teach: () => ({
    behavior: state.values.behavior,
    colourBy: state.values.colourBy,
    instances: valuesView.instances,
    chosenMarks: valuesView.chosenMarks,
    points: state.values.last?.points.length ?? null,
    pathPoints: state.values.last?.path?.length ?? null,
    pathTriangles: valuesView.group.visible ? (valuesView.path.geometry.index?.count ?? 0) / 3 : 0,
    legend: {
      min: document.getElementById('legend-min').textContent,
      max: document.getElementById('legend-max').textContent,
      caption: document.getElementById('legend-caption').textContent,
      shown: !document.getElementById('teach-hud').hidden
    },
    stateLine: document.getElementById('teach-state').textContent,
  }),
  fit: () => {
    if (latest) fit(latest);
  },
};
