// The control panel: mode, crowd size, clock, controller and behaviour weights. Built
// from the `scene` message (what the server can run) and kept in step with `scene` and
// `stats`; every change is one page message (docs/viewer-protocol.md).
import {throttled} from './protocol.js';

const $ = (id) => document.getElementById(id);
const kCrowdMin = 2, kCrowdMax = 2000;
// Which panel sections the user opened or folded (localStorage), by data-section.
const kSectionsKey = 'mgrl.panel.sections';

/** Folds the panel's sections as the user left them (else as index.html has them) and
 *  remembers every fold from now on. Without storage (disabled, private) it only folds. */
function keepSectionFolds() {
  const sections = [...document.querySelectorAll('#panel details[data-section]')];
  let saved = {};
  try {
    saved = JSON.parse(localStorage.getItem(kSectionsKey) ?? '{}') ?? {};
  } catch {
    saved = {};
  }
  for (const section of sections) {
    if (typeof saved[section.dataset.section] === 'boolean') section.open = saved[section.dataset.section];
    section.addEventListener('toggle', () => {
      const state = Object.fromEntries(sections.map((s) => [s.dataset.section, s.open]));
      try {
        localStorage.setItem(kSectionsKey, JSON.stringify(state));
      } catch {
        // not remembered: the folds still work
      }
    });
  }
}

export class Panel {
  /** @param send  sends one page message (an object) */
  constructor(send) {
    this.send = send;
    this.scene = null;
    this.paused = false;
    this.weightInputs = new Map();   // behaviour name -> <input type=range>
    this.sendWeights = throttled(send, 100);
    this.sendSpeed = throttled(send, 100);
    keepSectionFolds();

    for (const button of document.querySelectorAll('[data-mode]')) {
      button.addEventListener('click', () => this.sendMode(button.dataset.mode));
    }

    const slider = $('crowd-slider'), count = $('crowd-count');
    slider.addEventListener('input', () => { count.value = slider.value; });
    slider.addEventListener('change', () => this.crowdSizeChanged());
    count.addEventListener('change', () => {
      const n = Math.round(Number(count.value));
      count.value = slider.value = Number.isFinite(n) ? Math.min(kCrowdMax, Math.max(kCrowdMin, n)) : 30;
      this.crowdSizeChanged();
    });

    $('pause').addEventListener('click', () => {
      this.send({type: 'pause', paused: !this.paused});
      this.showPaused(!this.paused);   // the next stats confirm it
    });
    $('step').addEventListener('click', () => this.send({type: 'step'}));
    $('speed').addEventListener('input', () => {
      const speed = Number($('speed').value);
      $('speed-value').textContent = `${speed.toFixed(1)}×`;
      this.sendSpeed({type: 'speed', speed});
    });

    $('controller').addEventListener('change', () => this.sendController());
    $('horizon').addEventListener('change', () => {
      const h = Math.round(Number($('horizon').value));
      $('horizon').value = Number.isFinite(h) ? Math.min(5, Math.max(1, h)) : 3;
      this.sendController();
    });
  }

  crowdAvatars() { return Number($('crowd-slider').value); }

  sendMode(mode) {
    const message = {type: 'mode', mode};
    if (mode === 'crowd') message.avatars = this.crowdAvatars();
    this.send(message);
  }

  crowdSizeChanged() {
    if (this.scene?.mode === 'crowd') this.sendMode('crowd');
  }

  sendController() {
    const controller = $('controller').value;
    const message = {type: 'controller', controller};
    if (controller === 'online_search') message.horizon = Number($('horizon').value);
    this.send(message);
    this.showHorizon();
  }

  showHorizon() {
    $('horizon-row').hidden = $('controller').value !== 'online_search';
  }

  showPaused(paused) {
    this.paused = paused;
    $('pause').textContent = paused ? 'resume' : 'pause';
    $('pause').classList.toggle('active', paused);
    $('step').disabled = !paused;
  }

  setScene(scene) {
    this.scene = scene;
    for (const button of document.querySelectorAll('[data-mode]')) {
      button.classList.toggle('active', button.dataset.mode === scene.mode);
    }
    if (scene.mode === 'crowd' && document.activeElement !== $('crowd-slider')) {
      $('crowd-slider').value = $('crowd-count').value = scene.avatars;
    }
    $('height-row').hidden = scene.mode !== 'target';

    const select = $('controller');
    const controllers = Array.isArray(scene.controllers) ? scene.controllers : [];
    if ([...select.options].map((o) => o.value).join() !== controllers.join()) {
      select.replaceChildren(...controllers.map((name) => new Option(name, name)));
    }
    if (typeof scene.controller === 'string') select.value = scene.controller;
    if (Number.isInteger(scene.horizon) && document.activeElement !== $('horizon')) $('horizon').value = scene.horizon;
    this.showHorizon();

    this.setBehaviours(Array.isArray(scene.behaviors) ? scene.behaviors : []);
  }

  // One slider per behaviour; rebuilt only when the names change, so a slider being
  // dragged is not replaced by the scene that its own message caused.
  setBehaviours(behaviours) {
    const names = behaviours.map((b) => b.name);
    if ([...this.weightInputs.keys()].join() !== names.join()) {
      this.weightInputs.clear();
      $('weights').replaceChildren(...behaviours.map((b) => this.weightRow(b)));
    }
    for (const b of behaviours) {
      const input = this.weightInputs.get(b.name);
      if (input !== document.activeElement && Number.isFinite(b.weight)) {
        input.value = b.weight;
        input.nextElementSibling.textContent = b.weight.toFixed(1);
      }
    }
  }

  weightRow(behaviour) {
    const row = document.createElement('label');
    row.className = 'row weight';
    row.title = `${behaviour.name} (active: ${behaviour.activation ?? '?'})`;
    const name = document.createElement('span');
    name.textContent = behaviour.name;
    const input = Object.assign(document.createElement('input'),
                                {type: 'range', min: 0, max: 10, step: 0.1, value: behaviour.weight});
    input.dataset.behaviour = behaviour.name;
    const value = document.createElement('output');
    value.textContent = Number(behaviour.weight).toFixed(1);
    input.addEventListener('input', () => {
      value.textContent = Number(input.value).toFixed(1);
      const weights = {};
      for (const [n, i] of this.weightInputs) weights[n] = Number(i.value);
      this.sendWeights({type: 'weights', weights});
    });
    this.weightInputs.set(behaviour.name, input);
    row.append(name, input, value);
    return row;
  }

  setStats(stats) {
    if (typeof stats.paused === 'boolean' && stats.paused !== this.paused) this.showPaused(stats.paused);
    if (Number.isFinite(stats.speed) && document.activeElement !== $('speed')) {
      $('speed').value = stats.speed;
      $('speed-value').textContent = `${stats.speed.toFixed(1)}×`;
    }
  }
}
