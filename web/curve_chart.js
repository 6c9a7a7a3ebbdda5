// The learning-curve chart: each behaviour's training curve from the `scene` (rows of
// [updates, seconds, residual, mean residual], docs/viewer-protocol.md) as the Bellman
// residual on a log scale against updates, one line per behaviour (the mean residual
// dashed where the learner measured it). Plain SVG, drawn here.

const kNs = 'http://www.w3.org/2000/svg';
const kWidth = 500, kHeight = 260;
const kMargin = {left: 50, right: 14, top: 44, bottom: 36};
const kLineColours = ['#4fc3f7', '#ffb74d', '#81c784', '#f06292', '#ba68c8', '#e0e0e0'];

function element(name, attributes = {}, text = null) {
  const e = document.createElementNS(kNs, name);
  for (const [k, v] of Object.entries(attributes)) e.setAttribute(k, String(v));
  if (text !== null) e.textContent = text;
  return e;
}

/** Decades (and 2x, 5x when the range spans under two decades) within [lo, hi], lo > 0. */
function logTicks(lo, hi) {
  const ticks = [];
  const first = Math.floor(Math.log10(lo)), last = Math.ceil(Math.log10(hi));
  const steps = Math.log10(hi / lo) < 2 ? [1, 2, 5] : [1];
  for (let k = first; k <= last; ++k) {
    for (const s of steps) {
      const v = s * 10 ** k;
      if (v >= lo * 0.999 && v <= hi * 1.001) ticks.push(v);
    }
  }
  return ticks;
}

/** About five round values (1, 2 or 5 times a power of ten apart) within [lo, hi]. */
function linearTicks(lo, hi) {
  const raw = (hi - lo) / 5 || 1;
  const power = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((s) => s * power).find((s) => s >= raw);
  const ticks = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi * 1.000001; v += step) ticks.push(v);
  return ticks;
}

/** 1500000 -> "1.5M", 20000 -> "20k". */
export function shortCount(v) {
  for (const [unit, size] of [['G', 1e9], ['M', 1e6], ['k', 1e3]]) {
    if (Math.abs(v) >= size) return `${+(v / size).toPrecision(3)}${unit}`;
  }
  return `${+v.toPrecision(3)}`;
}

/** A power of ten as "10" with its exponent raised (an SVG <text>). */
function powerLabel(v, attributes) {
  const k = Math.round(Math.log10(v));
  if (Math.abs(v / 10 ** k - 1) > 1e-6) return element('text', attributes, v.toPrecision(1));
  const text = element('text', attributes, '10');
  text.append(element('tspan', {dy: -5, 'font-size': 8}, String(k).replace('-', '−')));
  return text;
}

/**
 * Draws the curves of `behaviours` (scene.behaviors: {name, learner, curve}) into `svg`,
 * replacing what it held. `logX`: updates on a log scale too. Returns how many behaviours
 * had a curve to draw.
 */
