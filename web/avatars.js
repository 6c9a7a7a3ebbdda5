// What the world looks like on the page: every avatar's bones as one instanced mesh of
// cylinders (one instance per bone per avatar; capsule-wide in body mode, thin in bones
// mode), its joints as one of spheres (body mode) and its head as one of spheres, the
// targets and the hit flashes as instanced spheres too. Three draw calls for the
// bodies whatever the crowd's size, so a thousand boxers stay fast; a frame's joint
// positions are written straight into the instance matrices.
import * as THREE from 'three';

const kBoneRadius = 0.03;        // m
const kHandBoneRadius = 0.02;    // m
const kHeadRadius = 0.1;         // m
const kTargetRadius = 0.12;      // m
const kPoleRadius = 0.012;       // m
const kFlashSeconds = 0.6;
const kFlashPool = 128;

// Writes into `m` (a 16-float column-major slice of `array` at `at`) the transform
// that takes the unit cylinder (radius 1, height 1, along y, centred) onto the segment
// a -> b with radius r. Any basis around the axis will do (the cylinder is round); the
// one chosen keeps the determinant positive so faces keep their winding.
function writeSegment(array, at, ax, ay, az, bx, by, bz, r) {
  let dx = bx - ax, dy = by - ay, dz = bz - az;
  const length = Math.hypot(dx, dy, dz);
  if (length < 1e-6) {
    array.fill(0, at, at + 16);
    return;
  }
  dx /= length; dy /= length; dz /= length;
  // u = normalize(d x h) with h the world axis least aligned with d; w = u x d.
  let ux, uy, uz;
  if (Math.abs(dx) < 0.9) { ux = 0; uy = dz; uz = -dy; } else { ux = -dz; uy = 0; uz = dx; }
  const un = Math.hypot(ux, uy, uz);
  ux /= un; uy /= un; uz /= un;
  const wx = uy * dz - uz * dy, wy = uz * dx - ux * dz, wz = ux * dy - uy * dx;
  array[at] = ux * r; array[at + 1] = uy * r; array[at + 2] = uz * r; array[at + 3] = 0;
  array[at + 4] = dx * length; array[at + 5] = dy * length; array[at + 6] = dz * length; array[at + 7] = 0;
  array[at + 8] = wx * r; array[at + 9] = wy * r; array[at + 10] = wz * r; array[at + 11] = 0;
  array[at + 12] = (ax + bx) / 2; array[at + 13] = (ay + by) / 2; array[at + 14] = (az + bz) / 2; array[at + 15] = 1;
}

function writeSphere(array, at, x, y, z, r) {
  array.fill(0, at, at + 16);
  array[at] = r; array[at + 5] = r; array[at + 10] = r;
  array[at + 12] = x; array[at + 13] = y; array[at + 14] = z; array[at + 15] = 1;
}

// An instanced mesh that grows (by doubling) when a frame needs more instances.
class GrowingInstances {
  constructor(scene, geometry, material, withColour) {
    this.scene = scene;
    this.geometry = geometry;
    this.material = material;
    this.withColour = withColour;
    this.mesh = null;
    this.ensure(64);
  }

  ensure(capacity) {
    if (this.mesh !== null && this.mesh.instanceMatrix.count >= capacity) return false;
    let size = 64;
    while (size < capacity) size *= 2;
    if (this.mesh !== null) {
      this.scene.remove(this.mesh);
      this.mesh.dispose();
    }
    this.mesh = new THREE.InstancedMesh(this.geometry, this.material, size);
    this.mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    if (this.withColour) this.mesh.setColorAt(0, new THREE.Color(1, 1, 1));
    // The bounds move every frame: culling and picking against stale ones would be wrong.
    this.mesh.frustumCulled = false;
    this.mesh.count = 0;
    this.scene.add(this.mesh);
    return true;
  }

  get matrices() { return this.mesh.instanceMatrix.array; }

  commit(count) {
    this.mesh.count = count;
    this.mesh.instanceMatrix.clearUpdateRanges();
    this.mesh.instanceMatrix.addUpdateRange(0, count * 16);
    this.mesh.instanceMatrix.needsUpdate = true;
    this.mesh.boundingSphere = null;
  }
}

