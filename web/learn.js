// The learn panel and live retraining (docs/viewer-protocol.md).
//
// Learn: the server runs the paper's Q-learning (sec. 4.2) on one behaviour's problem with
// a table of this page's own, a step at a time, and sends each step (`learn_step`). This
// module draws the step as the paper's Fig. 4 does, seen from above in the avatar's frame:
// the grid vertices, the target e before the action and e' after it, the action's root
// path, the cell of e whose corners are updated, and where each corner moves (e'_v); and
// it lists each corner's numbers: r, gamma^t, max Q(e'_v, .), the backup, Q before and
// after, with alpha.
//
// Retrain: change one of a behaviour's reward or grid parameters; the server retrains it
// with value iteration and the avatar switches to the new policy; the old and new success
// rates (the same trials) are shown.
import {formatValue} from './teach.js';

const $ = (id) => document.getElementById(id);
const kSvg = 'http://www.w3.org/2000/svg';
const kRates = [0, 2, 10, 50, 250, 1000];   // steps per second: pause, then faster

function svg(name, attributes = {}, parent = null) {
  const element = document.createElementNS(kSvg, name);
  for (const [key, value] of Object.entries(attributes)) element.setAttribute(key, String(value));
  if (parent) parent.append(element);
  return element;
}

const isPoint = (p) => Array.isArray(p) && p.length === 3 && p.every(Number.isFinite);

// A `learn_step` message as the page needs it, or the reason it is not.
function stepProblem(m) {
  if (!Number.isInteger(m.update) || !Number.isFinite(m.alpha)) return 'no "update"/"alpha"';
  if (!isPoint(m.target) || !isPoint(m.target_next)) return '"target"/"target_next" must be [x, y, z]';
  if (!Array.isArray(m.vertices) || !m.vertices.every((v) => isPoint(v?.position) && isPoint(v?.next) &&
      ['reward', 'discount', 'future', 'backup', 'before', 'after', 'weight'].every((k) => Number.isFinite(v[k])))) {
    return '"vertices" must be objects with position, next and the update\'s numbers';
  }
  if (!Array.isArray(m.path) || !m.path.every(isPoint)) return '"path" must be [x, y, z] points';
  return null;
}

export class Learn {
  /** @param send  sends one page message (an object) */
  constructor(send) {
    this.send = send;
    this.scene = null;
    this.rateIndex = 0;
    // What the page shows (window.mgrl.state.learn, for tests): the lesson, every step
    // message received (update numbers), the last one, and the retraining messages.
    this.record = {lesson: null, steps: [], last: null, retrain: []};

    $('learn-start').addEventListener('click', () => this.start());
    $('learn-step').addEventListener('click', () => this.send({type: 'learn', command: 'step'}));
    $('learn-step10').addEventListener('click', () => this.send({type: 'learn', command: 'step', steps: 10}));
    $('learn-run').addEventListener('click', () => this.setRate(this.rateIndex === 0 ? 1 : 0));
    $('learn-faster').addEventListener('click', () => this.setRate(Math.min(kRates.length - 1, Math.max(1, this.rateIndex + 1))));
    $('learn-stop').addEventListener('click', () => this.send({type: 'learn', command: 'stop'}));
    $('retrain-behavior').addEventListener('change', () => this.showParameters());
    $('retrain-parameter').addEventListener('change', () => this.showParameterValue());
    $('retrain-go').addEventListener('click', () => this.retrain());
    $('retrain-revert').addEventListener('click', () =>
      this.send({type: 'retrain', behavior: $('retrain-behavior').value, set: {}}));
    this.showControls();
  }

  start() {
    const seed = Math.max(0, Math.round(Number($('learn-seed').value)) || 0);
    const budget = Math.max(1, Math.round(Number($('learn-budget').value)) || 1);
    this.send({type: 'learn', command: 'start', behavior: $('learn-behavior').value, seed, budget});
  }

  setRate(index) {
    this.rateIndex = index;
    this.send({type: 'learn', command: 'run', rate: kRates[index]});
    this.showControls();
  }

  /** A new connection: no lesson, no retraining. */
  reset() {
    this.record.lesson = null;
    this.record.last = null;
    this.rateIndex = 0;
    this.showControls();
    this.draw();
  }

  setScene(scene) {
    this.scene = scene;
    const names = (Array.isArray(scene.behaviors) ? scene.behaviors : []).map((b) => String(b.name));
    for (const id of ['learn-behavior', 'retrain-behavior']) {
      const select = $(id);
      if ([...select.options].map((o) => o.value).join() !== names.join()) {
        const keep = select.value;
        select.replaceChildren(...names.map((name) => new Option(name, name)));
        if (names.includes(keep)) select.value = keep;
      }
    }
    const trained = scene.behaviors?.some((b) => Number.isInteger(b.vertices));
    $('retrain').disabled = !trained;
    $('retrain').title = trained ? '' : 'no policy bundle to retrain from (mgrl train makes one)';
    this.showParameters();
  }

