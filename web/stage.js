// The stage: an empty three.js scene on a plain background, lit from everywhere by a
// hemisphere light and from one side by a sun. The viewer and the glTF test's page
// (tests/web/gltf_test.mjs) set theirs up here, each with its own colours.
import * as THREE from 'three';

/**
 * A scene with a `background` colour, a hemisphere light (`sky` colour from above,
 * `ground` from below, `skyIntensity`) and a white directional sun of `sunIntensity`
 * shining from `sunAt` [x, y, z] (m) toward the origin.
 */
export function makeStage({background, sky, ground, skyIntensity, sunIntensity, sunAt}) {
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(background);
  scene.add(new THREE.HemisphereLight(sky, ground, skyIntensity));
  const sun = new THREE.DirectionalLight(0xffffff, sunIntensity);
  sun.position.set(...sunAt);
  scene.add(sun);
  return scene;
}
