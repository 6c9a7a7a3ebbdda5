// The teaching views (paper sec. 4 and 5): the panel's "Teach" section, which
// asks the server for one behaviour's values (`values` messages, docs/viewer-protocol.md),
// the HUD's read-outs of them (legend, state, chosen action), and the learning-curve
// overlay drawn from the scene's training curves. The heat map itself is values_view.js.
import {actionGradient, viridisGradient} from './colormap.js';
import {drawCurves} from './curve_chart.js';

const $ = (id) => document.getElementById(id);
const kKeptMessages = 2000;

/** A value as the legend shows it: three significant digits, exponent when tiny or huge. */
export function formatValue(v) {
  if (!Number.isFinite(v)) return '–';
  if (v !== 0 && (Math.abs(v) < 1e-3 || Math.abs(v) >= 1e4)) return v.toExponential(2);
  return v.toPrecision(3);
}

// A `values` message as the page needs it, or the reason it is not.
function problemOf(m) {
  if (typeof m.behavior !== 'string') return 'no "behavior"';
  if (!Array.isArray(m.points)) return 'no "points" list';
  if (!m.points.every((p) => Array.isArray(p) && p.length === 5 && p.every(Number.isFinite))) {
    return '"points" must be [x, y, z, V, greedy] numbers';
  }
  if (!Number.isFinite(m.v_min) || !Number.isFinite(m.v_max)) return 'no "v_min"/"v_max"';
  if (!Number.isInteger(m.chosen) || !Number.isInteger(m.actions) || !Number.isFinite(m.height)) {
    return 'no "chosen"/"actions"/"height"';
  }
  if (m.path !== undefined && !(Array.isArray(m.path) && m.path.every((p) => Array.isArray(p) && p.length === 3))) {
    return '"path" must be [x, y, z] points';
  }
  return null;
}

export class Teach {
  /**
   * @param send  sends one page message (an object)
   * @param view  the ValuesView that draws the heat map and path
   * @param redraw  called when the scene must be drawn again
   */
  constructor(send, view, redraw) {
    this.send = send;
    this.view = view;
    this.redraw = redraw;
    this.behaviours = [];
    this.curvesKey = null;
    // What the page shows and received (window.mgrl.state.values, for tests): the
    // behaviour asked for, the colouring, every `values` message's behaviour, time and
    // point count, and the last one drawn.
    this.record = {behavior: null, colourBy: 'value', received: [], last: null};

    $('values-behavior').addEventListener('change', () => this.show($('values-behavior').value || null));
    for (const button of document.querySelectorAll('[data-colour-by]')) {
      button.addEventListener('click', () => this.setColourBy(button.dataset.colourBy));
    }
    $('curves-toggle').addEventListener('change', () => { $('curves').hidden = !$('curves-toggle').checked; });
    $('curves-log-x').addEventListener('change', () => this.drawCurves(true));
  }

  /** Asks for `name`'s values (null: none) and clears what showed before. */
  show(name) {
    this.record.behavior = name;
    $('values-behavior').value = name ?? '';
    this.send({type: 'values', behavior: name});
    this.record.last = null;
    this.view.clear();
    this.showHud();
    this.redraw();
  }

  setColourBy(colourBy) {
    this.record.colourBy = colourBy;
    for (const button of document.querySelectorAll('[data-colour-by]')) {
      button.classList.toggle('active', button.dataset.colourBy === colourBy);
    }
    if (this.record.last !== null) this.draw(this.record.last);
  }

  /** A new connection: a new world that streams nothing yet. */
  reset() {
    this.record.behavior = null;
    this.record.last = null;
    $('values-behavior').value = '';
    this.view.clear();
    this.showHud();
  }

  /**
   * The scene: the behaviours with values to show (those with a trained table) and their
   * training curves. `newWorld`: the mode changed, so the values shown are of a world
   * that is gone; they are asked for again (the new world's arrive at once).
   */
  setScene(scene, newWorld) {
    const behaviours = Array.isArray(scene.behaviors) ? scene.behaviors : [];
    this.behaviours = behaviours;
    const trained = behaviours.filter((b) => Number.isInteger(b.vertices) && b.vertices > 0).map((b) => String(b.name));
    const select = $('values-behavior');
    if ([...select.options].slice(1).map((o) => o.value).join() !== trained.join()) {
      select.replaceChildren(new Option('none', ''), ...trained.map((name) => new Option(name, name)));
    }
    select.disabled = trained.length === 0;
    select.title = trained.length === 0 ? 'no policy bundle: no learned values to show (mgrl train makes one)' : '';
    if (this.record.behavior !== null && !trained.includes(this.record.behavior)) {
      this.show(null);
    } else {
      select.value = this.record.behavior ?? '';
      if (newWorld && this.record.behavior !== null) this.show(this.record.behavior);
    }
    this.drawCurves(false);
  }