  behaviour(name) {
    return this.scene?.behaviors?.find((b) => b.name === name) ?? null;
  }

  showParameters() {
    const b = this.behaviour($('retrain-behavior').value);
    const keys = Object.keys(b?.parameters ?? {}).filter((k) => !k.endsWith('.seed'));
    const select = $('retrain-parameter');
    if ([...select.options].map((o) => o.value).join() !== keys.join()) {
      const keep = select.value;
      select.replaceChildren(...keys.map((k) => new Option(k, k)));
      if (keys.includes(keep)) select.value = keep;
    }
    this.showParameterValue();
    $('retrain-revert').disabled = !b?.retrained;
  }

  showParameterValue() {
    const b = this.behaviour($('retrain-behavior').value);
    const value = b?.parameters?.[$('retrain-parameter').value];
    if (Number.isFinite(value)) $('retrain-value').value = String(value);
  }

  retrain() {
    const key = $('retrain-parameter').value;
    const value = Number($('retrain-value').value);
    if (!key || !Number.isFinite(value)) return;
    const b = this.behaviour($('retrain-behavior').value);
    // The parameters changed before stay changed: retraining starts from the scenario's.
    const set = {...(b?.retrained ?? {}), [key]: value};
    this.send({type: 'retrain', behavior: $('retrain-behavior').value, set});
  }

  onRetrain(m) {
    this.record.retrain.push(m);
    const line = $('retrain-status');
    const rate = (s) => (Number.isFinite(s?.success_rate) ? `${(100 * s.success_rate).toFixed(1)} %` : '–');
    const time = (s) => (Number.isFinite(s?.mean_time_to_hit_s) ? `${s.mean_time_to_hit_s.toFixed(2)} s` : 'no hit');
    if (m.status === 'started') {
      line.textContent = `retraining ${m.behavior} with ${JSON.stringify(m.set)}…`;
    } else if (m.status === 'done') {
      line.textContent = `${m.behavior} retrained (value iteration, ${m.vertices} vertices, ` +
        `${Number(m.seconds).toFixed(1)} s). Success on ${m.trials} trials: ${rate(m.before)} → ${rate(m.after)}; ` +
        `time to hit ${time(m.before)} → ${time(m.after)}`;
    } else if (m.status === 'reverted') {
      line.textContent = `${m.behavior}: back to the policy bundle's table`;
    } else if (m.status === 'failed') {
      line.textContent = `retraining ${m.behavior} failed: ${m.message}`;
    }
    line.dataset.status = String(m.status);
  }

  onLesson(m) {
    if (m.behavior === null) {
      this.record.lesson = null;
      this.record.last = null;
      this.rateIndex = 0;
    } else {
      if (!Array.isArray(m.vertices) || !m.vertices.every(isPoint)) {
        console.warn('mgrl: ignored a lesson message without a "vertices" list');
        return;
      }
      this.record.lesson = m;
      this.record.last = null;
      this.record.steps = [];
      this.rateIndex = 0;
    }
    this.showControls();
    this.draw();
  }

  onStep(m) {
    const problem = stepProblem(m);
    if (problem !== null) {
      console.warn(`mgrl: ignored a learn_step message: ${problem}`);
      return;
    }
    if (this.record.steps.length >= 2000) this.record.steps.splice(0, 1000);
    this.record.steps.push(m);
    this.record.last = m;
    if (m.done) this.rateIndex = 0;
    this.showControls();
    this.draw();
  }

  showControls() {
    const lesson = this.record.lesson !== null;
    const done = this.record.last?.done === true;
    for (const id of ['learn-step', 'learn-step10', 'learn-run', 'learn-faster', 'learn-stop']) $(id).disabled = !lesson;
    for (const id of ['learn-step', 'learn-step10', 'learn-run', 'learn-faster']) if (done) $(id).disabled = true;
    $('learn-run').textContent = this.rateIndex === 0 ? 'run' : 'pause';
    $('learn-rate').textContent = this.rateIndex === 0 ? '' : `${kRates[this.rateIndex]} steps/s`;
    $('lesson').hidden = !lesson;
  }

