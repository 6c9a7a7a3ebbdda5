// The `mgrl compare` report (issue 15) in headless Chromium: it opens from disk with no
// network, and every plot is drawn (each SVG has a size and shapes in it).
//
//   node tests/web/report_test.mjs REPORT_DIR [SCREENSHOT.png]
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
const kMetrics = 11;  // bar charts, one per metric in app/compare_command.cpp, plus the residual curve

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
    const shapes = svg.querySelectorAll('rect, polyline, line').length;
    return {label: svg.getAttribute('aria-label'), width: box.width, height: box.height, shapes};
  }));
  // A metric no learner recorded (bundles from before it existed) has no plot.
  check(plots.length >= kMetrics - 2 && plots.length <= kMetrics + 1,
        `the report has a plot per metric recorded and the residual curve (${kMetrics + 1} at most)`,
        `found ${plots.length}`);
  for (const plot of plots)
    check(plot.width > 100 && plot.height > 40 && plot.shapes > 0, `plot "${plot.label}" is drawn`,
          `${plot.width}x${plot.height} px, ${plot.shapes} shapes`);
  const rows = await page.evaluate(() => document.querySelectorAll('table tr').length);
  check(rows >= 2, 'the table has a row per learner', `${rows - 1} rows`);
  check(outside.length === 0, 'the report loads nothing from the network', outside.join(', '));
  check(errors.length === 0, 'no script errors', errors.join('; '));
  if (screenshot) await page.screenshot({path: screenshot, fullPage: true});
} finally {
  await browser.close();
  clearTimeout(timer);
}
console.log(failed ? `report_test: ${failed} failed` : 'report_test: every check passed');
process.exit(failed ? 1 : 0);
