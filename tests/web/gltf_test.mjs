// `mgrl simulate --gltf-out` checked by others' code: every .glb of FOLDER passes
// the Khronos glTF validator (npm gltf-validator) with no error, and three.js's GLTFLoader
// in headless Chromium loads it as a skinned figure whose joints, animated by the file's
// own clip, stand where three.js's BVHLoader puts the same joints of the same run's BVH
// (FOLDER/avatar_NNN.bvh, centimetres) at the same frames, within a millimetre. A
// screenshot of the loaded bodies goes to SCREENSHOT.png.
//
//   node tests/web/gltf_test.mjs FOLDER [SCREENSHOT.png]
import fs from 'node:fs';
import {createRequire} from 'node:module';
import path from 'node:path';
import {fileURLToPath} from 'node:url';

const repo = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const requireWeb = createRequire(path.join(repo, 'web/package.json'));
const {chromium} = requireWeb('playwright-core');
const validator = requireWeb('gltf-validator');

const [folder, screenshot] = process.argv.slice(2);
if (!folder) {
  console.error('usage: node tests/web/gltf_test.mjs FOLDER [SCREENSHOT.png]');
  process.exit(2);
}
const timer = setTimeout(() => {
  console.error('gltf_test: no result within 90 s');
  process.exit(1);
}, 90_000);

let failed = 0;
function check(condition, what, detail = '') {
  console.log(`${condition ? 'ok  ' : 'FAIL'} - ${what}${detail ? ': ' + detail : ''}`);
  if (!condition) failed += 1;
}

const manifest = JSON.parse(fs.readFileSync(path.join(folder, 'manifest.json'), 'utf8'));
const glbs = manifest.files.map((f) => f.file).filter((name) => name.endsWith('.glb'));
check(glbs.length >= 1, 'the manifest lists .glb files', glbs.join(', '));

// 1. The Khronos validator: no errors. Warnings and infos are printed, not failed.
for (const name of glbs) {
  const bytes = new Uint8Array(fs.readFileSync(path.join(folder, name)));
  const report = await validator.validateBytes(bytes, {uri: name, maxIssues: 50});
  const {numErrors, numWarnings, numInfos, messages} = report.issues;
  check(numErrors === 0, `gltf-validator: ${name} has no error`,
        `${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos` +
        messages.filter((m) => m.severity <= 1).slice(0, 8).map((m) => `\n    ${m.code} ${m.pointer ?? ''}: ${m.message}`).join(''));
  check(report.info.animationCount === 1 && report.info.hasSkins, `gltf-validator: ${name} has one animation and a skin`);
}

// 2. three.js in Chromium. Every request goes to a made-up origin answered from disk, so the
// page loads nothing from the network. The page lights its scene as the viewer does
// (web/stage.js), in colours of its own.
const files = {
  '/three/': path.join(repo, 'web/node_modules/three/'),
  '/web/': path.join(repo, 'web/'),
  '/out/': path.resolve(folder) + '/',
};
const page_html = `<!doctype html><html><head><meta charset="utf-8">
<script type="importmap">{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}</script>
</head><body style="margin:0"><canvas id="c" width="960" height="540"></canvas></body></html>`;

