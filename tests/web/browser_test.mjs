// The viewer end to end: the real `mgrl serve`, the real page in headless
// Chromium, real mouse events. See tests/web/README.md.
//
//   MGRL_BINARY=build/app/mgrl node tests/web/browser_test.mjs
//
// Environment: MGRL_BINARY (default build/app/mgrl), MGRL_SERVE_ARGS (more words for
// `mgrl serve`, e.g. "--data DIR --cache DIR"), MGRL_SCREENSHOT_DIR (default docs/img),
// MGRL_CHROMIUM (default /usr/bin/chromium), MGRL_WEB_TEST_TIMEOUT_S (default 420),
// MGRL_DODGE_POLICY (a bundle of scenarios/dodge.yaml for the dodge scene's page; without
// it that page runs the online search, and says so).
import {execFileSync, spawn} from 'node:child_process';
import {createRequire} from 'node:module';
import {mkdirSync, mkdtempSync, readFileSync, rmSync} from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import {fileURLToPath} from 'node:url';

const repo = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
// playwright-core comes from web/node_modules (scripts/setup.sh runs `npm ci` there); it
// drives the system's Chromium and never downloads a browser of its own.
const {chromium} = createRequire(path.join(repo, 'web/package.json'))('playwright-core');

const binary = path.resolve(process.env.MGRL_BINARY ?? path.join(repo, 'build/app/mgrl'));
const serveArgs = (process.env.MGRL_SERVE_ARGS ?? '').split(/\s+/).filter((w) => w.length > 0);
const screenshotDir = path.resolve(repo, process.env.MGRL_SCREENSHOT_DIR ?? 'docs/img');
const chromiumPath = process.env.MGRL_CHROMIUM ?? '/usr/bin/chromium';
const overallSeconds = Number(process.env.MGRL_WEB_TEST_TIMEOUT_S ?? 420);

const kServerStartSeconds = 120;   // the first start may load the capture and build a graph
const kMinFramesPerSecond = 20;
const kTargetTolerance = 0.2;      // m
const kHitWithinSimSeconds = 15;
const kStepDistance = 0.1;         // m closer to the target: the boxer's first step
const kSideDistance = 1.5;         // m beside the boxer, where the target is dragged
const kMinVariance = 30;           // luminance variance of a canvas that shows something
const kValuesWithinSimSeconds = 2; // the teaching view: values messages counted over this
const kMinValuesMessages = 3;      //   many simulated seconds, at least this many (5/s sent)
const kLessonBudget = 20000;       // the learn panel's budget (its input's default)
const kChainSteps = 400;           // single learn steps whose table the test rebuilds itself
// Live retraining's trials (app/serve/viewer.cpp: kRetrainTrials, kRetrainTrialSeconds, seed 1),
// repeated with `mgrl eval`.
const kRetrainTrials = 200;
const kRetrainSeconds = 10;
const kRetrainSeed = 1;

let passed = 0;
let server = null;
let browser = null;
let page = null;
const serverLines = [];

class CheckFailed extends Error {}

function ok(what) {
  passed += 1;
  console.log(`ok   - ${what}`);
}

function check(condition, what, detail = '') {
  if (!condition) throw new CheckFailed(`${what}${detail ? ': ' + detail : ''}`);
  ok(what);
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// ---- the server ------------------------------------------------------------------

function startServer(scenario = 'scenarios/boxing.yaml', more = serveArgs) {
  const args = ['serve', scenario, '--port', '0', ...more];
  console.log(`# starting ${binary} ${args.join(' ')} (cwd ${repo})`);
  server = spawn(binary, args, {cwd: repo, stdio: ['ignore', 'pipe', 'pipe']});
  const exited = new Promise((resolve) => server.once('exit', (code, signal) => resolve({code, signal})));
  server.exited = exited;
  const url = new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new CheckFailed(
      `the server printed no http://127.0.0.1:PORT/ line within ${kServerStartSeconds} s`)), kServerStartSeconds * 1000);
    let pending = '';
    const keep = (line) => {
      serverLines.push(line);
      if (serverLines.length > 200) serverLines.shift();
    };
    server.stdout.on('data', (chunk) => {
      pending += chunk.toString();
      const lines = pending.split('\n');
      pending = lines.pop();
      for (const line of lines) {
        keep(line);
        const match = /http:\/\/127\.0\.0\.1:(\d+)\//.exec(line);
        if (match) {
          clearTimeout(timer);
          resolve(match[0]);
        }
      }
    });
    server.stderr.on('data', (chunk) => chunk.toString().split('\n').filter((l) => l).forEach(keep));
    server.once('error', (e) => {
      clearTimeout(timer);
      reject(new CheckFailed(`could not start ${binary}: ${e.message}`));
    });
    exited.then(({code, signal}) => {
      clearTimeout(timer);
      reject(new CheckFailed(`the server exited (code ${code}, signal ${signal}) before it was listening`));
    });
  });
  return url;
}

async function stopServer() {
  if (server === null || server.exitCode !== null || server.signalCode !== null) return;
  server.kill('SIGINT');
  const stopped = await Promise.race([server.exited.then(() => true), sleep(5000).then(() => false)]);
  if (!stopped) {
    console.log('# the server did not stop within 5 s of SIGINT: SIGKILL');
    server.kill('SIGKILL');
    await server.exited;
  }
}

async function cleanUp() {
  if (browser !== null) await browser.close().catch(() => {});
  browser = null;
  await stopServer();
}

// ---- the command line, to check the server against --------------------------------

/** The values MGRL_SERVE_ARGS gives option `name` (`--name VALUE` or `--name=VALUE`), in order. */
function serveOption(name) {
  const values = [];
  for (let k = 0; k < serveArgs.length; ++k) {
    if (serveArgs[k] === name && k + 1 < serveArgs.length) values.push(serveArgs[++k]);
    else if (serveArgs[k].startsWith(`${name}=`)) values.push(serveArgs[k].slice(name.length + 1));
  }
  return values;
}

/** Runs `$MGRL_BINARY ...args` from the repository root (blocking) and returns its stdout. */
function mgrlCommand(args) {
  console.log(`#      running ${binary} ${args.join(' ')}`);
  const started = Date.now();
  try {
    const out = execFileSync(binary, args, {cwd: repo, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'],
                                            maxBuffer: 64 << 20, timeout: 300000});
    console.log(`#      (${((Date.now() - started) / 1000).toFixed(1)} s)`);
    return out;
  } catch (e) {
    const said = String(e.stderr ?? '').trim().split('\n').slice(-5).join(' | ');
    throw new CheckFailed(`${binary} ${args.join(' ')} failed (exit ${e.status}, signal ${e.signal}): ${said || e.message}`);
  }
}

// ---- the page --------------------------------------------------------------------

/** Waits until `predicate(arg)` (run in the page) is true; fails with `what` after `ms`. */
async function waitInPage(page, predicate, arg, ms, what) {
  try {
    await page.waitForFunction(predicate, arg, {timeout: ms, polling: 100});
  } catch (e) {
    const seen = await page.evaluate(() => ({
      scene: window.mgrl?.state.scene && {mode: mgrl.state.scene.mode, avatars: mgrl.state.scene.avatars},
      frames: window.mgrl?.state.frames.count, last: window.mgrl?.state.frames.last,
      error: window.mgrl?.state.lastError,
    })).catch(() => 'page not answering');
    throw new CheckFailed(`${what} (waited ${ms / 1000} s; page state ${JSON.stringify(seen)})`);
  }
}

/** Frames received and drawn per second over `seconds`, measured in the page. */
function framesPerSecond(page, seconds) {
  return page.evaluate(async (ms) => {
    const frames0 = mgrl.state.frames.count, draws0 = mgrl.state.draw.count, t0 = performance.now();
    await new Promise((resolve) => setTimeout(resolve, ms));
    const elapsed = (performance.now() - t0) / 1000;
    return {received: (mgrl.state.frames.count - frames0) / elapsed, drawn: (mgrl.state.draw.count - draws0) / elapsed,
            drawMs: mgrl.state.draw.cycleMs};
  }, seconds * 1000);
}

async function screenshot(page, name) {
  const file = path.join(screenshotDir, name);
  await page.screenshot({path: file});
  const {mean, variance} = await page.evaluate(() => mgrl.pixelStats());
  check(variance > kMinVariance, `screenshot ${path.relative(repo, file)} is not blank`,
        `canvas luminance mean ${mean.toFixed(1)}, variance ${variance.toFixed(1)} (need > ${kMinVariance})`);
  console.log(`#      canvas luminance mean ${mean.toFixed(1)}, variance ${variance.toFixed(1)}`);
}

async function waitForWorld(page, mode, avatars) {
  await waitInPage(page, ([m, n]) => {
    const s = window.mgrl?.state;
    return s?.scene?.mode === m && s.scene.avatars === n && s.frames.last?.avatars === n;
  }, [mode, avatars], 60000, `the server switches to ${mode} with ${avatars} avatars and sends its frames`);
  ok(`scene and frames in ${mode} mode with ${avatars} avatars`);
}

