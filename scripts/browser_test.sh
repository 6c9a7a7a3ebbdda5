#!/usr/bin/env bash
# The viewer's browser test (tests/web/browser_test.mjs): a real `mgrl serve` from
# BUILD_DIR driven by headless Chromium, with a boxing policy trained by value iteration
# (about a second) into BUILD_DIR/browser-test/. Screenshots go to MGRL_SCREENSHOT_DIR
# (default BUILD_DIR/browser-test/img; docs/img holds the README's).
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
cd "$root"
MGRL_BINARY="$mgrl" MGRL_SERVE_ARGS="--policy $work/policy --cache $work/cache --data $data" \
  MGRL_SCREENSHOT_DIR="${MGRL_SCREENSHOT_DIR:-$work/img}" node "$root/tests/web/browser_test.mjs"
