// The page's pose-frame reader (web/protocol.js) on frames built here by hand, one bad
// frame per case: `node --test tests/web/protocol_test.mjs` (no browser, no server).
import {test} from 'node:test';
import assert from 'node:assert/strict';
import {PoseFrame, avatarRecordBytes, throttled} from '../../web/protocol.js';

// A frame as docs/viewer-protocol.md lays it out: avatars = [{root, offsetsMm}], targets
// = [{avatar, centre}].
function buildFrame({joints, avatars, targets = [], frame = 7, time = 0.25, magic = 'MGRF', version = 1}) {
  const bytes = 24 + avatars.length * avatarRecordBytes(joints) + targets.length * 16;
  const view = new DataView(new ArrayBuffer(bytes));
  [...magic].forEach((c, k) => view.setUint8(k, c.charCodeAt(0)));
  view.setUint16(4, version, true);
  view.setUint16(6, joints, true);
  view.setUint32(8, avatars.length, true);
  view.setUint32(12, targets.length, true);
  view.setUint32(16, frame, true);
  view.setFloat32(20, time, true);
  let at = 24;
  for (const {root, offsetsMm} of avatars) {
    root.forEach((v, k) => view.setFloat32(at + 4 * k, v, true));
    at += 12;
    for (const offset of offsetsMm) {
      offset.forEach((v, k) => view.setInt16(at + 2 * k, v, true));
      at += 6;
    }
  }
  for (const {avatar, centre} of targets) {
    view.setUint32(at, avatar, true);
    centre.forEach((v, k) => view.setFloat32(at + 4 + 4 * k, v, true));
    at += 16;
  }
  return view.buffer;
}

const twoJoints = {
  joints: 2,
  avatars: [
    {root: [1, 0.5, -2], offsetsMm: [[0, 0, 0], [100, -250, 32767]]},
    {root: [-3, 1, 4], offsetsMm: [[0, 0, 0], [-32767, 5, 0]]},
  ],
  targets: [{avatar: 1, centre: [0.5, 1.5, 2.5]}],
};

const near = (actual, expected) =>
  expected.forEach((v, k) => assert.ok(Math.abs(actual[k] - v) < 1e-5, `component ${k}: ${actual[k]} vs ${v}`));

test('a well-formed frame gives its header, roots, joints and targets', () => {
  const frame = new PoseFrame(buildFrame(twoJoints), 2);
  assert.equal(frame.avatars, 2);
  assert.equal(frame.targets, 1);
  assert.equal(frame.frame, 7);
  assert.equal(frame.time, 0.25);
  near(frame.root(1), [-3, 1, 4]);
  assert.equal(frame.root(2), null);
  const positions = new Float32Array(2 * 2 * 3);
  frame.jointPositions(positions);
  near(positions, [1, 0.5, -2, 1.1, 0.25, 30.767, -3, 1, 4, -35.767, 1.005, 4]);
  near(frame.targetOf(1), [0.5, 1.5, 2.5]);
  assert.equal(frame.targetOf(0), null);
});

test('a frame of no avatars and no targets is 24 bytes and valid', () => {
  const frame = new PoseFrame(buildFrame({joints: 31, avatars: []}), 31);
  assert.equal(frame.avatars, 0);
  assert.equal(frame.byteLength, 24);
});

test('a frame shorter than its header is refused', () => {
  assert.throws(() => new PoseFrame(new ArrayBuffer(10)), /expected at least 24 bytes, found 10/);
});

test('a frame with the wrong magic is refused', () => {
  assert.throws(() => new PoseFrame(buildFrame({...twoJoints, magic: 'MGRX'})), /expected magic 'MGRF'/);
});

test('a frame of another version is refused', () => {
  assert.throws(() => new PoseFrame(buildFrame({...twoJoints, version: 2})), /expected version 1, found 2/);
});

test('a frame whose joint count differs from the scene is refused', () => {
  assert.throws(() => new PoseFrame(buildFrame(twoJoints), 31), /expected 31 joints per avatar \(scene\), found 2/);
});

test('a frame with bytes missing or left over is refused', () => {
  const whole = buildFrame(twoJoints);
  assert.throws(() => new PoseFrame(whole.slice(0, whole.byteLength - 1)), /expected 88 bytes .* found 87/);
  const longer = new Uint8Array(whole.byteLength + 4);
  longer.set(new Uint8Array(whole));
  assert.throws(() => new PoseFrame(longer.buffer), /expected 88 bytes .* found 92/);
});

test('throttled sends the first message at once and the newest one later', async () => {
  const sent = [];
  const send = throttled((m) => sent.push(m), 40);
  send(1);
  send(2);
  send(3);
  assert.deepEqual(sent, [1]);
  await new Promise((resolve) => setTimeout(resolve, 80));
  assert.deepEqual(sent, [1, 3]);
  send(4);
  send.flush();
  assert.deepEqual(sent, [1, 3, 4]);
});