const browser = await chromium.launch({
  executablePath: process.env.MGRL_CHROMIUM ?? '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
         '--disable-component-update', '--no-first-run'],
});
try {
  const page = await browser.newPage({viewport: {width: 960, height: 540}});
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.route('**/*', async (route) => {
    const url = new URL(route.request().url());
    if (url.origin !== 'http://mgrl.test') return route.abort();
    if (url.pathname === '/') return route.fulfill({contentType: 'text/html', body: page_html});
    for (const [prefix, dir] of Object.entries(files)) {
      if (!url.pathname.startsWith(prefix)) continue;
      const file = path.resolve(dir, decodeURIComponent(url.pathname.slice(prefix.length)));
      if (!file.startsWith(dir) || !fs.existsSync(file)) return route.fulfill({status: 404, body: ''});
      const type = file.endsWith('.js') ? 'text/javascript' : 'application/octet-stream';
      return route.fulfill({contentType: type, body: fs.readFileSync(file)});
    }
    return route.fulfill({status: 404, body: ''});
  });
  await page.goto('http://mgrl.test/');
  const result = await page.evaluate(async (names) => {
    const THREE = await import('three');
    const {GLTFLoader} = await import('three/addons/loaders/GLTFLoader.js');
    const {BVHLoader} = await import('three/addons/loaders/BVHLoader.js');
    const {makeStage} = await import('/web/stage.js');
    const worldPositions = (root, mixer, time, scale) => {
      mixer.setTime(time);
      root.updateMatrixWorld(true);
      const out = new Map();
      root.traverse((o) => {
        if (o.isBone || o.userData.joint) out.set(o.name, new THREE.Vector3().setFromMatrixPosition(o.matrixWorld).multiplyScalar(scale));
      });
      return out;
    };
    const scene = makeStage({background: 0xeef0f4, sky: 0xffffff, ground: 0x667788, skyIntensity: 2.0,
                             sunIntensity: 1.5, sunAt: [3, 6, 4]});
    const floor = new THREE.Mesh(new THREE.PlaneGeometry(20, 20), new THREE.MeshLambertMaterial({color: 0xbfc5cc}));
    floor.rotation.x = -Math.PI / 2;
    scene.add(floor);
    const out = [];
    const figures = [];
    for (const name of names) {
      const gltf = await new GLTFLoader().loadAsync('/out/' + name);
      const bvh = await new BVHLoader().loadAsync('/out/' + name.replace(/\.glb$/, '.bvh'));
      let skinned = null;
      gltf.scene.traverse((o) => { if (o.isSkinnedMesh) skinned = o; });
      const bones = skinned ? skinned.skeleton.bones.length : 0;
      gltf.scene.traverse((o) => { if (o.isBone) o.userData.joint = true; });
      const clip = gltf.animations[0];
      const mixer = new THREE.AnimationMixer(gltf.scene);
      mixer.clipAction(clip).play();
      const bvhRoot = new THREE.Group();
      bvhRoot.add(bvh.skeleton.bones[0]);
      const bvhMixer = new THREE.AnimationMixer(bvhRoot);
      bvhMixer.clipAction(bvh.clip).play();
      const times = gltf.parser.json.accessors[gltf.parser.json.animations[0].samplers[0].input];
      const duration = times.max[0];
      const frames = bvh.clip.tracks[0].times.length;
      const dt = frames > 1 ? duration / (frames - 1) : 0;
      let worst = 0, compared = 0, worstJoint = '';
      for (const frame of [0, 1, Math.floor(frames / 3), Math.floor(frames / 2), frames - 2]) {
        if (frame < 0 || frame >= frames) continue;
        const time = frame * dt;
        const a = worldPositions(gltf.scene, mixer, time, 1);
        const b = worldPositions(bvhRoot, bvhMixer, time, 0.01);  // the BVH is in centimetres
        for (const [joint, p] of a) {
          if (!b.has(joint)) continue;
          const d = p.distanceTo(b.get(joint));
          compared += 1;
          if (d > worst) { worst = d; worstJoint = `${joint} at frame ${frame}`; }
        }
      }
      out.push({name, bones, frames, duration, worst, worstJoint, compared,
                bvhJoints: bvh.skeleton.bones.filter((b) => b.name !== 'ENDSITE').length,
                vertices: skinned ? skinned.geometry.attributes.position.count : 0,
                colors: skinned ? !!skinned.geometry.attributes.color : false});
      mixer.setTime(duration / 2);
      figures.push(gltf.scene);
      scene.add(gltf.scene);
    }
    // Both fighters in view, half way through the bout.
    const box = new THREE.Box3();
    for (const f of figures) box.expandByObject(f);
    const centre = box.getCenter(new THREE.Vector3());
    const size = Math.max(box.getSize(new THREE.Vector3()).length(), 2);
    const camera = new THREE.PerspectiveCamera(40, 960 / 540, 0.05, 100);
    camera.position.set(centre.x + size * 0.9, centre.y + size * 0.45, centre.z + size * 0.9);
    camera.lookAt(centre);
    const renderer = new THREE.WebGLRenderer({canvas: document.getElementById('c'), antialias: true});
    renderer.render(scene, camera);
    return out;
  }, glbs);
  for (const r of result) {
    check(r.bones > 10, `three.js: ${r.name} is a skinned mesh over the skeleton`, `${r.bones} bones, ${r.vertices} vertices, vertex colours ${r.colors}`);
    check(r.bones === r.bvhJoints, `three.js: ${r.name} has the BVH's joints`, `${r.bones} and ${r.bvhJoints}`);
    check(r.compared >= 5 * r.bones, `three.js: ${r.name}'s joints compared at 5 frames`, `${r.compared} positions over ${r.frames} frames, ${r.duration.toFixed(2)} s`);
    check(r.worst < 0.001, `three.js: ${r.name}'s joints stand where the BVH's do, within 1 mm`,
          `worst ${(r.worst * 1000).toFixed(3)} mm (${r.worstJoint})`);
  }
  check(errors.length === 0, 'no page errors', errors.join(' | '));
  if (screenshot) {
    await page.screenshot({path: screenshot});
    console.log(`gltf_test: screenshot ${screenshot}`);
  }
} finally {
  await browser.close();
  clearTimeout(timer);
}
console.log(`gltf_test: ${failed ? failed + ' FAILED' : 'every check passed'}`);
process.exit(failed ? 1 : 0);
