#!/usr/bin/env bash
# Sets up, builds and runs every test.
#   scripts/test.sh          the full suite, what CI runs (.ci/run): a Release build (ccache)
#                            and every ctest test, the browser test, the README's figures,
#                            the main job (scripts/demo.sh --quick) from a fresh clone of
#                            this repository's HEAD with an empty mgrl cache, then one clang
#                            build with AddressSanitizer, UndefinedBehaviorSanitizer and
#                            libFuzzer's coverage (build-sanitize/) for a 20 s fuzz smoke of
#                            each libFuzzer harness and every ctest test again but those labelled
#                            *outcome (what training learns; tests/CMakeLists.txt).
#   scripts/test.sh --quick  the everyday tier between commits: an incremental Release build
#                            and every ctest test not labelled slow (a few minutes with a
#                            warm build/).
# Each stage prints its wall time when it ends; the last line gives the total and the three
# slowest stages (also when a stage fails, for the stages that ran).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
quick=0
case "${1:-}" in
  --quick) quick=1 ;;
  "") ;;
  *) echo "test.sh: expected no argument or --quick, found '$1'" >&2; exit 2 ;;
esac
jobs="$(nproc)"
start=$SECONDS
say() { echo "== [$((SECONDS - start)) s] $*" >&2; }

# stage NAME COMMAND...: runs COMMAND, says how long it took and keeps it for the summary.
names=() seconds=()
stage() {
  local name="$1" began=$SECONDS
  shift
  say "$name"
  "$@"
  names+=("$name")
  seconds+=($((SECONDS - began)))
  say "$name: $((SECONDS - began)) s"
}
scratch=()  # removed when the script ends, however it ends
summary() {
  local status=$? i
  ((${#scratch[@]} == 0)) || rm -rf "${scratch[@]}"
  ((${#names[@]})) || return 0
  echo "== stage times:" >&2
  for i in "${!names[@]}"; do printf '==   %5d s  %s\n' "${seconds[$i]}" "${names[$i]}" >&2; done
  local slowest
  slowest="$(for i in "${!names[@]}"; do printf '%s\t%s\n' "${seconds[$i]}" "${names[$i]}"; done |
    sort -rn | head -3 | awk -F'\t' '{printf "%s%s (%d s)", (NR > 1 ? ", " : ""), $2, $1}')"
  local verdict="every test passed"
  ((status == 0)) || verdict="FAILED (exit $status)"
  echo "== test.sh$( ((quick)) && echo ' --quick'): $verdict in $((SECONDS - start)) s; slowest: $slowest" >&2
}
trap summary EXIT

data="${MGRL_DATA:-$root/../shared/mocap}"

# Every part the suite tests was built and registered: a missing one fails here, naming it
# and how to get it, instead of its tests silently not running.
parts_built() {
  local missing=() cache="$root/build/CMakeCache.txt" listed
  listed="$(cd "$root/build" && ctest -N)"
  compgen -G "$root/build/python/mgrl/_core*.so" >/dev/null ||
    missing+=("the Python module (build/python/mgrl/_core*.so): pybind11 (apt-get install pybind11-dev), then configure again")
  for test in python_tests python_tests_slow python_notebooks session_example; do
    grep -q ": $test\$" <<<"$listed" || missing+=("the ctest entry $test (configured without its part)")
  done
  grep -Eq '^MPI_mpi_LIBRARY:FILEPATH=/' "$cache" ||
    missing+=("MPI (mpi_value_iteration's C API): Open MPI (apt-get install libopenmpi-dev openmpi-bin), then configure again")
  command -v mpirun >/dev/null || missing+=("mpirun (apt-get install openmpi-bin)")
  [ -x /usr/bin/chromium ] || missing+=("Chromium for the browser test (apt-get install chromium)")
  command -v clang++ >/dev/null || missing+=("clang++ for the sanitizer build and the fuzzers (apt-get install clang)")
  if [ ${#missing[@]} -gt 0 ]; then
    printf 'test: expected every part the suite tests, found missing:\n' >&2
    printf '  %s\n' "${missing[@]}" >&2
    return 1
  fi
}

release_tests() {
  local selection=()
  ((quick)) && selection=(-LE slow)
  (cd "$root/build" && ctest --output-on-failure -j "$jobs" "${selection[@]}")
}

# The README's first command, from what is committed (a file left out of a commit fails
# here), on an empty mgrl cache, as a new user runs it; quick budgets keep it to minutes.
# Its build is a real build of the clone's sources; ccache serves it the objects the
# Release build above compiled from the same sources.
fresh_clone_demo() {
  fresh="$(mktemp -d "${TMPDIR:-/tmp}/mgrl-fresh-clone.XXXXXX")"  # global: the trap below reads it
  trap 'rm -rf "${fresh:-}"' EXIT  # in product_checks' subshell: removed when it ends
  if git -C "$root" rev-parse --git-dir >/dev/null 2>&1; then
    git clone --quiet --no-hardlinks "$root" "$fresh/mgrl"
  else
    # Not a git checkout (an unpacked archive): copy the sources, never the builds.
    mkdir "$fresh/mgrl"
    tar -C "$root" --exclude='./build*' --exclude='./node_modules' -cf - . | tar -C "$fresh/mgrl" -xf -
  fi
  MGRL_DATA="$data" MGRL_CACHE="$fresh/cache" "$fresh/mgrl/scripts/demo.sh" --quick \
    >"$fresh/demo.out" 2>"$fresh/demo.err" || {
    cat "$fresh/demo.err" >&2
    echo "test: the main job failed from a fresh clone (scripts/demo.sh --quick); its output is above" >&2
    exit 1
  }
  "$root/scripts/check_demo.sh" "$fresh/demo.out" "$fresh/demo.err" "$fresh/mgrl/build/demo"
  grep -E 'demo: \[[0-9]+ s\] done' "$fresh/demo.err" >&2  # the demo's wall time
  # What `scripts/demo.sh --serve` starts, from the same clone: its page and three.js.
  MGRL_DATA="$data" MGRL_CACHE="$fresh/cache" \
    "$root/scripts/check_serve.sh" "$fresh/mgrl/build/app/mgrl" "$fresh/mgrl/scenarios/boxing.yaml" \
    --set behaviors.approach.learner.budget=200000 --set behaviors.hit.learner.budget=400000
  rm -rf "$fresh"
}

# The browser test (a real mgrl serve in headless Chromium, tests/web/), the README's
# figures against the program's (scripts/readme_outputs.py) and the main job from a fresh
# clone run side by side: each leaves a core idle much of the time (a page waiting for
# frames, a single-threaded training), and none depends on another. Each one's output goes
# to a log, shown whole if it fails; each one's time is said when it ends.
product_checks() {
  local logs pids=() names=(browser readme demo) i failed=0
  logs="$(mktemp -d "${TMPDIR:-/tmp}/mgrl-checks.XXXXXX")"
  scratch+=("$logs")
  timed() {  # NAME COMMAND...: runs it, then writes its seconds to NAME.seconds
    local name="$1" began=$SECONDS
    shift
    "$@" >"$logs/$name.log" 2>&1 || { echo $((SECONDS - began)) >"$logs/$name.seconds"; return 1; }
    echo $((SECONDS - began)) >"$logs/$name.seconds"
  }
  timed browser "$root/scripts/browser_test.sh" "$root/build" & pids+=($!)
  timed readme python3 "$root/scripts/readme_outputs.py" --check --mgrl "$root/build/app/mgrl" & pids+=($!)
  timed demo fresh_clone_demo & pids+=($!)
  for i in "${!pids[@]}"; do
    if wait "${pids[$i]}"; then
      say "  ${names[$i]}: passed in $(cat "$logs/${names[$i]}.seconds") s"
    else
      failed=1
      say "  ${names[$i]}: FAILED after $(cat "$logs/${names[$i]}.seconds" 2>/dev/null || echo '?') s; its output:"
      sed "s/^/  ${names[$i]}: /" "$logs/${names[$i]}.log" >&2
    fi
  done
  grep -h -E '^(browser_test|readme_outputs|check_demo|check_serve|demo: \[)' "$logs"/*.log | tail -n 12 >&2 || true
  return $failed
}

# Each reader's harness for 20 s (at 30 s the nine harnesses took
# 2.6 minutes of the run; the longer hunt is scripts/fuzz.sh's default), one per core at
# a time (CI: two), from the
# seeds only, so that every run does the same work: a corpus left by earlier runs is read
# whole first, which for the slow readers can outlast the 20 s. -timeout is one
# input's wall time at nice 19, generous so that a busy machine is not taken for a hang.
# One sanitizer build serves the fuzz smoke and the sanitizer run of the suite: clang with
# AddressSanitizer, UndefinedBehaviorSanitizer and libFuzzer's coverage on everything, the
# harnesses, mgrl and the tests (scripts/fuzz.sh, FUZZ_WITH_TESTS=1, build-sanitize/).
sanitize="$root/build-sanitize"
sanitizer_build() {
  FUZZ_BUILD="$sanitize" FUZZ_WITH_TESTS=1 FUZZ_BUILD_JOBS="$jobs" CXX=clang++ MGRL_DATA="$data" \
    "$root/scripts/fuzz.sh" --build-only
}
fuzz_smoke() {
  rm -rf "$sanitize/corpus" "$sanitize/findings"
  FUZZ_BUILD="$sanitize" FUZZ_WITH_TESTS=1 FUZZ_BUILD_JOBS="$jobs" FUZZ_JOBS="$jobs" FUZZ_TIMEOUT=30 CXX=clang++ \
    MGRL_DATA="$data" "$root/scripts/fuzz.sh" 20
}
sanitizer_tests() {
  # Not the tests labelled unit-outcome or slow-outcome (tests/CMakeLists.txt says why).
  (cd "$sanitize" && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j "$jobs" -LE outcome)
}

if ((quick)); then
  stage "set-up" "$root/scripts/setup.sh" --test
  stage "format of the C++ lines changed since HEAD (scripts/format_check.sh)" "$root/scripts/format_check.sh"
  stage "clang-tidy on the C++ sources changed since HEAD (scripts/tidy_check.sh)" "$root/scripts/tidy_check.sh"
  stage "Release build (incremental)" "$root/scripts/build.sh" "$root/build"
  stage "every part built (Python, MPI, Chromium, clang)" parts_built
  stage "Release tests not labelled slow" release_tests
  exit 0
fi

stage "set-up" "$root/scripts/setup.sh" --test
stage "Release build" "$root/scripts/build.sh" "$root/build"
stage "every part built (Python, MPI, Chromium, clang)" parts_built
stage "Release tests (ctest)" release_tests
stage "three checks at once: browser test, README figures, main job from a fresh clone" product_checks
# Not beside the stages above: tried (2026-11-26), the build at nice 10 still slowed the
# Release tests from 184 to 354 s and the checks from 196 to 325 s, and saved nothing.
stage "sanitizer build: clang, ASan/UBSan, libFuzzer coverage (build-sanitize/)" sanitizer_build
stage "fuzz smoke: each libFuzzer harness 20 s (scripts/fuzz.sh)" fuzz_smoke
stage "ASan/UBSan tests (ctest in build-sanitize/)" sanitizer_tests