// Avatar 0 and its target now (read in one go, so they belong to the same frame).
const snapshot = (page) => page.evaluate(() => ({
  root: mgrl.rootOf(0), target: mgrl.targetOf(0), time: mgrl.state.frames.last?.time,
}));
const floorDistance = (a, b) => Math.hypot(a[0] - b[0], a[2] - b[2]);

// The panel's sections fold; the checks below use them all, so they open every one (the
// page remembers it, so a reload keeps them open).
const openPanelSections = (page) => page.evaluate(() => {
  for (const d of document.querySelectorAll('#panel details')) d.open = true;
});

// ---- the checks ------------------------------------------------------------------

// In an 800 x 600 window the panel fits with its default folds (its top stays in view,
// nothing scrolls), every section's title shows, a folded one opens on a click, and the
// page remembers it after a reload.
async function smallWindow(url) {
  const small = await browser.newPage({viewport: {width: 800, height: 600}});
  try {
    await small.goto(url);
    await waitInPage(small, () => window.mgrl?.state?.scene?.mode === 'target' && window.mgrl.state.draw.count >= 3, null,
                     30000, 'the page in an 800 x 600 window gets its scene and draws');
    const fit = () => small.evaluate(() => {
      const panel = document.getElementById('panel').getBoundingClientRect();
      const head = document.querySelector('#panel h1').getBoundingClientRect();
      return {top: panel.top, bottom: panel.bottom, headTop: head.top, scrolls: document.getElementById('panel').scrollHeight >
              document.getElementById('panel').clientHeight, titles: [...document.querySelectorAll('#panel summary')].map((t) => {
                const r = t.getBoundingClientRect();
                return {text: t.textContent, shown: r.height > 0 && r.bottom <= innerHeight};
              }), open: [...document.querySelectorAll('#panel details')].filter((d) => d.open).map((d) => d.dataset.section)};
    });
    const folded = await fit();
    check(folded.headTop >= 0 && folded.bottom <= 600 && !folded.scrolls,
          '800 x 600: the panel fits the window with its default folds (its title in view, nothing to scroll)',
          `panel ${folded.top.toFixed(0)} to ${folded.bottom.toFixed(0)} px, scrolls: ${folded.scrolls}, open: ${folded.open.join(', ')}`);
    check(folded.titles.length === 7 && folded.titles.every((t) => t.shown),
          '800 x 600: every section of the panel shows its title', JSON.stringify(folded.titles));
    check(folded.open.join(',') === 'mode,clock,controller', '800 x 600: Mode, Clock and Controller start open',
          folded.open.join(', '));
    await screenshot(small, 'viewer-800x600.png');
    await small.click('#panel details[data-section="learn"] > summary');
    await small.click('#learn-start');  // a control inside the section it opened
    const opened = await fit();
    check(opened.open.includes('learn'), '800 x 600: a click on "Learn" opens its section', opened.open.join(', '));
    await small.reload();
    await waitInPage(small, () => window.mgrl?.state?.scene?.mode === 'target', null, 30000, 'the reloaded small page');
    const kept = await fit();
    check(kept.open.join(',') === 'mode,clock,controller,learn', '800 x 600: the page remembers the sections opened',
          kept.open.join(', '));
  } finally {
    await small.close();
  }
}

async function targetMode(page) {
  await waitInPage(page, () => {
    const s = window.mgrl?.state;
    return s?.scene?.mode === 'target' && s.frames.count > 0 && window.mgrl.targetOf(0) !== null && s.draw.count >= 5;
  }, null, 30000, 'the page gets a target-mode scene and a frame with a target, and draws');
  const scene = await page.evaluate(() => mgrl.state.scene);
  check(scene.avatars === 1 && Array.isArray(scene.joints) && scene.joints.length > 0,
        'the scene is target mode with 1 avatar and a skeleton', `avatars ${scene.avatars}, ${scene.joints?.length} joints`);
  check(Array.isArray(scene.controllers) && scene.controllers.includes(scene.controller),
        'the scene lists its controllers', `controller ${scene.controller}, controllers ${JSON.stringify(scene.controllers)}`);
  console.log(`#      controller ${scene.controller}${scene.note ? `; note: ${scene.note}` : ''}`);
  const webgl = await page.evaluate(() => mgrl.pixelStats());
  check(webgl.variance > kMinVariance, 'the page draws (WebGL canvas not blank)', `variance ${webgl.variance.toFixed(1)}`);

  // The world held still while the target is aimed at and dragged: until the page first
  // moves it, the server moves the target by itself every few seconds (world.target_hold,
  // 3 s), and one such move between aiming and pressing made the press miss the sphere
  // and orbit the camera instead.
  await setPaused(page, true);

  // A spot on the floor kSideDistance beside the boxer: perpendicular to its line to
  // the target (two consecutive roots say little about where it faces).
  const before = await snapshot(page);
  const [rx, , rz] = before.root;
  let dx = before.target[0] - rx, dz = before.target[2] - rz;
  const length = Math.hypot(dx, dz);
  if (length < 0.05) { dx = 1; dz = 0; } else { dx /= length; dz /= length; }
  const height = before.target[1];
  // Either side will do: the one whose spot shows on the canvas (not under the panels).
  const onCanvas = (p) => page.evaluate(({x, y}) => document.elementFromPoint(x, y)?.tagName === 'CANVAS', p);
  const from = await page.evaluate((p) => mgrl.project(p), before.target);
  let spot = null, to = null;
  for (const side of [1, -1]) {
    const candidate = [rx - side * dz * kSideDistance, 0, rz + side * dx * kSideDistance];
    const pixel = await page.evaluate((p) => mgrl.project(p), candidate);
    if (await onCanvas(pixel)) {
      spot = candidate;
      to = pixel;
      break;
    }
    if (spot === null) to = pixel;
  }
  check(await onCanvas(from) && spot !== null, 'the target and a spot beside the boxer are on screen',
        `target at (${from.x.toFixed(0)}, ${from.y.toFixed(0)}) px, spot at (${to.x.toFixed(0)}, ${to.y.toFixed(0)}) px`);

  // The drag, with real mouse events: press on the sphere, move over the floor, release.
  const landmark = [0, 0, 0];   // where it shows on screen says whether the camera moved
  const landmarkBefore = await page.evaluate((p) => mgrl.project(p), landmark);
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  await page.mouse.move(to.x, to.y, {steps: 15});
  await page.mouse.up();
  const dragEnd = (await snapshot(page)).time;
  await setPaused(page, false);
  const landmarkAfter = await page.evaluate((p) => mgrl.project(p), landmark);
  check(Math.hypot(landmarkAfter.x - landmarkBefore.x, landmarkAfter.y - landmarkBefore.y) < 1,
        'the camera stays put while the target is dragged (orbit controls off)',
        `the world origin moved from (${landmarkBefore.x.toFixed(0)}, ${landmarkBefore.y.toFixed(0)}) to ` +
        `(${landmarkAfter.x.toFixed(0)}, ${landmarkAfter.y.toFixed(0)}) px`);
  console.log(`#      dragged the target from (${before.target.map((v) => v.toFixed(2))}) to the floor spot ` +
              `(${spot[0].toFixed(2)}, ${spot[2].toFixed(2)}) at simulated ${dragEnd.toFixed(2)} s`);

  await waitInPage(page, ([x, z, tolerance]) => {
    const t = mgrl.targetOf(0);
    return t !== null && Math.hypot(t[0] - x, t[2] - z) < tolerance;
  }, [spot[0], spot[2], kTargetTolerance], 5000, `the server's target moves to within ${kTargetTolerance} m of the spot`);
  const moved = await snapshot(page);
  check(floorDistance(moved.target, spot) < kTargetTolerance && Math.abs(moved.target[1] - height) < kTargetTolerance,
        `the server's target is where it was dragged (within ${kTargetTolerance} m, height kept)`,
        `target (${moved.target.map((v) => v.toFixed(2))}), spot (${spot[0].toFixed(2)}, ${height.toFixed(2)}, ${spot[2].toFixed(2)})`);

  // Then the boxer goes after it: its first step (the root 0.1 m closer) and a punch on
  // its own target, both timed in simulated seconds from the end of the drag.
  const startDistance = floorDistance(moved.root, moved.target);
  let stepAfter = null, hit = null, now = moved;
  const wallLimit = Date.now() + (kHitWithinSimSeconds / 0.5 + 10) * 1000;   // if the clock crawls
  while (hit === null && now.time - dragEnd <= kHitWithinSimSeconds && Date.now() < wallLimit) {
    await sleep(50);
    now = await snapshot(page);
    if (stepAfter === null && floorDistance(now.root, now.target) <= startDistance - kStepDistance) {
      stepAfter = now.time - dragEnd;
    }
    hit = await page.evaluate((t) => mgrl.state.hits.find((h) => h.target === -1 && h.time >= t) ?? null, dragEnd);
  }
  if (hit !== null) await screenshot(page, 'viewer-target.png');   // the flash is still showing
  check(stepAfter !== null || hit !== null, 'the boxer steps toward the dragged target',
        `root stayed ${startDistance.toFixed(2)} m from it`);
  console.log(`#      drag to first step: ${stepAfter === null ? 'none before the hit' : stepAfter.toFixed(2) + ' s'} ` +
              `(simulated; the root was ${startDistance.toFixed(2)} m from the target)`);
  check(hit !== null && hit.time - dragEnd <= kHitWithinSimSeconds,
        `a hit on its own target (target -1) within ${kHitWithinSimSeconds} s of simulated time after the drag`,
        hit === null ? `none by simulated ${now.time.toFixed(1)} s (drag ended at ${dragEnd.toFixed(1)} s)`
                     : `first at ${hit.time.toFixed(1)} s`);
  console.log(`#      hit ${(hit.time - dragEnd).toFixed(2)} s after the drag: ${hit.hand} hand, ${hit.speed.toFixed(1)} m/s ` +
              `at (${hit.point.map((v) => v.toFixed(2))})`);

  // The height by the wheel over the sphere: four notches up, 5 cm each, and the camera
  // does not zoom.
  const over = await page.evaluate(() => mgrl.project(mgrl.targetOf(0)));
  const heightBefore = (await snapshot(page)).target[1];
  const zoomBefore = await page.evaluate((p) => mgrl.project(p), landmark);
  await page.mouse.move(over.x, over.y);
  for (let k = 0; k < 4; ++k) {
    await page.mouse.wheel(0, -100);
    await sleep(50);
  }
  await sleep(1000);
  const heightAfter = (await snapshot(page)).target[1];
  const zoomAfter = await page.evaluate((p) => mgrl.project(p), landmark);
  check(Math.abs(heightAfter - heightBefore - 0.2) < 0.1 && Math.hypot(zoomAfter.x - zoomBefore.x, zoomAfter.y - zoomBefore.y) < 1,
        'the wheel over the target raises it (4 notches: 0.2 m) without zooming the camera',
        `height ${heightBefore.toFixed(2)} -> ${heightAfter.toFixed(2)} m, origin moved ` +
        `${Math.hypot(zoomAfter.x - zoomBefore.x, zoomAfter.y - zoomBefore.y).toFixed(1)} px`);
  return {stepAfter, hitAfter: hit.time - dragEnd};
}