/** Colour of avatar i: sparring pairs in red and blue corners, each pair a shade apart. */
export function avatarColour(i, partners, out) {
  const partner = partners?.[i] ?? -1;
  if (partner < 0) return out.setHSL(0.07, 0.85, 0.55);  // a boxer with its own target
  const pair = Math.min(i, partner);
  const shade = ((pair * 0.618034) % 1) - 0.5;           // spread shades evenly
  return i < partner ? out.setHSL(0.0 + 0.03 * shade, 0.75, 0.5 + 0.12 * shade)
                     : out.setHSL(0.6 + 0.03 * shade, 0.75, 0.55 + 0.12 * shade);
}

// Body mode: each bone a capsule sized from its length, as the glTF export's
// body (framework/include/mgrl/motion/gltf.hpp): a cylinder of radius kBodyRadiusPerLength x length
// within [kBodyMinRadius, kBodyMaxRadius], closed by a sphere at each joint as wide as the
// widest bone meeting there. Gloves and shoes in their own colours.
const kBodyRadiusPerLength = 0.2;
const kBodyMinRadius = 0.025;  // m
const kBodyMaxRadius = 0.075;  // m
const kGloveRadius = 0.055;    // m: the fist's sphere, a glove's size
const kTrunkRadius = 0.085;    // m: bones from the pelvis and spine joints
const kNeckRadius = 0.05;      // m
const kSphereMinRadius = 0.045; // m: narrower joints get no sphere of their own
const kTrunk = /hips|pelvis|spine|chest|back/i;
const kGlove = new THREE.Color(0.93, 0.92, 0.88);  // white gloves: seen on either corner's colour
const kShoe = new THREE.Color(0.12, 0.12, 0.12);
const kStruck = new THREE.Color(1, 0.8, 0.05);
const kStruckSeconds = 0.35;

// What a joint is by its name: 'glove' (hands, fists, fingers), 'shoe' (feet, toes) or ''.
function jointKind(name) {
  if (/hand|fist|finger|thumb|wrist/i.test(name)) return 'glove';
  if (/foot|toe|ankle/i.test(name)) return 'shoe';
  return '';
}

// The body part a hit event names, as joints: the head, the chest (spine joints above the
// lowest two), the spine (the rest of the trunk).
function struckJoints(part, joints) {
  const trunk = joints.map((j, k) => ({name: j.name, k}))
                    .filter(({name}) => /spine|chest|back|neck|hips|pelvis|root|head/i.test(name));
  if (part === 'head') return trunk.filter(({name}) => /head|neck/i.test(name)).map(({k}) => k);
  if (part === 'chest') return trunk.filter(({name}) => /chest|spine[1-9]|neck/i.test(name)).map(({k}) => k);
  if (part === 'spine') return trunk.filter(({name}) => /spine|hips|pelvis|root|back/i.test(name)).map(({k}) => k);
  // A blocking arm: its forearm, hand and fingers (a guard that met a strike).
  const arm = /^(left|right)_arm$/.exec(part ?? '');
  if (arm) {
    const side = new RegExp(`^${arm[1]}|^${arm[1][0]}(?=[A-Z_])`, 'i');
    return joints.map((j, k) => ({name: j.name, k}))
        .filter(({name}) => side.test(name) && /forearm|lowerarm|hand|wrist|finger|thumb|fist/i.test(name))
        .map(({k}) => k);
  }
  return [];
}

/**
 * The bodies. Two looks: 'body' (the default: capsules, gloves, shoes) and 'bones' (thin
 * bones and a head, for teaching: every joint visible). Instanced meshes either way.
 */
export class Avatars {
  constructor(scene) {
    const material = new THREE.MeshLambertMaterial({color: 0xffffff});
    // Few vertices: a crowd multiplies them by thousands, and a page without a GPU
    // (SwiftShader) pays for each. Bones are open tubes: their ends hide in the joints.
    this.bones = new GrowingInstances(scene, new THREE.CylinderGeometry(1, 1, 1, 6, 1, true), material, true);
    this.heads = new GrowingInstances(scene, new THREE.SphereGeometry(1, 8, 6), material, true);
    this.joints = new GrowingInstances(scene, new THREE.SphereGeometry(1, 5, 2), material, true);
    this.positions = new Float32Array(0);
    this.look = 'body';
    this.struck = [];  // {avatar, joints, until}
    this.setSkeleton([]);
    this.partners = [];
    this.colouredFor = null;
  }

