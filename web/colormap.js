// Colours for the teaching views: a viridis-like ramp for values (dark blue-violet for
// low, yellow for high; perceptually even and readable without colour vision) and well
// separated hues for action indices. Colours are [r, g, b] in 0..1, sRGB.

// Nine samples of matplotlib's viridis at 0, 1/8, ..., 1; between them the ramp is
// linear in sRGB, close enough to the original for a heat map.
const kViridis = [
  [0x44, 0x01, 0x54], [0x47, 0x2c, 0x7a], [0x3b, 0x51, 0x8b], [0x2c, 0x71, 0x8e], [0x21, 0x90, 0x8d],
  [0x27, 0xad, 0x81], [0x5c, 0xc8, 0x63], [0xaa, 0xdc, 0x32], [0xfd, 0xe7, 0x25],
].map((c) => c.map((v) => v / 255));

/** The ramp's colour at t (clamped to 0..1; NaN counts as 0). */
export function viridis(t) {
  const x = Number.isFinite(t) ? Math.min(1, Math.max(0, t)) * (kViridis.length - 1) : 0;
  const k = Math.min(Math.floor(x), kViridis.length - 2);
  const f = x - k;
  const a = kViridis[k], b = kViridis[k + 1];
  return [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f];
}

/** A CSS linear-gradient (left to right) of the ramp, for a legend. */
export function viridisGradient() {
  const stops = kViridis.map((c, k) => `${css(c)} ${(100 * k / (kViridis.length - 1)).toFixed(1)}%`);
  return `linear-gradient(to right, ${stops.join(', ')})`;
}

/**
 * The colour of action index k: hues a golden angle apart, so neighbouring indices
 * (which mean nothing alike) never look alike, and lightness alternating in threes so
 * hues that come round close again still differ.
 */
export function actionColour(k) {
  const hue = ((k * 137.508) % 360) / 360;
  const lightness = [0.58, 0.45, 0.7][Math.floor(k / 3) % 3];
  return hsl(hue, 0.75, lightness);
}

/** A CSS gradient of hard-edged swatches for action indices 0..n-1. */
export function actionGradient(n) {
  if (n <= 0) return 'none';
  const stops = [];
  for (let k = 0; k < n; ++k) stops.push(`${css(actionColour(k))} ${(100 * k / n).toFixed(2)}% ${(100 * (k + 1) / n).toFixed(2)}%`);
  return `linear-gradient(to right, ${stops.join(', ')})`;
}

export function css([r, g, b]) {
  return `rgb(${Math.round(r * 255)}, ${Math.round(g * 255)}, ${Math.round(b * 255)})`;
}

function hsl(h, s, l) {
  const q = l < 0.5 ? l * (1 + s) : l + s - l * s;
  const p = 2 * l - q;
  const channel = (t) => {
    t = (t + 1) % 1;
    if (t < 1 / 6) return p + (q - p) * 6 * t;
    if (t < 1 / 2) return q;
    if (t < 2 / 3) return p + (q - p) * (2 / 3 - t) * 6;
    return p;
  };
  return [channel(h + 1 / 3), channel(h), channel(h - 1 / 3)];
}