// ---- the teaching views ------------------------------------------------

/** Simulated time of the newest frame. */
const frameTime = (page) => page.evaluate(() => mgrl.state.frames.last.time);

/** Waits until the world's clock is `seconds` past `from` (simulated), or 30 s of wall time. */
async function waitSimulated(page, from, seconds, what) {
  await waitInPage(page, (t) => mgrl.state.frames.last.time >= t, from + seconds, 30000, what);
}

/** `values` messages of `behaviour` received with a time in [from, from + seconds]. */
function valuesBetween(page, behaviour, from, seconds) {
  return page.evaluate(([b, t0, dt]) => mgrl.state.values.received
    .filter((m) => m.behavior === b && m.time >= t0 - 1e-6 && m.time <= t0 + dt).length, [behaviour, from, seconds]);
}

// One behaviour's values through the panel's select: the messages keep coming, the heat
// map has a cell per point and changes the picture, the HUD shows the legend and state.
async function showValues(page, behaviour, screenshotName) {
  const from = await frameTime(page);
  await page.selectOption('#values-behavior', behaviour);
  await waitSimulated(page, from, kValuesWithinSimSeconds + 0.3, `${kValuesWithinSimSeconds} s of simulated time after asking for ${behaviour}'s values`);
  const count = await valuesBetween(page, behaviour, from, kValuesWithinSimSeconds);
  check(count >= kMinValuesMessages,
        `values of ${behaviour}: ${kMinValuesMessages} or more messages within ${kValuesWithinSimSeconds} s of simulated time`,
        `${count} from simulated ${from.toFixed(2)} s`);
  // Held still for the checks and the screenshot (values come only as the world runs),
  // so the heat map, the HUD and the picture are of one message.
  await setPaused(page, true);

  // In one go, so the legend and the heat map are of the same message.
  const seen = await page.evaluate(() => {
    const m = mgrl.state.values.last;
    return {teach: mgrl.teach(), behavior: m.behavior, points: m.points.length, vMin: m.v_min, vMax: m.v_max,
            state: m.state, chosen: m.chosen, actions: m.actions, inside: m.target_inside, height: m.height,
            withValues: mgrl.pixelStats(), without: mgrl.pixelStats({withoutValues: true})};
  });
  const t = seen.teach;
  check(seen.behavior === behaviour && t.instances === seen.points && seen.points > 0,
        `values of ${behaviour}: the heat map draws one cell per point (${seen.points})`,
        `${t.instances} cells for ${seen.points} points of ${seen.behavior}`);
  check(t.pathTriangles > 0 && t.pathPoints > 1, `values of ${behaviour}: the chosen action's path is drawn on the floor`,
        `${t.pathPoints} path points, ${t.pathTriangles} triangles`);
  const dMean = seen.withValues.mean - seen.without.mean, dVariance = seen.withValues.variance - seen.without.variance;
  check(Math.abs(dMean) > 0.5 || Math.abs(dVariance) > 5, `values of ${behaviour}: the heat map changes the picture (pixelStats)`,
        `luminance mean ${seen.without.mean.toFixed(2)} -> ${seen.withValues.mean.toFixed(2)}, ` +
        `variance ${seen.without.variance.toFixed(1)} -> ${seen.withValues.variance.toFixed(1)}`);
  console.log(`#      ${behaviour}: ${count} values messages in ${kValuesWithinSimSeconds} s simulated; ${seen.points} points at height ` +
              `${seen.height.toFixed(2)} m, ${t.chosenMarks} greedy = chosen; luminance mean ${seen.without.mean.toFixed(2)} -> ` +
              `${seen.withValues.mean.toFixed(2)}, variance ${seen.without.variance.toFixed(1)} -> ${seen.withValues.variance.toFixed(1)}`);
  const near = (text, v) => Math.abs(Number.parseFloat(text) - v) <= 0.006 * Math.abs(v) + 1e-9;
  check(t.legend.shown && near(t.legend.min, seen.vMin) && near(t.legend.max, seen.vMax),
        `values of ${behaviour}: the legend shows v_min and v_max`,
        `legend "${t.legend.min}" .. "${t.legend.max}", message ${seen.vMin} .. ${seen.vMax}`);
  const line = `state ${seen.state}, chosen action ${seen.chosen} of ${seen.actions}`;
  check(t.stateLine.startsWith(line) && t.stateLine.includes(`target inside grid: ${seen.inside ? 'yes' : 'no'}`),
        `values of ${behaviour}: the HUD shows the state, the chosen action and whether the target is inside the grid`,
        `"${t.stateLine}"`);
  await screenshot(page, screenshotName);
  await setPaused(page, false);
}

/** Pauses or resumes the world (a page message) and waits until the stats say so. */
async function setPaused(page, paused) {
  await page.evaluate((p) => mgrl.send({type: 'pause', paused: p}), paused);
  await waitInPage(page, (p) => mgrl.state.stats?.paused === p, paused, 5000, paused ? 'paused' : 'running again');
  if (paused) await sleep(600);   // what was sent before the pause, and its draw
}