export function drawCurves(svg, behaviours, {logX = true} = {}) {
  svg.replaceChildren();
  svg.setAttribute('viewBox', `0 0 ${kWidth} ${kHeight}`);
  const series = behaviours.map((b, k) => {
    const rows = Array.isArray(b.curve) ? b.curve.filter((r) => Array.isArray(r) && r.length >= 3) : [];
    const usable = (v) => Number.isFinite(v) && v > 0;
    return {
      name: String(b.name), learner: b.learner ? String(b.learner) : '?', colour: kLineColours[k % kLineColours.length],
      max: rows.filter((r) => usable(r[2]) && (!logX || usable(r[0]))).map((r) => [r[0], r[2]]),
      mean: rows.filter((r) => usable(r[3]) && (!logX || usable(r[0]))).map((r) => [r[0], r[3]]),
    };
  });
  const all = series.flatMap((s) => s.max.concat(s.mean));
  const plotted = series.filter((s) => s.max.length > 0).length;

  svg.append(element('text', {x: 8, y: 15, class: 'chart-title'}, 'Bellman residual against updates'));
  if (all.length === 0) {
    svg.append(element('text', {x: kWidth / 2, y: kHeight / 2, 'text-anchor': 'middle', class: 'chart-empty'},
                       'no training curves: the server has no policy bundle'));
    return 0;
  }

  const xs = all.map((p) => p[0]), ys = all.map((p) => p[1]);
  let [x0, x1] = [Math.min(...xs), Math.max(...xs)];
  if (!logX) x0 = 0;
  if (x1 <= x0) x1 = logX ? x0 * 10 : x0 + 1;
  let [y0, y1] = [Math.min(...ys), Math.max(...ys)];
  y0 = 10 ** Math.floor(Math.log10(y0));
  y1 = 10 ** Math.ceil(Math.log10(y1));
  if (y1 <= y0) y1 = y0 * 10;
  const left = kMargin.left, right = kWidth - kMargin.right, top = kMargin.top, bottom = kHeight - kMargin.bottom;
  const sx = logX ? (v) => left + (Math.log10(v) - Math.log10(x0)) / (Math.log10(x1) - Math.log10(x0)) * (right - left)
                  : (v) => left + (v - x0) / (x1 - x0) * (right - left);
  const sy = (v) => bottom - (Math.log10(v) - Math.log10(y0)) / (Math.log10(y1) - Math.log10(y0)) * (bottom - top);

  const axes = element('g', {class: 'chart-axes'});
  for (const v of logTicks(y0, y1)) {
    const y = sy(v).toFixed(1);
    axes.append(element('line', {x1: left, x2: right, y1: y, y2: y, class: 'chart-grid'}));
    axes.append(powerLabel(v, {x: left - 6, y: Number(y) + 4, 'text-anchor': 'end'}));
  }
  for (const v of logX ? logTicks(x0, x1) : linearTicks(x0, x1)) {
    const x = sx(v).toFixed(1);
    axes.append(element('line', {x1: x, x2: x, y1: top, y2: bottom, class: 'chart-grid'}));
    axes.append(element('text', {x, y: bottom + 14, 'text-anchor': 'middle'}, shortCount(v)));
  }
  axes.append(element('rect', {x: left, y: top, width: right - left, height: bottom - top, class: 'chart-frame'}));
  axes.append(element('text', {x: (left + right) / 2, y: kHeight - 6, 'text-anchor': 'middle'},
                      `updates${logX ? ' (log)' : ''}`));
  axes.append(element('text', {x: 12, y: (top + bottom) / 2, 'text-anchor': 'middle',
                               transform: `rotate(-90 12 ${(top + bottom) / 2})`}, 'residual (log)'));
  svg.append(axes);

  const points = (rows) => rows.map(([u, r]) => `${sx(u).toFixed(1)},${sy(r).toFixed(1)}`).join(' ');
  series.forEach((s) => {
    if (s.mean.length > 1) {
      svg.append(element('polyline', {points: points(s.mean), stroke: s.colour, class: 'chart-mean',
                                      'data-behavior': s.name, 'data-points': s.mean.length}));
    }
    if (s.max.length > 0) {
      svg.append(element('polyline', {points: points(s.max), stroke: s.colour, class: 'chart-line',
                                      'data-behavior': s.name, 'data-points': s.max.length}));
      const [u, r] = s.max[s.max.length - 1];
      svg.append(element('circle', {cx: sx(u).toFixed(1), cy: sy(r).toFixed(1), r: 2.5, fill: s.colour}));
    }
  });

  // The legend, across the top: colour, behaviour, learner.
  let x = 8;
  const legend = element('g', {class: 'chart-legend'});
  series.forEach((s) => {
    legend.append(element('line', {x1: x, x2: x + 16, y1: 29, y2: 29, stroke: s.colour, 'stroke-width': 2.5}));
    const label = `${s.name} (${s.learner})${s.max.length === 0 ? ': no curve' : ''}`;
    legend.append(element('text', {x: x + 20, y: 33}, label));
    x += 28 + label.length * 6.2;
  });
  if (series.some((s) => s.mean.length > 1)) legend.append(element('text', {x: kWidth - 8, y: 15, 'text-anchor': 'end'}, 'dashed: mean residual'));
  svg.append(legend);
  return plotted;
}
