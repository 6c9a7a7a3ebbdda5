// The teaching view in the scene (paper sec. 5): one behaviour's learned values on the
// vertices of its grid around avatar 0, as a `values` message gives them
// (docs/viewer-protocol.md). Each vertex is drawn as a flat cell centred on it, coloured
// by V = max_a Q or by its greedy action; a ring marks the vertices whose greedy action is
// the one the avatar took; a ribbon on the floor shows that action's root path.
//
// The grids are polar (a disc on the floor) or cylindrical (a horizontal slice of the 3-D
// grid at the target's height), but the page is told only the vertices' positions, so a
// cell's shape comes from its neighbours: its first side spans the distance to the
// nearest vertex, its second the spacing across that direction. Cells of a polar grid
// then tile it ring by ring. One instanced mesh draws all the cells, another the rings.
import * as THREE from 'three';
import {actionColour, viridis} from './colormap.js';

const kFloorLift = 0.008;    // m, cells of a floor grid above the floor's lines
const kPathLift = 0.016;     // m, the path above the cells
const kPathWidth = 0.05;     // m
const kFill = 0.95;          // share of the spacing a cell covers: thin gaps show the grid
const kCoincident = 1e-3;    // m, vertices closer than this are one (a polar grid's centre)
const kMinCell = 0.01, kMaxCell = 1.5;   // m
const kFloorGridBelow = 0.05;            // m: a layer this low is the floor
const kSliceOpacity = 0.72;
const kFloorOpacity = 0.88;

/** How many instances a mesh of capacity >= n holds (doubling from 256). */
function capacityFor(n) {
  let size = 256;
  while (size < n) size *= 2;
  return size;
}

// For each vertex i of a horizontal layer: j1, its nearest vertex, and j2, the nearest
// whose direction from i is more than 60 degrees away from j1's (-1 when there is none).
// O(n^2); a layer is at most a few thousand vertices and is worked out once per grid.
function neighbours(points) {
  const n = points.length;
  const near = new Int32Array(n).fill(-1), across = new Int32Array(n).fill(-1);
  for (let i = 0; i < n; ++i) {
    const [xi, , zi] = points[i];
    let best = Infinity;
    for (let j = 0; j < n; ++j) {
      const d = Math.hypot(points[j][0] - xi, points[j][2] - zi);
      if (d > kCoincident && d < best) { best = d; near[i] = j; }
    }
    if (near[i] < 0) continue;
    const ux = (points[near[i]][0] - xi) / best, uz = (points[near[i]][2] - zi) / best;
    let second = Infinity;
    for (let j = 0; j < n; ++j) {
      const dx = points[j][0] - xi, dz = points[j][2] - zi;
      const d = Math.hypot(dx, dz);
      if (d > kCoincident && d < second && Math.abs(dx * ux + dz * uz) < 0.5 * d) { second = d; across[i] = j; }
    }
  }
  return {near, across};
}

export class ValuesView {
  constructor(scene) {
    this.scene = scene;
    this.group = new THREE.Group();
    this.group.visible = false;
    scene.add(this.group);

    this.cellGeometry = new THREE.PlaneGeometry(1, 1).rotateX(-Math.PI / 2);
    this.cellMaterial = new THREE.MeshBasicMaterial({
      color: 0xffffff, transparent: true, opacity: kFloorOpacity, depthWrite: false,
      side: THREE.DoubleSide, toneMapped: false, fog: false,
    });
    this.ringGeometry = new THREE.RingGeometry(0.62, 0.82, 20).rotateX(-Math.PI / 2);
    this.ringMaterial = new THREE.MeshBasicMaterial({color: 0xffffff, side: THREE.DoubleSide, toneMapped: false, fog: false});
    this.cells = null;
    this.rings = null;
    this.ensure(256);

    this.path = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshBasicMaterial({
      color: 0xff4fd8, side: THREE.DoubleSide, toneMapped: false, fog: false,
    }));
    this.path.renderOrder = 3;
    this.path.frustumCulled = false;
    this.group.add(this.path);