  /** 'body' or 'bones'. */
  setLook(look) {
    this.look = look === 'bones' ? 'bones' : 'body';
    this.colouredFor = null;
    this.measuredFor = null;
  }

  /** The skeleton of `scene.joints`: [{name, parent}], parents before children. */
  setSkeleton(joints) {
    this.skeleton = joints;
    this.jointCount = joints.length;
    this.bonePairs = [];
    this.boneRadii = [];
    this.thinRadii = [];
    joints.forEach((joint, j) => {
      if (joint.parent < 0) return;
      this.bonePairs.push(joint.parent, j);
      const hand = /hand|finger|thumb|toe/i.test(joint.name);
      this.thinRadii.push(hand ? kHandBoneRadius : kBoneRadius);
    });
    this.boneCount = this.thinRadii.length;
    this.boneRadii = this.thinRadii.slice();
    this.jointRadii = new Float32Array(joints.length).fill(kBodyMinRadius);
    this.sphereJoints = [];
    // A joint's kind passes down to its children: a hand's fingers are glove too.
    this.kinds = [];
    joints.forEach((joint, j) => {
      const own = jointKind(joint.name);
      this.kinds.push(own || (joint.parent >= 0 && this.kinds[joint.parent] === 'glove' ? 'glove' : ''));
    });
    // The head sphere sits past the head joint, along neck -> head (the BVH's head joint
    // is where the skull meets the neck; its end site is not a joint).
    this.head = joints.findIndex((joint) => /^head$/i.test(joint.name));
    if (this.head < 0) this.head = joints.findIndex((joint) => /head/i.test(joint.name));
    this.headParent = this.head >= 0 ? joints[this.head].parent : -1;
    this.colouredFor = null;
    this.measuredFor = null;
    this.struck = [];
  }

  /** Sparring partners of `scene.partners`, for the colours. */
  setPartners(partners) {
    this.partners = partners ?? [];
    this.colouredFor = null;
  }

  /** A hit message: the struck avatar's part flashes (a partner's head, chest or spine, or
   * the arm that blocked). */
  strike(hit, now) {
    if (!Number.isInteger(hit?.target) || hit.target < 0) return;
    const joints = struckJoints(hit.part, this.skeleton);
    if (joints.length === 0) return;
    this.struck = this.struck.filter((s) => s.until > now && s.avatar !== hit.target);
    this.struck.push({avatar: hit.target, joints, until: now + kStruckSeconds * 1000});
    this.colouredFor = null;
  }

  // Body radii from the bone lengths of avatar 0 in `p` (lengths do not change).
  measure(p) {
    this.jointRadii.fill(kBodyMinRadius);
    for (let b = 0; b < this.boneCount; ++b) {
      const a = this.bonePairs[2 * b] * 3, c = this.bonePairs[2 * b + 1] * 3;
      const length = Math.hypot(p[c] - p[a], p[c + 1] - p[a + 1], p[c + 2] - p[a + 2]);
      const parent = this.bonePairs[2 * b];
      const name = this.skeleton[parent].name;
      // The trunk wider than the limbs, as the glTF export's body (app/simulate_command.cpp).
      const r = kTrunk.test(name) ? kTrunkRadius :
          /neck/i.test(name)      ? kNeckRadius :
                                    Math.min(kBodyMaxRadius, Math.max(kBodyMinRadius, kBodyRadiusPerLength * length));
      // The tiny bones (a zero-length hip joint, fingers) get none.
      this.boneRadii[b] = length < 0.01 ? 0 : r;
      this.jointRadii[parent] = Math.max(this.jointRadii[parent], this.boneRadii[b]);
      this.jointRadii[this.bonePairs[2 * b + 1]] =
          Math.max(this.jointRadii[this.bonePairs[2 * b + 1]], Math.min(r, this.boneRadii[b]));
    }
    for (let j = 0; j < this.jointCount; ++j) {
      if (this.kinds[j] === 'glove' &&
          (j + 1 >= this.jointCount || this.kinds[j + 1] !== 'glove' || this.skeleton[j + 1].parent !== j)) {
        this.jointRadii[j] = Math.max(this.jointRadii[j], kGloveRadius);  // the fist: a glove
      }
    }
    // Spheres only where they show: the limbs' joints where a wide capsule bends
    // (kSphereMinRadius and up; the trunk's capsules run on nearly straight), and the fists.
    // Vertices set a software renderer's cost: a sphere at every joint made bodies a third
    // dearer to draw than bones.
    this.sphereJoints = [];
    for (let j = 0; j < this.jointCount; ++j)
      if (this.kinds[j] === 'glove' ? this.jointRadii[j] >= kGloveRadius :
          this.jointRadii[j] >= kSphereMinRadius && !kTrunk.test(this.skeleton[j].name)) this.sphereJoints.push(j);
    this.measuredFor = this.jointCount;
  }