async function teachViews(page) {
  const scene = await page.evaluate(() => mgrl.state.scene);
  const curves = scene.behaviors.filter((b) => Array.isArray(b.curve) && b.curve.some((r) => r[2] > 0));
  check(scene.behaviors.every((b) => typeof b.learner === 'string' && Number.isInteger(b.vertices) && Array.isArray(b.curve)),
        'the scene carries each behaviour\'s learner, vertex count and training curve',
        JSON.stringify(scene.behaviors.map((b) => ({name: b.name, learner: b.learner, vertices: b.vertices, curve: b.curve?.length}))));
  const hit = scene.behaviors.find((b) => b.name === 'hit');
  check(hit?.success === 'an effective strike of the fists within 0.15 m' && scene.behaviors.find((b) => b.name === 'approach')?.success === null,
        'the scene says what success is: hit\'s contact, nothing for approach', JSON.stringify(scene.behaviors.map((b) => b.success)));
  const hudSuccess = await page.evaluate(() => [...document.querySelectorAll('#hud-table tr')]
    .map((tr) => [...tr.children].map((c) => c.textContent)).find(([name]) => name === 'success')?.[1] ?? '');
  check(hudSuccess === 'hit: an effective strike of the fists within 0.15 m', 'the HUD shows the success criterion', hudSuccess);
  // And counts successes live, as eval counts them (stats.successes, twice a second).
  const successesRow = () => [...document.querySelectorAll('#hud-table tr')]
    .map((tr) => [...tr.children].map((c) => c.textContent)).find(([name]) => name === 'successes')?.[1] ?? '';
  await waitInPage(page, `(${successesRow.toString()})() !== '–'`, undefined, 5000, 'a stats message in the HUD');
  const hudSuccesses = await page.evaluate(successesRow);
  check(/^\d+ \(\d+\.\d \/min\)$/.test(hudSuccesses), 'the HUD counts successes (count and rate per minute)', hudSuccesses);

  await page.click('#look-down');
  await showValues(page, 'hit', 'teach-values-hit.png');
  await showValues(page, 'approach', 'teach-values-approach.png');

  // Greedy-action colours (redrawn from the last message at once): the legend runs
  // over the action indices.
  await setPaused(page, true);
  await page.click('#colour-greedy');
  const greedy = await page.evaluate(() => ({teach: mgrl.teach(), actions: mgrl.state.values.last.actions}));
  check(greedy.teach.colourBy === 'greedy' && greedy.teach.legend.min === '0' &&
        greedy.teach.legend.max === String(greedy.actions - 1),
        'colour by greedy action: the legend runs over the action indices',
        `legend "${greedy.teach.legend.min}" .. "${greedy.teach.legend.max}" for ${greedy.actions} actions`);

  // The learning curves: one line per behaviour that has a curve, a point per row.
  await page.check('#curves-toggle');
  const chart = await page.evaluate(() => ({
    shown: !document.getElementById('curves').hidden,
    lines: [...document.querySelectorAll('#curves-chart polyline.chart-line')].map((l) => ({
      behavior: l.dataset.behavior, points: l.getAttribute('points').trim().split(/\s+/).length})),
    legend: document.querySelector('#curves-chart .chart-legend')?.textContent ?? '',
  }));
  const expected = curves.map((b) => ({behavior: b.name, points: b.curve.filter((r) => r[0] > 0 && r[2] > 0).length}));
  check(chart.shown && JSON.stringify(chart.lines) === JSON.stringify(expected) && expected.every((e) => e.points >= 2),
        `the learning-curve chart has one line per behaviour with its curve's points (${expected.map((e) => `${e.behavior} ${e.points}`).join(', ')})`,
        `drawn ${JSON.stringify(chart.lines)}, expected ${JSON.stringify(expected)}`);
  check(curves.every((b) => chart.legend.includes(`${b.name} (${b.learner})`)),
        'the chart\'s legend names each behaviour and its learner', `"${chart.legend}"`);
  await screenshot(page, 'teach-curves.png');
  await page.uncheck('#curves-toggle');
  await page.click('#colour-value');
  await setPaused(page, false);

  // None: the messages stop and the heat map goes.
  await page.selectOption('#values-behavior', '');
  await sleep(500);   // what the server sent before it read "none"
  const stoppedAt = await frameTime(page);
  const countBefore = await page.evaluate(() => mgrl.state.values.received.length);
  await waitSimulated(page, stoppedAt, kValuesWithinSimSeconds, `${kValuesWithinSimSeconds} s of simulated time after "none"`);
  const after = await page.evaluate(() => ({count: mgrl.state.values.received.length, teach: mgrl.teach()}));
  check(after.count === countBefore && after.teach.instances === 0 && after.teach.pathTriangles === 0 && !after.teach.legend.shown,
        `values of none: no more messages over ${kValuesWithinSimSeconds} s of simulated time, heat map, path and legend gone`,
        `${after.count - countBefore} more messages, ${after.teach.instances} cells, legend shown ${after.teach.legend.shown}`);
}

// A new world (mode change) while values are shown. boxing.yaml names boxing_spar.yaml as
// its sparring_scenario, so sparring plays that scenario's behaviours (one per
// stance): the values of approach stop and the select offers them. Between sparring and crowd (the same
// scenario) the page asks again and the new world's values arrive at once. Target mode
// brings the paper's two behaviours back.
async function valuesAcrossModeChange(page) {
  await page.selectOption('#values-behavior', 'approach');
  await waitInPage(page, () => mgrl.teach().instances > 0, null, 10000, 'approach values before the mode change');
  await page.click('#mode-sparring');
  await waitForWorld(page, 'sparring', 2);
  await waitInPage(page, () => mgrl.state.scene.scenario === 'boxing_spar', null, 5000, 'the sparring scene of boxing_spar');
  await sleep(300);
  const spar = await page.evaluate(() => ({
    names: mgrl.state.scene.behaviors.map((b) => b.name).join(),
    options: [...document.querySelectorAll('#values-behavior option')].map((o) => o.value).join(),
    selected: document.querySelector('#values-behavior').value,
    cells: mgrl.teach().instances,
    note: mgrl.state.scene.note}));
  check(spar.names === 'spar_square,spar,spar_turned' && spar.options === ',spar_square,spar,spar_turned' &&
        spar.selected === '' && spar.cells === 0 && spar.note.includes('Sparring plays'),
        'sparring plays boxing_spar.yaml\'s three stances (its note says so); approach\'s values stop and the select offers them',
        JSON.stringify(spar));
  await page.selectOption('#values-behavior', 'spar');
  await waitInPage(page, () => mgrl.teach().instances > 0, null, 10000, 'spar values in sparring');
  await page.click('#mode-crowd');
  await waitInPage(page, () => mgrl.state.scene?.mode === 'crowd', null, 10000, 'the crowd scene');
  const from = await frameTime(page);
  await waitSimulated(page, from, kValuesWithinSimSeconds + 0.3, `${kValuesWithinSimSeconds} s of the crowd`);
  const count = await valuesBetween(page, 'spar', from, kValuesWithinSimSeconds);
  const cells = await page.evaluate(() => mgrl.teach().instances);
  check(count >= kMinValuesMessages && cells > 0,
        `values of spar keep coming after a switch from sparring to a crowd (${kMinValuesMessages} or more within ${kValuesWithinSimSeconds} s simulated)`,
        `${count} messages from simulated ${from.toFixed(2)} s, ${cells} cells`);
  await page.selectOption('#values-behavior', '');
  await waitInPage(page, () => mgrl.teach().instances === 0, null, 5000, 'the heat map gone after none');
  await page.click('#mode-target');
  await waitForWorld(page, 'target', 1);
  await waitInPage(page, () => mgrl.state.scene.behaviors.map((b) => b.name).join() === 'approach,hit', null, 5000,
                   'target mode plays the paper\'s approach and hit again');
  ok('target mode plays the paper\'s approach and hit again');
}

/** Sets a range input as a user's drag would end: its value, then `input` and `change`. */
function setRange(page, selector, value) {
  return page.$eval(selector, (input, v) => {
    input.value = String(v);
    input.dispatchEvent(new Event('input', {bubbles: true}));
    input.dispatchEvent(new Event('change', {bubbles: true}));
  }, value);
}

// The panel's controls, each through the page's own inputs, and what the server says back.
async function panelControls(page) {
  await page.click('#pause');
  await waitInPage(page, () => mgrl.state.stats?.paused === true, null, 5000, 'pause: the stats say paused');
  await sleep(300);
  const frameBefore = await page.evaluate(() => mgrl.state.frames.last.frame);
  await page.click('#step');
  await waitInPage(page, (f) => mgrl.state.frames.last.frame === f + 1, frameBefore, 5000, 'step: one more frame');
  await sleep(500);
  const frameAfter = await page.evaluate(() => mgrl.state.frames.last.frame);
  check(frameAfter === frameBefore + 1, 'pause holds the world and step advances it by one frame',
        `frame ${frameBefore} -> ${frameAfter}`);
  await page.click('#pause');
  await waitInPage(page, () => mgrl.state.stats?.paused === false, null, 5000, 'resume: the stats say running');

  await setRange(page, '#speed', 2);
  await waitInPage(page, () => mgrl.state.stats?.speed === 2, null, 5000, 'speed: the stats say 2');
  await setRange(page, '#speed', 1);
  await waitInPage(page, () => mgrl.state.stats?.speed === 1, null, 5000, 'speed: the stats say 1');
  ok('the speed slider sets the server clock (2, then 1)');

  const scene = await page.evaluate(() => mgrl.state.scene);
  for (const controller of scene.controllers.filter((c) => c !== scene.controller).concat([scene.controller])) {
    await page.selectOption('#controller', controller);
    await waitInPage(page, (c) => mgrl.state.scene.controller === c, controller, 10000, `controller ${controller} taken`);
  }
  ok(`the controller select switches the server's controller (${scene.controllers.join(', ')})`);
  if (scene.controllers.includes('online_search')) {
    await page.selectOption('#controller', 'online_search');
    await page.fill('#horizon', '2');
    await page.press('#horizon', 'Enter');
    await waitInPage(page, () => mgrl.state.scene.controller === 'online_search' && mgrl.state.scene.horizon === 2,
                     null, 10000, 'online search horizon 2 taken');
    ok('the horizon input sets the online search horizon (2)');
    // Back to the scene's controller and horizon, which the measurements below are of.
    await page.fill('#horizon', String(scene.horizon));
    await page.press('#horizon', 'Enter');
    await waitInPage(page, (h) => mgrl.state.scene.horizon === h, scene.horizon, 10000, `horizon ${scene.horizon} again`);
    await page.selectOption('#controller', scene.controller);
    await waitInPage(page, ([c, h]) => mgrl.state.scene.controller === c && mgrl.state.scene.horizon === h,
                     [scene.controller, scene.horizon], 10000, `controller ${scene.controller} (horizon ${scene.horizon}) again`);
  }

  const behaviour = scene.behaviors[0];
  await setRange(page, `input[data-behaviour="${behaviour.name}"]`, 2.5);
  await waitInPage(page, (name) => mgrl.state.scene.behaviors.find((b) => b.name === name)?.weight === 2.5,
                   behaviour.name, 5000, `weight of ${behaviour.name} taken`);
  await setRange(page, `input[data-behaviour="${behaviour.name}"]`, behaviour.weight);
  await waitInPage(page, ([name, w]) => mgrl.state.scene.behaviors.find((b) => b.name === name)?.weight === w,
                   [behaviour.name, behaviour.weight], 5000, `weight of ${behaviour.name} restored`);
  ok(`the weight slider of ${behaviour.name} sets its weight (2.5, then ${behaviour.weight})`);

  // A message the server must refuse: its error shows on the page.
  await page.evaluate(() => mgrl.send({type: 'speed', speed: 9}));
  await waitInPage(page, () => mgrl.state.lastError !== null, null, 5000, 'an error for speed 9');
  const shown = await page.$eval('#error', (e) => (e.hidden ? '' : e.textContent));
  const error = await page.evaluate(() => mgrl.state.lastError);
  check(shown.includes(error), 'a refused message (speed 9) comes back as an error shown on the page', `"${error}"`);
  console.log(`#      server error: ${error}`);
}

