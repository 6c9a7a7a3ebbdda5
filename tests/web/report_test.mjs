// The `mgrl compare` report in headless Chromium: it opens from disk with no
// network, and every plot is drawn (each SVG has a size and shapes in it), the learning
// curves with a line per run, and the table has a row for every learner of results.json.
//
//   node tests/web/report_test.mjs REPORT_DIR [SCREENSHOT.png]
import fs from 'node:fs';
import {createRequire} from 'node:module';
import path from 'node:path';
import {fileURLToPath, pathToFileURL} from 'node:url';

const repo = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const {chromium} = createRequire(path.join(repo, 'web/package.json'))('playwright-core');

const [reportDir, screenshot] = process.argv.slice(2);
if (!reportDir) {
  console.error('usage: node tests/web/report_test.mjs REPORT_DIR [SCREENSHOT.png]');
  process.exit(2);
}
const kMetrics = 11;  // bar charts, one per metric in app/compare_report.cpp
// The learning curves, every run on one plot each: success rate from the
// snapshots along training, Bellman residual as recorded, against updates and seconds.
const kCurves = ['Success rate against updates', 'Success rate against training seconds',
                 'Bellman residual against updates', 'Bellman residual against training seconds'];

const timer = setTimeout(() => {
  console.error('report_test: no result within 60 s');
  process.exit(1);
}, 60_000);

let failed = 0;
function check(condition, what, detail = '') {
  console.log(`${condition ? 'ok  ' : 'FAIL'} - ${what}${detail ? ': ' + detail : ''}`);
  if (!condition) failed += 1;
}

const browser = await chromium.launch({
  executablePath: process.env.MGRL_CHROMIUM ?? '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
         '--disable-component-update', '--no-first-run'],
});
try {
  const page = await browser.newPage({viewport: {width: 1200, height: 1400}});
  const outside = [];
  page.on('request', (request) => {
    if (!request.url().startsWith('file:')) outside.push(request.url());
  });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(pathToFileURL(path.resolve(reportDir, 'index.html')).href);
  const plots = await page.evaluate(() => [...document.querySelectorAll('svg')].map((svg) => {
    const box = svg.getBoundingClientRect();
    const shapes = svg.querySelectorAll('rect, polyline, line, circle').length;
    // Each line's drawn points (a polyline with fewer than 2 draws nothing).
    const lines = [...svg.querySelectorAll('polyline')].map(
        (p) => p.getAttribute('points').trim().split(/\s+/).filter((xy) => xy.length > 0).length);
    const dots = svg.querySelectorAll('circle').length;
    return {label: svg.getAttribute('aria-label'), width: box.width, height: box.height, shapes, lines, dots};
  }));
  // A metric no learner recorded (bundles from before it existed) has no plot.
  check(plots.length >= kMetrics - 2 + kCurves.length && plots.length <= kMetrics + kCurves.length,
        `the report has a plot per metric recorded and the ${kCurves.length} learning curves ` +
        `(${kMetrics + kCurves.length} at most)`, `found ${plots.length}`);
  const results = JSON.parse(fs.readFileSync(path.resolve(reportDir, 'results.json'), 'utf8'));
  const runs = (results.runs ?? []).length;
  for (const label of kCurves) {
    const plot = plots.find((p) => p.label === label);
    const drawn = plot ? plot.lines.filter((n) => n >= 2).length : 0;
    check(plot && runs >= 1 && drawn === runs, `"${label}" has a line of at least 2 points per run (${runs})`,
          plot ? `lines of ${plot.lines.join(', ')} points` : 'no such plot');
    if (label.startsWith('Success rate'))
      check(plot && plot.dots >= 2 * 5, `"${label}" marks each snapshot`, plot ? `${plot.dots} dots` : '');
  }
  for (const plot of plots)
    check(plot.width > 100 && plot.height > 40 && plot.shapes > 0, `plot "${plot.label}" is drawn`,
          `${plot.width}x${plot.height} px, ${plot.shapes} shapes`);
  // Every learner compared (results.json's learner_names, written with the page) has its
  // row, and nothing else has one: a report that lost a learner's row fails here.
  const learners = results.learner_names ?? [];
  const rows = await page.evaluate(() => [...document.querySelectorAll('table tr')].slice(1).map(
      (tr) => (tr.cells[0]?.textContent ?? '').trim()));
  check(learners.length >= 1, 'results.json names the learners compared', JSON.stringify(learners));
  for (const learner of learners)
    check(rows.includes(learner), `the table has a row for ${learner}`, `rows: ${rows.join(', ')}`);
  check(rows.length === learners.length, 'the table has one row per learner and no other',
        `${rows.length} rows for ${learners.length} learners`);
  check(outside.length === 0, 'the report loads nothing from the network', outside.join(', '));
  check(errors.length === 0, 'no script errors', errors.join('; '));
  if (screenshot) await page.screenshot({path: screenshot, fullPage: true});
} finally {
  await browser.close();
  clearTimeout(timer);
}
console.log(failed ? `report_test: ${failed} failed` : 'report_test: every check passed');
process.exit(failed ? 1 : 0);