  /** Draws `frame` (a PoseFrame whose joint count matches the skeleton). */
  update(frame, now = performance.now()) {
    const N = frame.avatars, J = frame.joints;
    if (J !== this.jointCount) return;
    if (this.positions.length < N * J * 3) this.positions = new Float32Array(N * J * 3);
    frame.jointPositions(this.positions);
    const p = this.positions;
    const body = this.look === 'body';
    if (body && N > 0 && this.measuredFor !== J) this.measure(p);
    const radii = body ? this.boneRadii : this.thinRadii;

    const grewBones = this.bones.ensure(N * this.boneCount);
    const grewHeads = this.heads.ensure(N);
    const S = body ? this.sphereJoints.length : 0;
    const grewJoints = this.joints.ensure(N * S);
    const bones = this.bones.matrices;
    let at = 0;
    for (let i = 0; i < N; ++i) {
      const base = i * J * 3;
      for (let b = 0; b < this.boneCount; ++b, at += 16) {
        const pa = base + this.bonePairs[2 * b] * 3, pb = base + this.bonePairs[2 * b + 1] * 3;
        writeSegment(bones, at, p[pa], p[pa + 1], p[pa + 2], p[pb], p[pb + 1], p[pb + 2], radii[b]);
      }
    }
    this.bones.commit(N * this.boneCount);
    if (S > 0) {
      const spheres = this.joints.matrices;
      for (let i = 0, k = 0; i < N; ++i) {
        for (const j of this.sphereJoints) {
          const q = (i * J + j) * 3;
          writeSphere(spheres, k * 16, p[q], p[q + 1], p[q + 2], this.jointRadii[j]);
          ++k;
        }
      }
    }
    this.joints.commit(N * S);

    const heads = this.heads.matrices;
    const headCount = this.head >= 0 ? N : 0;
    for (let i = 0; i < headCount; ++i) {
      const h = (i * J + this.head) * 3;
      let x = p[h], y = p[h + 1], z = p[h + 2];
      if (this.headParent >= 0) {
        const n = (i * J + this.headParent) * 3;
        const dx = x - p[n], dy = y - p[n + 1], dz = z - p[n + 2];
        const length = Math.hypot(dx, dy, dz) || 1;
        x += dx / length * kHeadRadius * 0.8; y += dy / length * kHeadRadius * 0.8; z += dz / length * kHeadRadius * 0.8;
      }
      writeSphere(heads, i * 16, x, y, z, kHeadRadius);
    }
    this.heads.commit(headCount);

    if (this.struck.length > 0 && this.struck.every((s) => s.until <= now)) {
      this.struck = [];
      this.colouredFor = null;
    }
    if (grewBones || grewHeads || grewJoints || this.colouredFor !== N) this.colour(N, now);
  }