async function measured(page, avatars) {
  await sleep(1000);   // past the switch
  const {received: fps, drawn, drawMs} = await framesPerSecond(page, 3);
  const stats = await page.evaluate(() => mgrl.state.stats);
  const last = await page.evaluate(() => mgrl.state.frames.last);
  return {avatars, fps, drawn, drawMs, bytes: stats?.bytes_per_avatar_frame, frameBytes: last?.bytes,
          serverMs: stats?.server_ms_per_frame, decisionUs: stats?.decision_us, dropped: stats?.frames_dropped};
}

async function setCrowdSize(page, avatars) {
  await page.fill('#crowd-count', String(avatars));
  await page.press('#crowd-count', 'Enter');   // a change: sent only when in crowd mode
}


// The learn panel: Q-learning stepped on the page, each update shown as the
// paper's Fig. 4 draws it. Each update is recomputed here from the numbers it shows, as
// framework/learning/q_learning_steps.cpp computes it in float (built with -ffp-contract=off):
//   alpha    = float(1 - (update - 1) / budget)       (alpha_final 0, the panel's lesson)
//   discount = float(gamma^frames)                    (to an ulp: std::pow and Math.pow)
//   backup   = r + discount * future, or r off the grid (future 0 there)
//   after    = before + alpha (backup - before)
// and over a run of single steps from a fresh lesson the test keeps the table itself: each
// `before` is the `after` the last step left at that (action, vertex), 0 if none did, and
// each look-ahead `future` (max over a' of Q interpolated at e'_v, weights >= 0) lies
// within the smallest and largest entry of that table.
const f32 = Math.fround;

/** What breaks the update rule in `step` (a learn_step message), [] if nothing. */
function ruleBreaks(step, gamma, budget = kLessonBudget) {
  const broken = [];
  const alpha = f32(1 - (1 / budget) * (step.update - 1));
  if (step.alpha !== alpha) broken.push(`update ${step.update}: alpha ${step.alpha}, expected ${alpha}`);
  for (const v of step.vertices) {
    const at = `update ${step.update}, action ${step.action}, vertex ${v.vertex}`;
    const discount = f32(gamma ** step.frames);
    if (Math.abs(v.discount - discount) > discount * 2 ** -23) {
      broken.push(`${at}: discount ${v.discount}, expected gamma^${step.frames} = ${discount}`);
    }
    if (!v.next_inside && v.future !== 0) broken.push(`${at}: e' off the grid but future ${v.future}`);
    const backup = v.next_inside ? f32(v.reward + f32(v.discount * v.future)) : v.reward;
    if (v.backup !== backup) broken.push(`${at}: backup ${v.backup}, expected r + discount * future = ${backup}`);
    const after = f32(v.before + f32(alpha * f32(backup - v.before)));
    if (v.after !== after) broken.push(`${at}: after ${v.after}, expected before + alpha (backup - before) = ${after}`);
  }
  return broken;
}
const ruleHolds = (step, gamma) => ruleBreaks(step, gamma).length === 0;

/**
 * Replays `steps` (every step of a lesson from its first, one each) on a table kept here:
 * what breaks the chain, how many updates found an entry an earlier one had left, how many
 * looked ahead into a nonzero value.
 */
function replayTable(steps) {
  const table = new Map();   // "action vertex" -> Q after its last update; absent: 0
  const broken = [];
  let revisits = 0, looked = 0;
  steps.forEach((step, k) => {
    if (step.update !== k + 1 || step.taken !== 1) broken.push(`message ${k}: update ${step.update}, taken ${step.taken}`);
    for (const v of step.vertices) {
      const key = `${step.action} ${v.vertex}`;
      const at = `update ${step.update}, action ${step.action}, vertex ${v.vertex}`;
      const known = table.has(key);
      const expected = known ? table.get(key) : 0;
      if (v.before !== expected) {
        broken.push(`${at}: before ${v.before}, but ${known ? 'the last update there left' : 'no update had touched it:'} ${expected}`);
      }
      revisits += known;
      if (v.next_inside) {
        let lo = 0, hi = 0;
        for (const q of table.values()) { lo = Math.min(lo, q); hi = Math.max(hi, q); }
        if (v.future < lo || v.future > hi) broken.push(`${at}: future ${v.future} outside the table's [${lo}, ${hi}]`);
        looked += v.future !== 0;
      }
      table.set(key, v.after);
    }
  });
  return {broken, revisits, looked, entries: table.size};
}

async function learnPanel(page) {
  const scene = await page.evaluate(() => mgrl.state.scene);
  const approach = scene.behaviors.find((b) => b.name === 'approach');
  await page.selectOption('#learn-behavior', 'approach');
  await page.fill('#learn-budget', String(kLessonBudget));
  await page.click('#learn-start');
  await waitInPage(page, () => mgrl.state.learn.lesson?.behavior === 'approach', null, 10000, 'a lesson on approach');
  const lesson = await page.evaluate(() => mgrl.state.learn.lesson);
  const gamma = lesson.gamma;
  check(lesson.vertices.length === approach.vertices && lesson.updates === 0 && lesson.budget === kLessonBudget &&
        gamma === approach.parameters?.['reward.gamma'],
        'learn: a lesson starts on approach\'s grid with no update yet',
        `${lesson.vertices.length} vertices (scene: ${approach.vertices}), ${lesson.updates} updates, budget ${lesson.budget}, ` +
        `gamma ${gamma} (scene: ${approach.parameters?.['reward.gamma']})`);

  await page.click('#learn-step');
  await waitInPage(page, () => mgrl.state.learn.steps.length === 1, null, 5000, 'the first step');
  const first = await page.evaluate(() => mgrl.state.learn.last);
  check(first.update === 1 && first.alpha === 1 && first.vertices.length === 4 &&
        first.vertices.every((v) => v.before === 0 && v.future === 0 && v.after === v.reward),
        'learn: the first update starts from zeros (alpha 1, max Q(e\') = 0, Q after = r)',
        JSON.stringify(first.vertices.map((v) => [v.before, v.future, v.reward, v.after])));
  check(ruleHolds(first, gamma), 'learn: the first update obeys Q += alpha (r + gamma^t max Q(e\'_v) - Q) at each corner',
        ruleBreaks(first, gamma).join('; '));
  const drawn = await page.evaluate(() => ({
    corners: document.querySelectorAll('#lesson-chart .lesson-corner').length,
    e: document.querySelectorAll('#lesson-chart .lesson-e, #lesson-chart .lesson-e-next').length,
    path: document.querySelector('#lesson-chart .lesson-path')?.getAttribute('d') ?? '',
    rows: [...document.querySelectorAll('#lesson-table tr')].map((tr) => [...tr.children].map((c) => c.textContent)),
    shown: !document.getElementById('lesson').hidden,
  }));
  check(drawn.shown && drawn.corners === 4 && drawn.e === 2 && drawn.path.length > 0,
        'learn: the Fig. 4 view draws the cell\'s 4 corners, e, e\' and the action\'s path', JSON.stringify(drawn).slice(0, 200));
  check(drawn.rows.length === 5 && drawn.rows.slice(1).every((r, k) => Number(r[0]) === first.vertices[k].vertex),
        'learn: the table lists each updated vertex', JSON.stringify(drawn.rows));

  // One step at a time through the panel's button, each its own message: the test keeps
  // the table these steps build from zeros and checks every number of every step against it.
  await page.evaluate(async (n) => {
    for (let k = 0; k < n; ++k) {
      document.getElementById('learn-step').click();
      if (k % 40 === 39) await new Promise((resolve) => setTimeout(resolve, 500));   // the server takes 200 messages/s
    }
  }, kChainSteps - 1);
  await waitInPage(page, (n) => mgrl.state.learn.last?.update === n, kChainSteps, 30000, `${kChainSteps} single steps`);
  const chain = await page.evaluate(() => mgrl.state.learn.steps);
  const replay = replayTable(chain);
  const chainBreaks = [...replay.broken, ...chain.flatMap((m) => ruleBreaks(m, gamma))];
  check(chain.length === kChainSteps && chainBreaks.length === 0 && replay.revisits > 0,
        `learn: ${kChainSteps} single steps replayed on the test's own table from zeros: each Q before is what the last ` +
        `update of that (action, vertex) left (${replay.revisits} revisits over ${replay.entries} entries), else 0; each ` +
        `look-ahead within the table's range (${replay.looked} nonzero); alpha, gamma^t, backup and Q after recomputed in float`,
        `${chain.length} messages, ${replay.revisits} revisits; ${chainBreaks.length} breaks: ${chainBreaks.slice(0, 4).join('; ')}`);

  // Ten at a time, then running faster: the count and alpha follow, and every update shown
  // obeys the rule; values learned earlier come back as look-ahead.
  await page.click('#learn-step10');
  await waitInPage(page, (n) => mgrl.state.learn.last?.update === n, kChainSteps + 10, 5000, '10 more steps');
  const ten = await page.evaluate(() => mgrl.state.learn.last);
  check(ten.taken === 10 && ruleHolds(ten, gamma),
        `learn: 10 steps at once: update ${kChainSteps + 10}, alpha ${ten.alpha} = 1 - ${kChainSteps + 9}/${kLessonBudget} ` +
        `(falls linearly over the budget), the rule holds`,
        `taken ${ten.taken}; ${ruleBreaks(ten, gamma).join('; ')}`);
  await page.click('#learn-run');
  for (let k = 0; k < 3; ++k) await page.click('#learn-faster');
  await waitInPage(page, () => mgrl.state.learn.last?.update > 1500, null, 20000, 'the lesson running fast');
  await page.click('#learn-run');   // pause
  const run = await page.evaluate(() => mgrl.state.learn.steps);
  const looked = run.filter((m) => m.vertices.some((v) => v.future !== 0)).length;
  const changed = run.filter((m) => m.vertices.some((v) => v.after !== v.before)).length;
  const runBreaks = run.flatMap((m) => ruleBreaks(m, gamma));
  check(runBreaks.length === 0 && looked > 0 && changed > 0,
        `learn: running, ${run.length} updates shown, each obeys the rule; ${looked} look ahead into learned values`,
        `${runBreaks.length} breaks: ${runBreaks.slice(0, 4).join('; ')}`);
  await screenshot(page, 'teach-learn.png');

  // The hit grid is 3-D: 8 corners per update.
  await page.selectOption('#learn-behavior', 'hit');
  await page.click('#learn-start');
  await waitInPage(page, () => mgrl.state.learn.lesson?.behavior === 'hit', null, 10000, 'a lesson on hit');
  await page.click('#learn-step');
  await waitInPage(page, () => mgrl.state.learn.last?.update === 1, null, 5000, 'the first hit step');
  const hit = await page.evaluate(() => mgrl.state.learn.last);
  const hitGamma = await page.evaluate(() => mgrl.state.learn.lesson.gamma);
  check(hit.vertices.length === 8 && ruleHolds(hit, hitGamma), 'learn: a hit update changes the 8 corners of a 3-D cell by the rule',
        `${hit.vertices.length} corners; ${ruleBreaks(hit, hitGamma).join('; ')}`);
  await page.click('#learn-stop');
  await waitInPage(page, () => mgrl.state.learn.lesson === null, null, 5000, 'the lesson stopped');
  check(await page.evaluate(() => document.getElementById('lesson').hidden), 'learn: stop hides the lesson view');
}