  drawCurves(force) {
    const logX = $('curves-log-x').checked;
    const key = JSON.stringify(this.behaviours.map((b) => [b.name, b.learner, b.curve?.length ?? 0, b.curve?.at?.(-1)])) + logX;
    if (!force && key === this.curvesKey) return;
    this.curvesKey = key;
    drawCurves($('curves-chart'), this.behaviours, {logX});
  }

  /** A `values` message. */
  onValues(message) {
    const problem = problemOf(message);
    if (problem !== null) {
      console.warn(`mgrl: ignored a values message: ${problem}`);
      return;
    }
    const received = this.record.received;   // every one, shown or not
    if (received.length >= kKeptMessages) received.splice(0, kKeptMessages / 2);
    received.push({behavior: message.behavior, time: message.time, points: message.points.length, at: performance.now()});
    // One of the behaviour shown before the select changed may still be on its way.
    if (message.behavior !== this.record.behavior) return;
    this.record.last = message;
    this.draw(message);
  }

  draw(message) {
    this.view.update(message, this.record.colourBy);
    this.showHud();
    this.redraw();
  }

  showHud() {
    const m = this.record.last;
    $('teach-hud').hidden = this.record.behavior === null;
    if (this.record.behavior === null) return;
    if (m === null) {
      $('teach-title').textContent = `values of ${this.record.behavior}: waiting for the server…`;
      for (const id of ['legend-min', 'legend-max', 'legend-caption', 'teach-state']) $(id).textContent = '';
      $('legend-bar').style.background = 'none';
      return;
    }
    const b = this.behaviours.find((x) => x.name === m.behavior);
    const floor = Math.abs(m.height) < 0.05;
    $('teach-title').textContent = `values of ${m.behavior}${b?.learner ? ` (${b.learner})` : ''}: ` +
      (floor ? `${m.points.length} vertices on the floor` :
               `${m.points.length} of ${b?.vertices ?? '?'} vertices, the layer at ${m.height.toFixed(2)} m`);
    const range = `V from ${formatValue(m.v_min)} to ${formatValue(m.v_max)}`;
    const marks = `ring: greedy = chosen (${this.view.chosenMarks} vertices); pink: the chosen action's root path`;
    if (this.record.colourBy === 'greedy') {
      $('legend-min').textContent = '0';
      $('legend-max').textContent = String(Math.max(0, m.actions - 1));
      $('legend-bar').style.background = actionGradient(m.actions);
      $('legend-caption').textContent = `colour: the greedy action's index (of ${m.actions}); ${range}; ${marks}`;
    } else {
      $('legend-min').textContent = formatValue(m.v_min);
      $('legend-max').textContent = formatValue(m.v_max);
      $('legend-bar').style.background = viridisGradient();
      $('legend-caption').textContent = `colour: V = max over actions of Q; ${marks}`;
    }
    // A scenario of stances: which one avatar 0 holds, and whether the shown
    // behaviour (one stance's) played at that decision.
    const stanceText = (v) => {
      if (v.stance === null || v.stance === undefined) return '';
      if (v.behavior_stance === null || v.behavior_stance === undefined) return `, holding stance ${v.stance}`;
      return v.stance === v.behavior_stance
        ? `, holding stance ${v.stance}: this behaviour's, it plays`
        : `, holding stance ${v.stance}: this behaviour's is ${v.behavior_stance}, it waits`;
    };
    // A grid that holds the target's motion shows the layers of the target's motion.
    const motion = m.speed > 0
      ? `, values for a target at ${Number(m.speed).toFixed(1)} m/s turning ${Number(m.turn_deg_s).toFixed(0)} deg/s`
      : '';
    $('teach-state').textContent = `state ${m.state}, chosen action ${m.chosen} of ${m.actions} (counted from 0), ` +
      `target inside grid: ${m.target_inside ? 'yes' : 'no'}${motion}${stanceText(m)} (t ${Number(m.time).toFixed(1)} s)`;
  }
}