  // The paper's Fig. 4 from above: x to the avatar's side, z ahead (up on the page).
  draw() {
    const lesson = this.record.lesson;
    const chart = $('lesson-chart');
    chart.replaceChildren();
    if (lesson === null) return;
    const m = this.record.last;
    const points = lesson.vertices.map((p) => [p[0], p[2]]);
    let reach = 0.5;
    for (const [x, z] of points) reach = Math.max(reach, Math.abs(x), Math.abs(z));
    if (m) for (const p of [m.target, m.target_next]) reach = Math.max(reach, Math.abs(p[0]), Math.abs(p[2]));
    reach *= 1.08;
    const size = 300;
    chart.setAttribute('viewBox', `0 0 ${size} ${size}`);
    const X = (x) => size / 2 - (x / reach) * (size / 2);   // the avatar's left on the page's left
    const Y = (z) => size / 2 - (z / reach) * (size / 2);
    // Grid vertices (of a 3-D grid, every layer: they overlap from above).
    const seen = new Set();
    for (const [x, z] of points) {
      const key = `${x.toFixed(3)},${z.toFixed(3)}`;
      if (seen.has(key)) continue;
      seen.add(key);
      svg('circle', {cx: X(x), cy: Y(z), r: 1.6, class: 'lesson-vertex'}, chart);
    }
    // The avatar at the origin, facing +z.
    svg('path', {d: `M ${X(0)} ${Y(0) - 9} L ${X(0) - 6} ${Y(0) + 6} L ${X(0) + 6} ${Y(0) + 6} Z`, class: 'lesson-avatar'}, chart);
    if (m) {
      if (m.path.length > 0) {
        const d = [[0, 0, 0], ...m.path].map((p, k) => `${k ? 'L' : 'M'} ${X(p[0]).toFixed(1)} ${Y(p[2]).toFixed(1)}`).join(' ');
        svg('path', {d, class: 'lesson-path'}, chart);
      }
      for (const v of m.vertices) {
        // v moved along by the action: the point whose value the backup looks up.
        svg('line', {x1: X(v.position[0]), y1: Y(v.position[2]), x2: X(v.next[0]), y2: Y(v.next[2]),
                     class: v.next_inside ? 'lesson-move' : 'lesson-move outside'}, chart);
        svg('circle', {cx: X(v.next[0]), cy: Y(v.next[2]), r: 2.5, class: 'lesson-next'}, chart);
      }
      for (const v of m.vertices) {
        const changed = v.after !== v.before;
        svg('circle', {cx: X(v.position[0]), cy: Y(v.position[2]), r: 5, class: changed ? 'lesson-corner changed' : 'lesson-corner'}, chart);
      }
      svg('circle', {cx: X(m.target[0]), cy: Y(m.target[2]), r: 6, class: 'lesson-e'}, chart);
      svg('circle', {cx: X(m.target_next[0]), cy: Y(m.target_next[2]), r: 6, class: 'lesson-e-next'}, chart);
      const label = (p, text) => {
        const t = svg('text', {x: X(p[0]) + 8, y: Y(p[2]) - 6, class: 'lesson-label'}, chart);
        t.textContent = text;
      };
      label(m.target, 'e');
      label(m.target_next, "e'");
    }
    this.drawTable();
  }

  drawTable() {
    const lesson = this.record.lesson;
    const m = this.record.last;
    const head = $('lesson-head');
    if (m === null) {
      head.textContent = `Q-learning on ${lesson.behavior}: ${lesson.vertices.length} vertices x ${lesson.actions} actions, ` +
        `all zeros. Step to take the first random action.`;
      $('lesson-table').replaceChildren();
      return;
    }
    head.textContent = `update ${m.update} of ${m.budget}` + (m.taken > 1 ? ` (${m.taken} taken since the last shown)` : '') +
      `: state ${m.state}, action ${m.action_index} of ${m.actions} (${m.frames} frames) to state ${m.next_state}; ` +
      `alpha ${m.alpha.toFixed(4)}; ${m.touched} of ${m.pairs} Q entries updated so far, ${m.restarts} restarts` +
      (m.restarted ? '; e\' left the grid: restart' : '');
    const rows = [['vertex', 'w', 'r', 'γ^t', "max Q(e'_v)", 'backup', 'Q before', 'Q after']];
    for (const v of m.vertices) {
      rows.push([v.vertex, v.weight.toFixed(2), formatValue(v.reward), v.discount.toFixed(3),
                 v.next_inside ? formatValue(v.future) : 'off grid', formatValue(v.backup), formatValue(v.before),
                 formatValue(v.after)]);
    }
    $('lesson-table').replaceChildren(...rows.map((cells, k) => {
      const tr = document.createElement('tr');
      for (const cell of cells) {
        const td = document.createElement(k === 0 ? 'th' : 'td');
        td.textContent = String(cell);
        tr.append(td);
      }
      return tr;
    }));
  }
}