// Live retraining: a reward parameter and a grid resolution changed on the page;
// the server retrains with value iteration and the avatar's policy switches.
async function retrainOnce(page, behaviour, parameter, value) {
  const before = await page.evaluate(() => mgrl.state.learn.retrain.length);
  await page.selectOption('#retrain-behavior', behaviour);
  await page.selectOption('#retrain-parameter', parameter);
  await page.fill('#retrain-value', String(value));
  const started = Date.now();
  await page.click('#retrain-go');
  await waitInPage(page, (n) => mgrl.state.learn.retrain.slice(n).some((m) => m.status === 'done' || m.status === 'failed'),
                   before, 60000, `retraining ${behaviour} with ${parameter} = ${value}`);
  const seconds = (Date.now() - started) / 1000;
  const message = await page.evaluate((n) => mgrl.state.learn.retrain.slice(n).find((m) => m.status !== 'started'), before);
  return {seconds, message};
}

// The trials' summary (app/trials.hpp, Trials::summary) compared field by field: what differs.
function summaryDifferences(server, cli, keys) {
  const same = (a, b) => (a === null && b === null) ||
    (Number.isFinite(a) && Number.isFinite(b) && Math.abs(a - b) <= 1e-9 * Math.max(1, Math.abs(a), Math.abs(b)));
  return keys.filter((k) => !same(server?.[k], cli?.[k])).map((k) => `${k}: server ${server?.[k]}, mgrl eval ${cli?.[k]}`);
}

// The server's "before" and "after" repeated on the command line, from scratch: `mgrl eval`
// of the bundle the server was started with (the page's weights are the bundle's: checked
// before retraining), and `mgrl train` with the bundle's own --set's (its manifest's
// provenance) and the page's change, by value iteration with its defaults as the server's
// retraining, then `mgrl eval` of that bundle; the same trials (count, seconds, seed 1).
// The server counts success by the scenario's criterion, not the retrained reward's (hit's
// contact within the old radius): the second eval declares that criterion
// (behaviors.hit.success), which the behaviour's key leaves out. Its mean return is of the
// retrained reward, the server's of the scenario's: not compared.
function retrainAgainstCommandLine(m, hitBefore, change) {
  const policy = serveOption('--policy').at(-1);
  if (policy === undefined) {
    console.log('#      retrain: no --policy in MGRL_SERVE_ARGS, so no bundle to repeat the trials with: not compared');
    return;
  }
  const bundle = path.resolve(repo, policy);
  const bundleSets = JSON.parse(readFileSync(path.join(bundle, 'manifest.json'), 'utf8')).provenance?.sets ?? [];
  const sets = [...bundleSets, ...serveOption('--set')];
  const where = [...serveOption('--cache').flatMap((d) => ['--cache', d]), ...serveOption('--data').flatMap((d) => ['--data', d])];
  const common = ['--trials', String(kRetrainTrials), '--seconds', String(kRetrainSeconds), '--seed', String(kRetrainSeed), ...where];
  const asSets = (list) => list.flatMap((x) => ['--set', x]);
  const before = JSON.parse(mgrlCommand(['eval', 'scenarios/boxing.yaml', '--policy', bundle, '--json', ...asSets(sets), ...common]));
  const beforeDiff = summaryDifferences(m.before, before,
    ['success_rate', 'successes', 'mean_time_to_hit_s', 'median_time_to_hit_s', 'decisions', 'mean_return']);
  check(beforeDiff.length === 0 && before.success?.text === hitBefore.success,
        `retrain: the server's "before" is \`mgrl eval\` of its bundle on ${kRetrainTrials} trials of ${kRetrainSeconds} s, ` +
        `seed ${kRetrainSeed}: success ${before.success_rate} (${before.successes}), time to hit ${before.mean_time_to_hit_s} s, ` +
        `return ${before.mean_return}`,
        `${beforeDiff.join('; ')}; success "${before.success?.text}", server's "${hitBefore.success}"`);

  const work = mkdtempSync(path.join(os.tmpdir(), 'mgrl-retrain-'));
  try {
    // The server retrains with {type: value_iteration} whatever the bundle's learner: the
    // last --set of the type resets the block to its defaults (approach keeps the bundle's).
    const changed = [...sets, ...Object.entries(change).map(([key, value]) => `behaviors.hit.${key}=${value}`),
                     'behaviors.hit.learner.type=value_iteration'];
    mgrlCommand(['train', 'scenarios/boxing.yaml', ...asSets(changed), '--out', path.join(work, 'policy'), ...where]);
    const criterion = ['behaviors.hit.success.term=contact',
                       `behaviors.hit.success.radius=${hitBefore.parameters['reward.contact_radius']}`];
    const after = JSON.parse(mgrlCommand(['eval', 'scenarios/boxing.yaml', '--policy', path.join(work, 'policy'), '--json',
                                          ...asSets([...changed, ...criterion]), ...common]));
    const afterDiff = summaryDifferences(m.after, after,
      ['success_rate', 'successes', 'mean_time_to_hit_s', 'median_time_to_hit_s', 'decisions']);
    check(afterDiff.length === 0 && after.success?.text === hitBefore.success,
          `retrain: the server's "after" is \`mgrl train\` (value iteration, ${Object.entries(change).map(([k, v]) => `${k}=${v}`)}) ` +
          `then \`mgrl eval\` on the same trials: success ${after.success_rate} (${after.successes}), time to hit ` +
          `${after.mean_time_to_hit_s} s`,
          `${afterDiff.join('; ')}; success "${after.success?.text}", server's "${hitBefore.success}"`);
  } finally {
    rmSync(work, {recursive: true, force: true});
  }
}

