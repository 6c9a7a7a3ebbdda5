// The HUD's hit count (web/hud.js) against the messages a page receives: stats twice a
// second, each counting every hit up to its time, and a hit message at once.
// `node --test tests/web/hud_test.mjs` (no browser, no server).
import {test} from 'node:test';
import assert from 'node:assert/strict';

// The HUD touches a few elements when a scene arrives; a stand-in for each.
globalThis.document = {getElementById: () => ({hidden: false, textContent: ''})};
const {Hud, opponentText, successText} = await import('../../web/hud.js');

const hit = (time) => ({time, speed: 4, hand: 'right', limb: 'hand', attacker: 0, target: -1});

test('a hit message counts at once, before the stats that include it', () => {
  const hud = new Hud();
  assert.equal(hud.hitCount(), null);
  hud.addHit(hit(0.9));
  assert.equal(hud.hitCount(), 1);                 // no stats yet
  hud.setStats({hits: 1, time: 1.0});
  assert.equal(hud.hitCount(), 1);                 // the stats include it: not counted twice
  hud.addHit(hit(1.2));
  hud.addHit(hit(1.4));
  assert.equal(hud.hitCount(), 3);                 // stats still at t 1.0
  hud.setStats({hits: 3, time: 1.5});
  assert.equal(hud.hitCount(), 3);
});

test('a hit message the stats already count is not counted again', () => {
  // The server sends a tick's stats before that tick's hit messages, and the stats count them.
  const hud = new Hud();
  hud.setStats({hits: 2, time: 2.0});
  hud.addHit(hit(2.0));
  hud.addHit(hit(1.97));
  assert.equal(hud.hitCount(), 2);
});

test('a new world forgets the old world\'s hits and stats', () => {
  const hud = new Hud();
  hud.setStats({hits: 4, time: 8.0});
  hud.addHit(hit(8.2));
  assert.equal(hud.hitLines.length, 1);
  hud.setScene({mode: 'target'}, false);           // the same world: a scene update
  assert.equal(hud.hitCount(), 5);
  hud.setScene({mode: 'sparring'}, true);
  assert.equal(hud.hitCount(), null);
  assert.equal(hud.hitLines.length, 0);
  hud.addHit(hit(0.4));                            // the new world's clock starts at 0
  assert.equal(hud.hitCount(), 1);
});

test('the note shows the scene\'s note and, while the server slows this world, why', () => {
  const hud = new Hud();
  hud.setScene({mode: 'crowd', note: 'The online search\'s horizon was lowered.'}, true);
  assert.equal(hud.noteText(), 'The online search\'s horizon was lowered.');
  hud.setStats({hits: 0, time: 1, slowed: 'The server shares its time among 16 pages.'});
  assert.equal(hud.noteText(), 'The online search\'s horizon was lowered. The server shares its time among 16 pages.');
  hud.setStats({hits: 0, time: 2, slowed: null});
  assert.equal(hud.noteText(), 'The online search\'s horizon was lowered.');
  hud.setScene({mode: 'target', note: ''}, true);
  assert.equal(hud.noteText(), '');
});

test('the note says who the blue corner is when the server plays a scripted opponent', () => {
  const hud = new Hud();
  hud.setScene({note: '', opponent: null, controller: 'policy'});
  assert.equal(hud.noteText(), '');
  hud.setScene({note: '', opponent: 'pursue', controller: 'policy'});
  assert.match(hud.noteText(), /^Blue: the scripted opponent .*walking in.*; red: the trained avatar\.$/);
  // Without a bundle the page runs the search: red is not a trained avatar then.
  hud.setScene({note: 'No policy bundle.', opponent: 'pursue', controller: 'online_search'});
  assert.match(hud.noteText(), /^No policy bundle\. Blue: .*red: the page's controller \(online_search\)\.$/);
  hud.setScene({note: '', opponent: 'stand', controller: 'random'});
  assert.match(hud.noteText(), /standing.*red: the page's controller \(random\)/);
});

test('the blue corner is named when the server plays it: a scripted opponent or a partner bundle', () => {
  assert.match(opponentText('pursue', 'policy'), /^Blue: the scripted opponent .*walking in.*; red: the trained avatar\.$/);
  assert.match(opponentText('partner_policy', 'policy'),
               /^Blue: the partner's own policy bundle \(serve --partner-policy\); red: the trained avatar\.$/);
  assert.match(opponentText('partner_policy', 'random'), /red: the page's controller \(random\)\.$/);
  assert.equal(opponentText(null, 'policy'), '');
});

test('behaviours that declare the same success criterion share one entry in the HUD', () => {
  const strike = 'an effective strike of the fists within 0.15 m';
  // boxing_spar.yaml's three stances declare the same criterion.
  assert.equal(successText([{name: 'spar_square', success: strike}, {name: 'spar', success: strike},
                            {name: 'spar_turned', success: strike}]),
               `spar_square, spar, spar_turned: ${strike}`);
  // Different criteria stay apart, in the behaviours' order; undeclared ones are left out.
  assert.equal(successText([{name: 'approach', success: null}, {name: 'hit', success: strike},
                            {name: 'keep', success: 'within 0.3 m'}]),
               `hit: ${strike}; keep: within 0.3 m`);
  assert.equal(successText([{name: 'approach', success: null}]), '–');
  assert.equal(successText(undefined), '–');
});