    this.layout = null;      // {key, near, across, check} of the grid last drawn
    this.chosenCount = 0;
    this.colour = new THREE.Color();
  }

  ensure(n) {
    if (this.cells !== null && this.cells.instanceMatrix.count >= n) return;
    const size = capacityFor(n);
    for (const mesh of [this.cells, this.rings]) {
      if (mesh === null) continue;
      this.group.remove(mesh);
      mesh.dispose();
    }
    this.cells = new THREE.InstancedMesh(this.cellGeometry, this.cellMaterial, size);
    this.cells.setColorAt(0, new THREE.Color(1, 1, 1));
    this.rings = new THREE.InstancedMesh(this.ringGeometry, this.ringMaterial, size);
    for (const [mesh, order] of [[this.cells, 1], [this.rings, 2]]) {
      mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
      mesh.frustumCulled = false;   // the bounds move with the avatar
      mesh.renderOrder = order;
      mesh.count = 0;
      this.group.add(mesh);
    }
  }

  /** Cells currently drawn (0 when hidden). */
  get instances() { return this.group.visible ? this.cells.count : 0; }

  /** Rings currently drawn: vertices whose greedy action is the chosen one. */
  get chosenMarks() { return this.group.visible ? this.rings.count : 0; }

  clear() {
    this.group.visible = false;
    this.cells.count = 0;
    this.rings.count = 0;
    this.chosenCount = 0;
  }

  /**
   * Draws a checked `values` message (points [[x, y, z, V, greedy], ...] in world metres,
   * path [[x, 0, z], ...]), coloured by 'value' (v_min..v_max) or 'greedy'.
   */
  update(message, colourBy) {
    const points = message.points;
    const n = points.length;
    this.ensure(n);
    const layout = this.layoutOf(message);
    const floor = Math.abs(message.height) < kFloorGridBelow;
    this.cellMaterial.opacity = floor ? kFloorOpacity : kSliceOpacity;
    const lift = floor ? kFloorLift : 0;
    const span = message.v_max - message.v_min;
    const cells = this.cells.instanceMatrix.array, rings = this.rings.instanceMatrix.array;
    let marked = 0;
    for (let i = 0; i < n; ++i) {
      const [x, y, z, value, greedy] = points[i];
      // The cell's axes: u toward the nearest vertex, w across it.
      let ux = 1, uz = 0, su = 0.1, sw = 0.1;
      const j = layout.near[i];
      if (j >= 0) {
        const dx = points[j][0] - x, dz = points[j][2] - z;
        su = Math.hypot(dx, dz);
        ux = dx / su; uz = dz / su;
        const k = layout.across[i];
        sw = k >= 0 ? Math.abs((points[k][0] - x) * -uz + (points[k][2] - z) * ux) : su;
      }
      su = Math.min(kMaxCell, Math.max(kMinCell, su * kFill));
      sw = Math.min(kMaxCell, Math.max(kMinCell, sw * kFill));
      writeFlat(cells, i * 16, x, y + lift, z, ux, uz, su, sw);

      if (colourBy === 'greedy') {
        const [r, g, b] = actionColour(greedy);
        this.colour.setRGB(r, g, b, THREE.SRGBColorSpace);
      } else {
        const [r, g, b] = viridis(span > 0 ? (value - message.v_min) / span : 0.5);
        this.colour.setRGB(r, g, b, THREE.SRGBColorSpace);
      }
      this.cells.setColorAt(i, this.colour);

      if (greedy === message.chosen) {
        const size = 0.4 * Math.min(su, sw);
        writeFlat(rings, marked * 16, x, y + lift + 0.004, z, ux, uz, size, size);
        ++marked;
      }
    }
    this.cells.count = n;
    this.rings.count = marked;
    this.chosenCount = marked;
    for (const mesh of [this.cells, this.rings]) mesh.instanceMatrix.needsUpdate = true;
    this.cells.instanceColor.needsUpdate = true;
    this.setPath(message.path);
    this.group.visible = true;
  }

  // Which vertices neighbour which depends only on the grid (the message places it
  // rigidly around the avatar): worked out again only for another grid or layer.
  layoutOf(message) {
    const points = message.points;
    const key = `${message.behavior}|${points.length}|${message.height}`;
    const l = this.layout;
    if (l !== null && l.key === key) {
      // A rigid placement keeps distances: the first vertex's nearest is as far as before.
      const j = l.near[0];
      const d = j >= 0 ? Math.hypot(points[j][0] - points[0][0], points[j][2] - points[0][2]) : 0;
      if (Math.abs(d - l.check) < 0.01) return l;
    }
    const {near, across} = neighbours(points);
    const j = near[0];
    const check = j >= 0 ? Math.hypot(points[j][0] - points[0][0], points[j][2] - points[0][2]) : 0;
    this.layout = {key, near, across, check};
    return this.layout;
  }

  // A flat ribbon along the path, with an arrowhead at its end.
  setPath(path) {
    const positions = [];
    const index = [];
    const m = Array.isArray(path) ? path.length : 0;
    let last = null;
    for (let k = 0; k < m; ++k) {
      const [x, , z] = path[k];
      const [ax, , az] = path[Math.max(0, k - 1)], [bx, , bz] = path[Math.min(m - 1, k + 1)];
      let dx = bx - ax, dz = bz - az;
      const length = Math.hypot(dx, dz);
      if (length < 1e-6) {
        if (last === null) continue;
        [dx, dz] = last;
      } else {
        dx /= length; dz /= length;
      }
      last = [dx, dz];
      const base = positions.length / 3;
      const h = kPathWidth / 2;
      positions.push(x - dz * h, kPathLift, z + dx * h, x + dz * h, kPathLift, z - dx * h);
      if (base > 0) index.push(base - 2, base - 1, base, base - 1, base + 1, base);
    }
    if (last !== null && m > 0) {
      const [x, , z] = path[m - 1];
      const [dx, dz] = last;
      const base = positions.length / 3;
      const w = kPathWidth * 1.6, l = kPathWidth * 2.4;
      positions.push(x - dz * w, kPathLift, z + dx * w, x + dz * w, kPathLift, z - dx * w,
                     x + dx * l, kPathLift, z + dz * l);
      index.push(base, base + 1, base + 2);
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
    geometry.setIndex(index);
    this.path.geometry.dispose();
    this.path.geometry = geometry;
  }
}

// A flat instance: the unit square (or ring) in the floor's plane scaled to su along
// (ux, 0, uz) and sw across it, at (x, y, z). Column-major; determinant positive.
function writeFlat(array, at, x, y, z, ux, uz, su, sw) {
  array[at] = ux * su; array[at + 1] = 0; array[at + 2] = uz * su; array[at + 3] = 0;
  array[at + 4] = 0; array[at + 5] = 1; array[at + 6] = 0; array[at + 7] = 0;
  array[at + 8] = -uz * sw; array[at + 9] = 0; array[at + 10] = ux * sw; array[at + 11] = 0;
  array[at + 12] = x; array[at + 13] = y; array[at + 14] = z; array[at + 15] = 1;
}