async function liveRetraining(page) {
  // What "before" is of: this page's policy, the bundle's tables at the bundle's weights
  // (a page's weights are its own; this page, loaded afresh, has changed none).
  const behaviours = await page.evaluate(() => mgrl.state.scene.behaviors);
  const hitBefore = behaviours.find((b) => b.name === 'hit');
  const policyDir = serveOption('--policy').at(-1);
  if (policyDir !== undefined) {
    const manifest = JSON.parse(readFileSync(path.join(path.resolve(repo, policyDir), 'manifest.json'), 'utf8'));
    check(behaviours.every((b) => !b.retrained && b.weight === manifest.behaviors?.[b.name]?.record?.weight),
          'retrain: before it, the page runs the bundle\'s tables at the bundle\'s weights',
          JSON.stringify(behaviours.map((b) => [b.name, b.weight, manifest.behaviors?.[b.name]?.record?.weight, b.retrained])));
  }
  const radius = await retrainOnce(page, 'hit', 'reward.contact_radius', 0.3);
  const m = radius.message;
  check(m.status === 'done' && m.learner === 'value_iteration' && Number.isFinite(m.before?.success_rate) &&
        Number.isFinite(m.after?.success_rate) && m.set['reward.contact_radius'] === 0.3 && m.trials === kRetrainTrials,
        `retrain: hit with contact radius 0.3 m retrained by value iteration in ${radius.seconds.toFixed(1)} s ` +
        `(server ${Number(m.seconds).toFixed(1)} s); success ${(100 * m.before?.success_rate).toFixed(1)} % -> ` +
        `${(100 * m.after?.success_rate).toFixed(1)} % on ${m.trials} trials`, JSON.stringify(m).slice(0, 300));
  const scene = await page.evaluate(() => mgrl.state.scene.behaviors.find((b) => b.name === 'hit'));
  const status = await page.evaluate(() => document.getElementById('retrain-status').textContent);
  check(scene.retrained?.['reward.contact_radius'] === 0.3 && scene.learner === 'value_iteration' &&
        scene.parameters['reward.contact_radius'] === 0.3 && status.includes('→'),
        'retrain: the scene says hit is retrained and the page shows old -> new success', `${JSON.stringify(scene.retrained)}; "${status}"`);
  // The command line's numbers, with the world held still meanwhile (2 cores).
  await setPaused(page, true);
  retrainAgainstCommandLine(m, hitBefore, {'reward.contact_radius': 0.3});
  await setPaused(page, false);

  const grid = await retrainOnce(page, 'hit', 'discretizer.angles', 10);
  // Its "before" is the page's policy as the first retraining left it: that one's "after".
  check(grid.message.status === 'done' && grid.message.vertices !== m.vertices && grid.message.set['discretizer.angles'] === 10 &&
        grid.message.set['reward.contact_radius'] === 0.3 && JSON.stringify(grid.message.before) === JSON.stringify(m.after),
        `retrain: hit on a coarser grid (10 angles, ${grid.message.vertices} vertices against ${m.vertices}) in ` +
        `${grid.seconds.toFixed(1)} s; its "before" is the first retraining's "after"`,
        `${JSON.stringify(grid.message).slice(0, 300)}; first's after ${JSON.stringify(m.after)}`);

  // A value the reward refuses: one error naming it, nothing retrained.
  const errorsBefore = await page.evaluate(() => mgrl.state.errors.length);
  await page.selectOption('#retrain-parameter', 'reward.contact_radius');
  await page.fill('#retrain-value', '-1');
  await page.click('#retrain-go');
  await waitInPage(page, (n) => mgrl.state.errors.length > n, errorsBefore, 10000, 'the refusal of a negative radius');
  const error = await page.evaluate(() => mgrl.state.lastError);
  check(/contact_radius/.test(error), 'retrain: a negative contact radius is refused naming the parameter', error);

  await page.click('#retrain-revert');
  await waitInPage(page, () => !mgrl.state.scene.behaviors.find((b) => b.name === 'hit').retrained, null, 10000, 'revert');
  ok('retrain: revert goes back to the policy bundle\'s table');
  console.log(`#      retraining hit from the page: contact radius ${radius.seconds.toFixed(1)} s, angles ${grid.seconds.toFixed(1)} s (click to new policy)`);
}

// A dodge scene (scenarios/dodge.yaml, a second server) shows the avatar and the
// scripted opponent it was trained against as two bodies, the opponent closing in.
async function dodgeScene() {
  await stopServer();
  const more = [];
  for (let k = 0; k < serveArgs.length; ++k) {
    if (serveArgs[k] === '--policy') ++k;
    else if (!serveArgs[k].startsWith('--policy=')) more.push(serveArgs[k]);
  }
  const policy = process.env.MGRL_DODGE_POLICY;
  if (policy) more.push('--policy', policy);
  else console.log('# MGRL_DODGE_POLICY unset: the dodge page runs the online search');
  const url = await startServer('scenarios/dodge.yaml', more);
  ok(`the dodge server listens at ${url}`);
  await page.close();  // its server is gone: it would only try to reconnect
  const dodge = page = await browser.newPage({viewport: {width: 1280, height: 800}});
  const errors = [];
  dodge.on('pageerror', (e) => errors.push(e.message));
  await dodge.goto(url);
  await waitForWorld(dodge, 'sparring', 2);
  const scene = await dodge.evaluate(() => mgrl.state.scene);
  check(scene.opponent === 'pursue' && scene.scenario === 'dodge' && scene.controller === (policy ? 'policy' : 'online_search'),
        'a dodge page opens on the avatar and its scripted opponent (scene.opponent "pursue")',
        JSON.stringify({opponent: scene.opponent, scenario: scene.scenario, controller: scene.controller}));
  await dodge.evaluate(() => mgrl.renderHud());
  const note = await dodge.evaluate(() => document.getElementById('note').textContent);
  check(/Blue: the scripted opponent/.test(note), 'the HUD says who the blue corner is', note);
  // Over 15 s the opponent follows the avatar, which keeps away from it: it moves off its
  // start (pelvis, on the floor) while the two stay within 3 m. Both are drawn as bodies.
  const gaps = [];
  let start = null, travelled = 0;
  const began = Date.now();
  while (Date.now() - began < 15000) {
    const [a, b] = await dodge.evaluate(() => [mgrl.rootOf(0), mgrl.rootOf(1)]);
    if (a && b) {
      start ??= b;
      gaps.push(floorDistance(a, b));
      travelled = Math.max(travelled, floorDistance(b, start));
    }
    await sleep(200);
  }
  gaps.sort((x, y) => x - y);
  const gapText = gaps.length ? `pelvises ${gaps[0].toFixed(2)} to ${gaps[gaps.length - 1].toFixed(2)} m apart ` +
      `(median ${gaps[gaps.length >> 1].toFixed(2)}), the opponent ${travelled.toFixed(2)} m off its start` : 'no frames';
  console.log(`#      dodge: ${gapText}`);
  check(gaps.length > 20 && travelled >= 0.5 && gaps[gaps.length - 1] <= 3,
        'the scripted opponent follows the avatar (0.5 m or more off its start, never 3 m away)', gapText);
  const bodies = await dodge.evaluate(() => mgrl.bodies());
  check(bodies.look === 'body' && bodies.heads === 2 && bodies.joints >= 20, 'the avatar and its opponent are drawn as bodies',
        JSON.stringify(bodies));
  await dodge.evaluate(() => mgrl.fit());
  await sleep(500);
  await screenshot(dodge, 'viewer-dodge.png');
  check(errors.length === 0, 'no script errors in the dodge page', errors.join('; '));
}

