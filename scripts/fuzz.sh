#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz, clang, -DMGRL_FUZZ=ON in build-fuzz/) and
# runs each for SECONDS (default 30) from its seed corpus; fails on the first finding
# (an exception other than mgrl::Error, a sanitizer report, a crash, a timeout, or an
# allocation above the limits below). Findings are saved as build-fuzz/findings/<reader>/
# crash-*, oom-*, timeout-*; the inputs the fuzzer finds go to build-fuzz/corpus/<reader>/
# (the seeds are only read), so later runs start from them. Seeds: the project's own in
# tests/fuzz/corpus/<reader>/, and those cut from the capture (MGRL_DATA, else
# ../shared/mocap) by tests/fuzz/make_corpus.py into build-fuzz/seeds/<reader>/ first.
# Usage: scripts/fuzz.sh [SECONDS [READER...]]
#   FUZZ_BUILD=DIR (default build-fuzz), CXX=clang++ (default), FUZZ_BUILD_JOBS=N (default 2).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
seconds="${1:-30}"
shift || true
readers=("$@")
[ ${#readers[@]} -gt 0 ] || readers=(bvh asf amc scenario npy graph_cache policy_bundle checkpoint protocol)
build="${FUZZ_BUILD:-$root/build-fuzz}"
cxx="${CXX:-clang++}"
command -v "$cxx" >/dev/null || { echo "fuzz.sh: $cxx not found (libFuzzer needs clang)" >&2; exit 1; }

targets=()
for r in "${readers[@]}"; do targets+=("${r}_fuzz"); done
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DMGRL_FUZZ=ON -DMGRL_BUILD_TESTS=OFF -DMGRL_BUILD_BENCH=OFF >/dev/null
nice -n 10 cmake --build "$build" -j "${FUZZ_BUILD_JOBS:-2}" --target "${targets[@]}"

data="${MGRL_DATA:-$root/../shared/mocap}"
python3 "$root/tests/fuzz/make_corpus.py" "$data" "$build" --capture-only

status=0
for r in "${readers[@]}"; do
  corpus="$build/corpus/$r" findings="$build/findings/$r"
  mkdir -p "$corpus" "$findings"
  log="$build/findings/$r.log"
  # -rss_limit_mb and -malloc_limit_mb: a reader that asks for more than 2 GB for an input
  # of a few KB is a finding (issue 19, defects 1 and 2). -timeout: 10 s for one input.
  seeds=()
  for d in "$root/tests/fuzz/corpus/$r" "$build/seeds/$r"; do [ -d "$d" ] && seeds+=("$d"); done
  if nice -n 19 "$build/tests/fuzz/${r}_fuzz" "$corpus" "${seeds[@]}" \
      -max_total_time="$seconds" -rss_limit_mb=2560 -malloc_limit_mb=2048 -timeout=10 -max_len=65536 \
      -artifact_prefix="$findings/" -print_final_stats=1 >"$log" 2>&1; then
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
    cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 || true)
    echo "fuzz $r: ${seconds} s, ${execs} executions, ${cov:-cov ?}, no finding"
  else
    echo "fuzz $r: FINDING (see $log and $findings/)" >&2
    grep -m3 -E 'FINDING|ERROR: |runtime error|SUMMARY' "$log" >&2 || tail -5 "$log" >&2
    status=1
  fi
done
exit $status