  colour(N, now) {
    const colour = new THREE.Color(), part = new THREE.Color();
    const body = this.look === 'body';
    const struck = new Map();  // avatar -> set of joints flashing
    for (const s of this.struck)
      if (s.until > now && s.avatar < N) struck.set(s.avatar, new Set(s.joints));
    const jointColour = (j, flashing) => {
      if (flashing?.has(j)) return part.copy(kStruck);
      if (body && this.kinds[j] === 'glove') return part.copy(kGlove);
      if (body && this.kinds[j] === 'shoe') return part.copy(kShoe);
      return part.copy(colour);
    };
    for (let i = 0; i < N; ++i) {
      avatarColour(i, this.partners, colour);
      const flashing = struck.get(i);
      for (let b = 0; b < this.boneCount; ++b) {
        // A bone takes its lower joint's kind (the forearm into the glove stays the body's).
        const child = this.bonePairs[2 * b + 1], parent = this.bonePairs[2 * b];
        const j = this.kinds[parent] === this.kinds[child] ? child : parent;
        this.bones.mesh.setColorAt(i * this.boneCount + b, jointColour(j, flashing));
      }
      if (body) {
        const S = this.sphereJoints?.length ?? 0;
        this.sphereJoints?.forEach((j, k) => this.joints.mesh.setColorAt(i * S + k, jointColour(j, flashing)));
      }
      this.heads.mesh.setColorAt(i, flashing?.has(this.head) ? kStruck : colour);
    }
    this.bones.mesh.instanceColor.needsUpdate = true;
    this.heads.mesh.instanceColor.needsUpdate = true;
    if (this.joints.mesh.instanceColor) this.joints.mesh.instanceColor.needsUpdate = true;
    this.colouredFor = N;
  }
}

/** The targets: a sphere on a thin pole from the floor, one per target record. */
export class Targets {
  constructor(scene) {
    this.spheres = new GrowingInstances(scene, new THREE.SphereGeometry(1, 16, 12),
                                        new THREE.MeshLambertMaterial({color: 0xffd23f, emissive: 0x332200}), false);
    this.poles = new GrowingInstances(scene, new THREE.CylinderGeometry(1, 1, 1, 6, 1),
                                      new THREE.MeshLambertMaterial({color: 0x8a8f99}), false);
    this.avatarOf = [];   // instance -> avatar index, for picking
  }

  get mesh() { return this.spheres.mesh; }

  update(frame) {
    const T = frame.targets;
    this.spheres.ensure(T);
    this.poles.ensure(T);
    this.avatarOf.length = T;
    for (let r = 0; r < T; ++r) {
      const {avatar, centre: [x, y, z]} = frame.targetRecord(r);
      this.avatarOf[r] = avatar;
      writeSphere(this.spheres.matrices, r * 16, x, y, z, kTargetRadius);
      writeSegment(this.poles.matrices, r * 16, x, 0, z, x, Math.max(0, y - kTargetRadius), z, kPoleRadius);
    }
    this.spheres.commit(T);
    this.poles.commit(T);
  }
}

/** Short-lived spheres where punches land, sized by the fist's speed. */
export class HitFlashes {
  constructor(scene) {
    const material = new THREE.MeshBasicMaterial({color: 0xfff3b0, transparent: true, opacity: 0.75, depthWrite: false});
    this.flashes = new GrowingInstances(scene, new THREE.SphereGeometry(1, 12, 8), material, false);
    this.flashes.ensure(kFlashPool);
    this.live = [];   // {x, y, z, radius, born}
  }

  /** A `hit` message: point [x, y, z] in metres, speed in m/s. */
  add(hit, now) {
    if (!Array.isArray(hit.point) || hit.point.length !== 3) return;
    if (this.live.length >= kFlashPool) this.live.shift();
    const speed = Number.isFinite(hit.speed) ? hit.speed : 1;
    this.live.push({x: hit.point[0], y: hit.point[1], z: hit.point[2],
                    radius: 0.03 + 0.012 * Math.min(speed, 10), born: now});
  }

  removeAll() { this.live.length = 0; this.flashes.commit(0); }

  /** Animates the flashes at time `now` (ms); true while any is showing. */
  update(now) {
    this.live = this.live.filter((flash) => now - flash.born < kFlashSeconds * 1000);
    const m = this.flashes.matrices;
    this.live.forEach((flash, k) => {
      const age = (now - flash.born) / (kFlashSeconds * 1000);
      // Swells fast, then shrinks away.
      const r = flash.radius * (age < 0.25 ? 1 + 3 * age : 1.75 * (1 - age) / 0.75);
      writeSphere(m, k * 16, flash.x, flash.y, flash.z, Math.max(r, 0));
    });
    this.flashes.commit(this.live.length);
    return this.live.length > 0;
  }
}