async function main() {
  mkdirSync(screenshotDir, {recursive: true});
  const url = await startServer();
  ok(`the server listens at ${url}`);

  browser = await chromium.launch({
    executablePath: chromiumPath,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
           '--disable-component-update', '--no-first-run',
           // WebGL without a GPU: ANGLE on SwiftShader, the software Vulkan.
           '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
  page = await browser.newPage({viewport: {width: 1280, height: 800}});
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));
  page.on('console', (message) => {
    // (ReadPixels stalls are pixelStats()'s own doing.)
    if ((message.type() === 'warning' || message.type() === 'error') && !/GL Driver Message/.test(message.text())) console.log(`#      page ${message.type()}: ${message.text()}`);
  });
  const outside = [];
  page.on('request', (request) => {
    if (!request.url().startsWith('data:') && !request.url().startsWith(url) && !request.url().startsWith(url.replace('http:', 'ws:'))) outside.push(request.url());
  });
  await page.goto(url);
  await openPanelSections(page);

  const target = await targetMode(page);
  const targetRows = await page.evaluate(() => [...document.querySelectorAll('#hud-table tr')].map((tr) => tr.cells[0].textContent));
  check(targetRows.includes('hits') && !targetRows.includes('blocked'), 'target mode: the HUD has no "blocked" row (a target has no guard)',
        targetRows.join(', '));

  await page.click('#mode-sparring');
  await waitForWorld(page, 'sparring', 2);
  const sparring = await measured(page, 2);
  check(sparring.fps >= kMinFramesPerSecond, `sparring: frames keep arriving (>= ${kMinFramesPerSecond}/s over 3 s)`,
        `${sparring.fps.toFixed(1)}/s`);
  const sparScene = await page.evaluate(() => mgrl.state.scene.scenario);
  check(sparScene === 'boxing_spar', 'sparring plays boxing.yaml\'s sparring_scenario, boxing_spar (a fighting distance)', sparScene);
  // A new world: the target mode's hit lines are gone (sparring has no target).
  const oldLines = await page.evaluate(() => [...document.querySelectorAll('#hits li')]
    .map((li) => li.textContent).filter((t) => t.includes(' on target ')));
  check(oldLines.length === 0, 'after the switch to sparring the HUD lists no target-mode hits', oldLines.join(' | '));
  // A landed punch makes the struck part of the partner flash.
  await waitInPage(page, () => mgrl.bodies().struck > 0, null, 20000, 'a struck body part flashing in sparring');
  check(true, 'sparring: a landed punch flashes the struck part of the partner\'s body');
  // A punch that meets the partner's forearm is blocked: its message says so, the
  // HUD lists it as "blocked ... by avatar N left arm" and counts it apart from the hits.
  await waitInPage(page, () => mgrl.state.hits.some((h) => h.blocked === true), null, 30000, 'a blocked punch in sparring');
  const blockedHit = await page.evaluate(() => mgrl.state.hits.find((h) => h.blocked === true));
  check(blockedHit.part === 'left_arm' || blockedHit.part === 'right_arm', 'sparring: a blocked punch names the arm that blocked it',
        JSON.stringify(blockedHit));
  await waitInPage(page, () => [...document.querySelectorAll('#hits li')].some((li) => /^blocked .* by avatar \d (left|right) arm/.test(li.textContent)),
                   null, 5000, 'a "blocked" line in the HUD');
  const blockedRow = await page.evaluate(() => [...document.querySelectorAll('#hud-table tr')]
    .map((tr) => [tr.cells[0].textContent, tr.cells[1].textContent]).find(([name]) => name === 'blocked'));
  check(blockedRow !== undefined && Number(blockedRow[1]) >= 1, 'the HUD counts blocked punches apart from hits',
        JSON.stringify(blockedRow));
  await screenshot(page, 'viewer-sparring.png');

  // Follow: the camera keeps looking at avatar 0 (its root, at 1 m) as it moves.
  await page.check('#follow');
  await sleep(1500);
  const centre = await page.evaluate(() => {
    const [x, , z] = mgrl.rootOf(0);
    const p = mgrl.project([x, 1, z]);
    return {dx: p.x - innerWidth / 2, dy: p.y - innerHeight / 2};
  });
  await page.uncheck('#follow');
  check(Math.hypot(centre.dx, centre.dy) < 40, 'follow keeps avatar 0 in the middle of the view',
        `${Math.hypot(centre.dx, centre.dy).toFixed(0)} px off centre`);

  await setCrowdSize(page, 100);
  await page.click('#mode-crowd');
  await waitForWorld(page, 'crowd', 100);
  const crowd100 = await measured(page, 100);
  check(crowd100.fps >= kMinFramesPerSecond, `crowd of 100: frames keep arriving (>= ${kMinFramesPerSecond}/s over 3 s)`,
        `${crowd100.fps.toFixed(1)}/s`);
  await screenshot(page, 'viewer-crowd.png');
  // Bodies (capsules, a sphere per joint, gloves and shoes) by default; bones
  // only as a toggle, for teaching. Its budget for bodies is 20 % more per draw (see the bound below).
  const bodies = await page.evaluate(() => mgrl.bodies());
  check(bodies.look === 'body' && bodies.heads === 100 && bodies.joints >= 10 * bodies.heads,
        'the crowd is drawn as bodies (spheres closing the capsules at 10 or more joints each)', JSON.stringify(bodies));
  await page.check('#bones-look');
  const bones100 = await measured(page, 100);
  const thin = await page.evaluate(() => mgrl.bodies());
  check(thin.look === 'bones' && thin.joints === 0 && thin.bones === bodies.bones,
        '"bones only" draws the bones without the joint spheres', JSON.stringify(thin));
  await screenshot(page, 'viewer-crowd-bones.png');
  await page.uncheck('#bones-look');
  // Each look measured five times, alternately, and each bodies draw compared with the
  // bones draw measured right after it: the machine's load (the README check and the demo
  // run beside this test) changes between pairs, not within one. The median ratio is checked.
  const bodyRuns = [crowd100.drawMs], boneRuns = [bones100.drawMs];
  for (let k = 0; k < 4; ++k) {
    bodyRuns.push((await measured(page, 100)).drawMs);
    await page.check('#bones-look');
    boneRuns.push((await measured(page, 100)).drawMs);
    await page.uncheck('#bones-look');
  }
  const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];
  const ratio = median(bodyRuns.map((ms, k) => ms / boneRuns[k]));
  // The page's own cost of a draw (ms, writing the instances and the draw call): what
  // limits its frame rate. Draws per second are not compared: on a software renderer the
  // page rests as long as a slow draw took between draws, so they swing with the machine.
  const listed = (xs) => xs.map((x) => x.toFixed(1)).join(', ');
  console.log(`# 100 avatars: ${listed(bodyRuns)} ms a draw as bodies (${crowd100.drawn.toFixed(1)} draws/s), ` +
              `${listed(boneRuns)} ms as bones (${bones100.drawn.toFixed(1)} draws/s)`);
  // A guard against a regression, not the budget of 20 % for bodies over bones: on Chromium's software
  // renderer the ratio measured 1.20 at 0c49a9d and 1.22 to 1.32 later with the same drawing
  // code (quiet machine and under load), so a 20 % bound failed by chance. The budget itself
  // wants a benchmark on a real GPU.
  check(ratio <= 1.35, 'bodies cost at most 35 % more than bones a draw at 100 avatars (median of 5 paired ratios)',
        `${ratio.toFixed(2)}x`);
  await panelControls(page);

  const table = [sparring];
  for (const avatars of [60, 1000]) {
    await setCrowdSize(page, avatars);
    await waitForWorld(page, 'crowd', avatars);
    table.push(await measured(page, avatars));
  }
  table.splice(2, 0, crowd100);

  console.log('#');
  console.log('#      avatars | frames/s received | drawn/s | page ms/draw | bytes/avatar-frame | frame bytes | server ms/frame | decision us | dropped');
  for (const row of table) {
    const cell = (v, digits = 0, width = 8) => String(Number.isFinite(v) ? v.toFixed(digits) : '?').padStart(width);
    console.log(`#     ${cell(row.avatars, 0, 8)} | ${cell(row.fps, 1, 17)} | ${cell(row.drawn, 1, 7)} | ${cell(row.drawMs, 1, 12)} | ${cell(row.bytes, 0, 18)} | ` +
                `${cell(row.frameBytes, 0, 11)} | ${cell(row.serverMs, 2, 15)} | ${cell(row.decisionUs, 2, 11)} | ${cell(row.dropped, 0, 7)}`);
  }
  console.log(`#      drag to first step ${target.stepAfter === null ? 'n/a' : target.stepAfter.toFixed(2) + ' s'}, ` +
              `drag to first hit ${target.hitAfter.toFixed(2)} s (simulated)`);
  console.log('#');

  const errors = await page.evaluate(() => mgrl.state.errors);
  check(errors.length === 1, 'no error from the server but the one asked for', errors.join('; '));
  const bad = await page.evaluate(() => mgrl.state.frames.bad);
  check(bad === 0, 'every binary frame was well-formed', `${bad} refused`);

  // The teaching views on the page loaded afresh, as a class would open it: a new
  // connection is a new world in target mode, with a clean HUD and the first camera.
  await page.goto(url);
  await waitInPage(page, () => {
    const s = window.mgrl?.state;
    return s?.scene?.mode === 'target' && s.frames.count > 0 && s.draw.count >= 5;
  }, null, 30000, 'the reloaded page gets a target-mode scene and frames, and draws');
  await openPanelSections(page);
  await teachViews(page);
  await valuesAcrossModeChange(page);
  const after = await page.evaluate(() => ({errors: mgrl.state.errors, bad: mgrl.state.frames.bad}));
  check(after.errors.length === 0 && after.bad === 0, 'the teaching views: no error from the server, every frame well-formed',
        `${after.errors.join('; ')}; ${after.bad} frames refused`);
  await learnPanel(page);
  await liveRetraining(page);
  const learnt = await page.evaluate(() => ({errors: mgrl.state.errors, bad: mgrl.state.frames.bad}));
  check(learnt.errors.length === 1 && learnt.bad === 0, 'learn and retrain: no error from the server but the one asked for',
        learnt.errors.join('; '));
  await smallWindow(url);
  check(pageErrors.length === 0, 'no script errors in the page', pageErrors.join('; '));
  check(outside.length === 0, 'the page loads nothing from outside the server', outside.join(', '));
  await dodgeScene();
}

const overall = setTimeout(async () => {
  console.log(`FAIL - the test did not finish within ${overallSeconds} s`);
  await cleanUp();
  process.exit(1);
}, overallSeconds * 1000);

process.on('exit', () => { if (server !== null && server.exitCode === null) server.kill('SIGKILL'); });

let failure = null;
try {
  await main();
} catch (e) {
  failure = e;
}
clearTimeout(overall);
if (failure !== null && page !== null) {
  const file = path.join(screenshotDir, 'viewer-failure.png');
  if (await page.screenshot({path: file, timeout: 10000}).then(() => true, () => false)) console.log(`# the page at the failure: ${file}`);
}
await cleanUp();
if (failure !== null) {
  console.log(`FAIL - ${failure instanceof CheckFailed ? failure.message : failure.stack}`);
  if (serverLines.length > 0) console.log(`# the server's last lines:\n${serverLines.slice(-30).map((l) => '#   ' + l).join('\n')}`);
  console.log(`${passed} passed, 1 failed`);
  process.exit(1);
}
console.log(`${passed} passed, 0 failed`);
