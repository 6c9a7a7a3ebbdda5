#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz, clang, -DMGRL_FUZZ=ON in build-fuzz/) and
# runs each for SECONDS (default 30) from its seed corpus, FUZZ_JOBS at once; exits 1 if
# any had a finding (an exception other than mgrl::Error, a sanitizer report, a crash, a
# timeout, or an allocation above the limits below), after showing what the fuzzer said.
# Findings are saved as build-fuzz/findings/<reader>/ crash-*, oom-*, timeout-*; the
# inputs the fuzzer finds go to build-fuzz/corpus/<reader>/ (the seeds are only read), so
# later runs start from them. Seeds: the project's own in tests/fuzz/corpus/<reader>/, and
# those cut from the capture (MGRL_DATA, else ../shared/mocap) by tests/fuzz/make_corpus.py
# into build-fuzz/seeds/<reader>/ first. scripts/test.sh runs it as CI's fuzz smoke.
# Usage: scripts/fuzz.sh [--build-only] [SECONDS [READER...]]
#   FUZZ_BUILD=DIR (default build-fuzz), CXX=clang++ (default), FUZZ_BUILD_JOBS=N (default 2),
#   FUZZ_JOBS=N harnesses run at once (default 1), FUZZ_TIMEOUT=S for one input (default 10),
#   FUZZ_OPT=-O1 (or another level) instead of -O2,
#   FUZZ_WITH_TESTS=1: the same folder also builds the whole test suite and mgrl with these
#   sanitizers (scripts/test.sh's one sanitizer build, whose ctest is its ASan/UBSan run).
#   --build-only: configure and build, fuzz nothing.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build_only=0
if [ "${1:-}" = "--build-only" ]; then
  build_only=1
  shift
fi
seconds="${1:-30}"
shift || true
readers=("$@")
[ ${#readers[@]} -gt 0 ] || readers=(bvh asf amc scenario npy graph_cache policy_bundle checkpoint protocol)
build="${FUZZ_BUILD:-$root/build-fuzz}"
cxx="${CXX:-clang++}"
command -v "$cxx" >/dev/null || { echo "fuzz.sh: $cxx not found (libFuzzer needs clang)" >&2; exit 1; }
jobs="${FUZZ_JOBS:-1}"
timeout="${FUZZ_TIMEOUT:-10}"
[[ "$jobs" =~ ^[1-9][0-9]*$ && "$timeout" =~ ^[1-9][0-9]*$ ]] ||
  { echo "fuzz.sh: expected FUZZ_JOBS and FUZZ_TIMEOUT of at least 1, found '$jobs' and '$timeout'" >&2; exit 2; }

targets=()
for r in "${readers[@]}"; do targets+=("${r}_fuzz"); done
tests=OFF
if [ "${FUZZ_WITH_TESTS:-0}" = 1 ]; then
  tests=ON
  targets=(all)
fi
# -O2: at -O1 clang left Eigen's coefficient accessors as calls, each checked
# by AddressSanitizer: a third of a learned opponent's tabulation went to them. Measured
# (2026-11-27, 2 cores, no ccache): the mgrl program compiles in the same time at both
# levels (970 and 1,005 s of compiler time for the same objects), and spar_learned.yaml's
# two self-play rounds on the self-play test's small grid train in 73 s of CPU at -O2
# against 185 s at -O1 (tabulation 15.5 s against 43.3 s per round).
# Line tables only (-gline-tables-only): enough for a sanitizer's or the fuzzer's stack
# trace with files and lines, and far quicker to compile and link than full debug info.
# ccache as in scripts/build.sh. With debug information ccache hashes the working folder
# (the objects would name it), so a second checkout missed every object (measured: the
# sanitizer build took 978 s with a warm cache, 998 s cold); the objects name "." instead
# (-fdebug-compilation-dir=., paths relative to the build folder) and ccache leaves the
# folder out (CCACHE_NOHASHDIR).
launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=)
if [ "${MGRL_CCACHE:-1}" != 0 ] && command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}"
  # The test files compiled with the precompiled header (tests/CMakeLists.txt) are cached too.
  export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
  export CCACHE_NOHASHDIR=1
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="${FUZZ_OPT:--O2} -gline-tables-only -fdebug-compilation-dir=." -DMGRL_FUZZ=ON -DMGRL_BUILD_TESTS="$tests" \
  -DMGRL_BUILD_BENCH=OFF "${launcher[@]}" >/dev/null
nice -n 10 cmake --build "$build" -j "${FUZZ_BUILD_JOBS:-2}" --target "${targets[@]}"
((build_only)) && exit 0

data="${MGRL_DATA:-$root/../shared/mocap}"
python3 "$root/tests/fuzz/make_corpus.py" "$data" "$build" --capture-only

# What the fuzzer said about a finding: its report from the first line of it to its
# SUMMARY line (the error, the stack), then where the input was saved and, when short, the
# input itself.
show_finding() {
  local log="$1"
  awk '!on && /FINDING|==[0-9]+==(ERROR|WARNING)|runtime error|ERROR: libFuzzer|deadly signal|ALARM: /{on = 1}
       on && shown < 60 {print; shown++}
       on && /^SUMMARY: /{exit}' "$log"
  grep -E '^(artifact_prefix=|Base64: )' "$log" || true
  grep -qE 'FINDING|==[0-9]+==(ERROR|WARNING)|runtime error|ERROR: libFuzzer|deadly signal|ALARM: ' "$log" || tail -20 "$log"
}

# One harness; its line goes to stdout when it ends, a finding's report to stderr.
fuzz_one() {
  local r="$1"
  local corpus="$build/corpus/$r" findings="$build/findings/$r" log="$build/findings/$r.log"
  mkdir -p "$corpus" "$findings"
  local seeds=() d
  for d in "$root/tests/fuzz/corpus/$r" "$build/seeds/$r"; do [ -d "$d" ] && seeds+=("$d"); done
  # -rss_limit_mb and -malloc_limit_mb: a reader that asks for more than 2 GB for an input
  # of a few KB is a finding (the readers once did so). -timeout: one input's wall time,
  # so a loaded machine (CI) wants more than the default.
  local started=$SECONDS
  if nice -n 19 "$build/tests/fuzz/${r}_fuzz" "$corpus" "${seeds[@]}" \
      -max_total_time="$seconds" -rss_limit_mb=2560 -malloc_limit_mb=2048 -timeout="$timeout" -max_len=65536 \
      -artifact_prefix="$findings/" -print_final_stats=1 >"$log" 2>&1; then
    local execs cov
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
    cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 || true)
    echo "fuzz $r: $((SECONDS - started)) s, ${execs} executions, ${cov:-cov ?}, no finding"
  else
    # One write, so that the report of a harness run beside it does not cut into it.
    local report
    report="$(echo "fuzz $r: FINDING (the fuzzer's output: $log; the input: $findings/)"
              show_finding "$log" | sed "s/^/fuzz $r: | /")"
    printf '%s\n' "$report" >&2
    return 1
  fi
}

# FUZZ_JOBS harnesses at a time, each started as soon as one ends.
status=0 running=0
for r in "${readers[@]}"; do
  if ((running >= jobs)); then
    wait -n || status=1
    running=$((running - 1))
  fi
  fuzz_one "$r" &
  running=$((running + 1))
done
while ((running > 0)); do
  wait -n || status=1
  running=$((running - 1))
done
exit $status
