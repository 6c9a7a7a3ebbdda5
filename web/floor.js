// The floor: a dark plane and a grid of 1 m cells with a brighter line every 10 m
// (world units are metres, ground at y = 0).
//
// Not THREE.GridHelper, though it draws the same lines: GridHelper draws each line in one
// piece, 200 m long, and a software renderer (SwiftShader in a headless browser, on a
// machine without a GPU) drops a whole line that crosses the camera's plane, so the grid
// vanished around the camera. Here every line is cut into short pieces: only the pieces
// behind the camera are lost.
import * as THREE from 'three';

const kHalfSize = 100;     // m
const kPiece = 2;          // m, length of one piece of line
const kMajorEvery = 10;    // cells

export function makeFloor(minorColour = 0x465063, majorColour = 0x7d889c) {
  const group = new THREE.Group();

  const plane = new THREE.Mesh(new THREE.PlaneGeometry(4 * kHalfSize, 4 * kHalfSize),
                               new THREE.MeshBasicMaterial({color: 0x1e232b}));
  plane.rotation.x = -Math.PI / 2;
  plane.position.y = -0.002;
  group.add(plane);

  const positions = [];
  const colours = [];
  const minor = new THREE.Color(minorColour), major = new THREE.Color(majorColour);
  for (let k = -kHalfSize; k <= kHalfSize; ++k) {
    const colour = k % kMajorEvery === 0 ? major : minor;
    for (let s = -kHalfSize; s < kHalfSize; s += kPiece) {
      positions.push(k, 0, s, k, 0, s + kPiece);   // along z at x = k
      positions.push(s, 0, k, s + kPiece, 0, k);   // along x at z = k
      for (let v = 0; v < 4; ++v) colours.push(colour.r, colour.g, colour.b);
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.Float32BufferAttribute(colours, 3));
  const lines = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({vertexColors: true, toneMapped: false}));
  group.add(lines);
  return group;
}
