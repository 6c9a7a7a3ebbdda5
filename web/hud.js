// The heads-up display: what the server says (scene, stats, hits, errors) and how fast
// frames reach this page. Redrawn a few times a second, not per frame.

const $ = (id) => document.getElementById(id);
const kHitLines = 5;

const fixed = (v, digits) => (Number.isFinite(v) ? v.toFixed(digits) : '–');

/** What eval counts as success, behaviour by behaviour ("hit: an effective strike ..."); behaviours
 * that declare the same criterion (a scenario's stances) share one entry ("a, b: ..."). */
export const successText = (behaviors) => {
  const byText = new Map();
  for (const b of behaviors ?? []) {
    if (typeof b.success !== 'string') continue;
    if (!byText.has(b.success)) byText.set(b.success, []);
    byText.get(b.success).push(b.name);
  }
  return byText.size ? [...byText].map(([text, names]) => `${names.join(', ')}: ${text}`).join('; ') : '–';
};

/** Who the blue corner is when the server plays it (scene.opponent), as a sentence; red
 * plays the page's controller (the trained policy, or the search or random actions). */
export function opponentText(opponent, controller) {
  const red = controller === 'policy' ? 'the trained avatar' : `the page's controller (${controller ?? '?'})`;
  if (opponent === 'partner_policy') return `Blue: the partner's own policy bundle (serve --partner-policy); red: ${red}.`;
  if (opponent !== 'pursue' && opponent !== 'stand') return '';
  const blue = opponent === 'pursue' ? "walking in with the capture's steps and throwing its punches"
                                     : 'standing, turning to face the avatar and punching';
  return `Blue: the scripted opponent the behaviours were trained against, ${blue}; red: ${red}.`;
}

export class Hud {
  constructor() {
    this.scene = null;
    this.stats = null;
    this.framesPerSecond = 0;
    this.frameTime = null;
    this.hitLines = [];
    // Hit messages newer than this.stats: stats come twice a second and count every hit up
    // to their time, a hit message comes at once; the HUD adds the two so that the count
    // never trails the hit lines it shows.
    this.hitsAhead = 0;
    this.blockedAhead = 0;  // the same for blocked strikes
  }

  setConnection(text) { $('connection').textContent = text; }

  /** `newWorld`: a mode change or a new crowd size; the old world's hits and stats go. */
  setScene(scene, newWorld = false) {
    this.scene = scene;
    if (newWorld) {
      this.stats = null;
      this.hitLines = [];
      this.hitsAhead = 0;
      this.blockedAhead = 0;
    }
    this.showNote();
  }

  setStats(stats) {
    this.stats = stats;
    this.hitsAhead = 0;   // it counts every hit sent before it
    this.blockedAhead = 0;
    this.showNote();
  }

  /** The scene's note (no policy bundle, a lowered horizon) and, while the server slows this
   * page's world to share its time with the others, the stats' reason. */
  noteText() {
    return [this.scene?.note, opponentText(this.scene?.opponent, this.scene?.controller), this.stats?.slowed]
        .filter((t) => typeof t === 'string' && t.length > 0).join(' ');
  }

  showNote() {
    const note = $('note');
    const text = this.noteText();
    note.hidden = text.length === 0;
    note.textContent = text;
  }

  setError(message) {
    const error = $('error');
    error.hidden = false;
    error.textContent = `last error: ${message}`;
  }

  /** Hits so far in this world: the last stats' count and the hit messages newer than them (null before either). */
  hitCount() {
    if (Number.isFinite(this.stats?.hits)) return this.stats.hits + this.hitsAhead;
    return this.hitsAhead > 0 ? this.hitsAhead : null;
  }

  /** Blocked strikes so far in this world, as hitCount() counts hits. */
  blockedCount() {
    if (Number.isFinite(this.stats?.blocked)) return this.stats.blocked + this.blockedAhead;
    return this.blockedAhead > 0 ? this.blockedAhead : null;
  }

  /** A `hit` message: one line "hit 4.1 m/s" (or "blocked 4.1 m/s": it met a guarding
   * forearm) with who hit what. */
  addHit(hit) {
    // A hit at a time the last stats had not reached is not in their count yet.
    if (this.stats === null || !(hit.time <= this.stats.time)) {
      if (hit.blocked) this.blockedAhead += 1;
      else this.hitsAhead += 1;
    }
    const part = String(hit.part ?? '').replace('_', ' ');
    const who = hit.target === -1 ? 'target' : `avatar ${hit.target} ${part}`;
    const line = `${hit.blocked ? 'blocked' : 'hit'} ${fixed(hit.speed, 1)} m/s — ${hit.hand ?? '?'} ${hit.limb === 'foot' ? 'foot' : 'hand'} of ${hit.attacker} ${hit.blocked ? 'by' : 'on'} ${who} (t ${fixed(hit.time, 1)} s)`;
    this.hitLines.unshift({line, at: performance.now()});
    this.hitLines.length = Math.min(this.hitLines.length, kHitLines);
  }

  render(framesPerSecond, framesDrawn, frameTime, frameAvatars, draw) {
    const s = this.stats ?? {};
    const c = this.scene ?? {};
    const rows = [
      ['mode', c.mode ?? '–'],
      ['avatars', frameAvatars ?? c.avatars ?? '–'],
      ['controller', c.controller ? (c.controller === 'online_search' ? `${c.controller} (h ${c.horizon})` : c.controller) : '–'],
      ['simulated time', `${fixed(frameTime ?? s.time, 1)} s${s.paused ? ' (paused)' : ''}`],
      ['speed', `${fixed(s.speed, 1)}×`],
      ['frames received', `${fixed(framesPerSecond, 1)} /s`],
      ['frames drawn', `${fixed(framesDrawn, 1)} /s${draw?.software ? ' (software)' : ''}`],
      ['page draw', `${fixed(draw?.cycleMs, 1)} ms`],
      ['decision', `${fixed(s.decision_us, 2)} µs`],
      ['server', `${fixed(s.server_ms_per_frame, 2)} ms/frame`],
      ['frames dropped', s.frames_dropped ?? '–'],
      ['hits', this.hitCount() ?? '–'],
      ['hits per minute', fixed(s.hits_per_minute, 1)],
      // A target has no guard: blocks are counted where fighters face each other.
      ...(c.mode === 'target' ? [] : [['blocked', this.blockedCount() ?? '–']]),
      ['success', successText(c.behaviors)],
      ['successes', s.successes === undefined ? '–' : `${s.successes} (${fixed(s.successes_per_minute, 1)} /min)`],
      ['bytes per avatar-frame', s.bytes_per_avatar_frame ?? '–'],
    ];
    const table = $('hud-table');
    if (table.rows.length !== rows.length) {
      table.replaceChildren(...rows.map(() => {
        const tr = document.createElement('tr');
        tr.append(document.createElement('th'), document.createElement('td'));
        return tr;
      }));
    }
    rows.forEach(([name, value], k) => {
      const [th, td] = table.rows[k].cells;
      th.textContent = name;
      td.textContent = String(value);
    });

    const now = performance.now();
    const list = $('hits');
    list.replaceChildren(...this.hitLines.map(({line, at}) => {
      const li = document.createElement('li');
      li.textContent = line;
      if (now - at > 1500) li.className = 'old';
      return li;
    }));
  }
}
