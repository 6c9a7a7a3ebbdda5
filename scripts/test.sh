#!/usr/bin/env bash
# Sets up, builds and runs every test: the full suite in a Release build, the main job
# (scripts/demo.sh --quick) from a fresh clone of this repository's HEAD with an empty
# cache, a 30 s fuzz smoke of each libFuzzer harness (clang, build-fuzz-smoke/), then the
# full suite again under AddressSanitizer and UndefinedBehaviorSanitizer.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
jobs="$(nproc)"
start=$SECONDS
say() { echo "== [$((SECONDS - start)) s] $*" >&2; }
"$root/scripts/setup.sh" --test

say "Release build and full test suite"
"$root/scripts/build.sh" "$root/build"
(cd "$root/build" && ctest --output-on-failure -j "$jobs")

say "browser test: a real mgrl serve in headless Chromium (tests/web/)"
"$root/scripts/browser_test.sh" "$root/build"

say "README sample outputs against the program's (scripts/readme_outputs.py)"
python3 "$root/scripts/readme_outputs.py" --check --mgrl "$root/build/app/mgrl"

# The README's first command, from what is committed (a file left out of a commit fails
# here), on an empty cache, as a new user runs it; quick budgets keep it to minutes.
say "main job from a fresh clone: scripts/demo.sh --quick"
fresh="$(mktemp -d "${TMPDIR:-/tmp}/mgrl-fresh-clone.XXXXXX")"
trap 'rm -rf "$fresh"' EXIT
if git -C "$root" rev-parse --git-dir >/dev/null 2>&1; then
  git clone --quiet --no-hardlinks "$root" "$fresh/mgrl"
else
  # Not a git checkout (an unpacked archive): copy the sources, never the builds.
  mkdir "$fresh/mgrl"
  tar -C "$root" --exclude='./build*' --exclude='./node_modules' -cf - . | tar -C "$fresh/mgrl" -xf -
fi
MGRL_DATA="${MGRL_DATA:-$root/../shared/mocap}" MGRL_CACHE="$fresh/cache" "$fresh/mgrl/scripts/demo.sh" --quick \
  >"$fresh/demo.out" 2>"$fresh/demo.err" || {
  cat "$fresh/demo.err" >&2
  echo "test: the main job failed from a fresh clone (scripts/demo.sh --quick); its output is above" >&2
  exit 1
}
"$root/scripts/check_demo.sh" "$fresh/demo.out" "$fresh/demo.err" "$fresh/mgrl/build/demo"
grep -E 'demo: \[[0-9]+ s\] done' "$fresh/demo.err" >&2  # the demo's wall time
# What `scripts/demo.sh --serve` starts, from the same clone: its page and three.js.
MGRL_DATA="${MGRL_DATA:-$root/../shared/mocap}" MGRL_CACHE="$fresh/cache" \
  "$root/scripts/check_serve.sh" "$fresh/mgrl/build/app/mgrl" "$fresh/mgrl/scenarios/boxing.yaml" \
  --set behaviors.approach.learner.budget=200000 --set behaviors.hit.learner.budget=400000
rm -rf "$fresh"
trap - EXIT

# Issue 19: each reader's harness for 30 s, one per core at a time (CI: two), from the
# seeds only, so that every run does the same work: a corpus left by earlier runs is read
# whole first, which for the slow readers can outlast the 30 s. -timeout is one
# input's wall time at nice 19, generous so that a busy machine is not taken for a hang.
say "fuzz smoke: each libFuzzer harness 30 s (scripts/fuzz.sh, clang, build-fuzz-smoke/)"
rm -rf "$root/build-fuzz-smoke/corpus" "$root/build-fuzz-smoke/findings"
FUZZ_BUILD="$root/build-fuzz-smoke" FUZZ_BUILD_JOBS="$jobs" FUZZ_JOBS="$jobs" FUZZ_TIMEOUT=30 CXX=clang++ \
  MGRL_DATA="${MGRL_DATA:-$root/../shared/mocap}" "$root/scripts/fuzz.sh" 30

say "ASan/UBSan build and full test suite"
"$root/scripts/build.sh" "$root/build-asan" -DMGRL_SANITIZE=ON -DMGRL_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo
(cd "$root/build-asan" && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j "$jobs")
say "every test passed"
