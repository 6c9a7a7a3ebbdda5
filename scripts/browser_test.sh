#!/usr/bin/env bash
# The browser tests (tests/web/): the page's frame reader (node --test), the viewer end to
# end (browser_test.mjs: a real `mgrl serve` from BUILD_DIR driven by headless Chromium,
# with a boxing policy trained by value iteration, about a second, into
# BUILD_DIR/browser-test/), the `mgrl compare` report (report_test.mjs), and a sparring bout
# exported with --gltf-out beside --bvh-out (gltf_test.mjs: the Khronos validator, and
# three.js's GLTFLoader against its BVHLoader on the same run). Screenshots
# go to MGRL_SCREENSHOT_DIR (default BUILD_DIR/browser-test/img; docs/img holds the
# README's).
#   scripts/browser_test.sh [BUILD_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
work="$build/browser-test"
mgrl="$build/app/mgrl"
data="${MGRL_DATA:-$root/../shared/mocap}"
mkdir -p "$work"
[ -x "$mgrl" ] || { echo "browser_test: expected the mgrl binary at $mgrl; build first (scripts/build.sh)" >&2; exit 1; }
"$mgrl" train "$root/scenarios/boxing.yaml" --set behaviors.approach.learner.type=value_iteration \
  --set behaviors.hit.learner.type=value_iteration --out "$work/policy" --cache "$work/cache" --data "$data" \
  >"$work/train.out" 2>"$work/train.err" || { cat "$work/train.err" >&2; exit 1; }
# boxing.yaml's sparring and crowds play boxing_spar.yaml (its sparring_scenario),
# whose default bundle in this cache the server finds (value iteration, a few seconds).
"$mgrl" train "$root/scenarios/boxing_spar.yaml" --cache "$work/cache" --data "$data" \
  >"$work/train-spar.out" 2>"$work/train-spar.err" || { cat "$work/train-spar.err" >&2; exit 1; }
# The dodge scene's page plays a bundle of scenarios/dodge.yaml (value iteration,
# a few seconds).
"$mgrl" train "$root/scenarios/dodge.yaml" --out "$work/dodge-policy" --cache "$work/cache" --data "$data" \
  >"$work/train-dodge.out" 2>"$work/train-dodge.err" || { cat "$work/train-dodge.err" >&2; exit 1; }
cd "$root"
node --test "$root/tests/web/protocol_test.mjs" "$root/tests/web/hud_test.mjs" >"$work/protocol.out" 2>&1 || { cat "$work/protocol.out" >&2; exit 1; }
echo "browser_test: the page's frame reader and HUD count passed (tests/web/protocol_test.mjs, hud_test.mjs)" >&2
shots="${MGRL_SCREENSHOT_DIR:-$work/img}"
mkdir -p "$shots"
"$mgrl" compare "$root/scenarios/boxing.yaml" --behavior hit --learners q_learning,value_iteration --seeds 1,2 \
  --learner-set q_learning:budget=300000 --set behaviors.approach.learner.budget=200000 --trials 20 \
  --cache "$work/cache" --data "$data" --report "$work/report" >"$work/compare.out" 2>"$work/compare.err" ||
  { cat "$work/compare.err" >&2; exit 1; }
node "$root/tests/web/report_test.mjs" "$work/report" "$shots/compare-report.png"
rm -rf "$work/export"
"$mgrl" simulate "$root/scenarios/boxing.yaml" --policy "$work/policy" --cache "$work/cache" --data "$data" \
  --avatars 2 --seconds 8 --seed 3 --bvh-out "$work/export" --gltf-out "$work/export" >"$work/export.out" \
  2>"$work/export.err" || { cat "$work/export.err" >&2; exit 1; }
node "$root/tests/web/gltf_test.mjs" "$work/export" "$shots/gltf-bodies.png"
MGRL_BINARY="$mgrl" MGRL_SERVE_ARGS="--policy $work/policy --cache $work/cache --data $data" \
  MGRL_DODGE_POLICY="$work/dodge-policy" \
  MGRL_SCREENSHOT_DIR="$shots" node "$root/tests/web/browser_test.mjs"
