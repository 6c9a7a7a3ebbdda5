#!/usr/bin/env bash
# scripts/bench_compare.sh refuses wrong arguments in one line, exit 2, before it builds
# anything: no arguments, an unknown revision, a benchmark name that is not a word, and
# BENCH_ROUNDS below 1. Usage: bench_compare_args_test.sh SOURCE_DIR
set -uo pipefail
script="$1/scripts/bench_compare.sh"
failures=0
expect() {  # MESSAGE COMMAND...: the command exits 2 and its stderr holds MESSAGE
  local message="$1"
  shift
  local err status
  err="$("$@" 2>&1 >/dev/null)"
  status=$?
  if [ "$status" != 2 ] || [[ "$err" != *"$message"* ]]; then
    echo "FAIL: $*: expected exit 2 and '$message', found exit $status and: $err"
    failures=$((failures + 1))
  fi
}
expect "usage: scripts/bench_compare.sh REV BENCH" "$script"
expect "expected a revision of this repository, found 'no-such-revision'" "$script" no-such-revision learn
expect "expected a benchmark name such as learn, found 'learn;rm'" "$script" HEAD 'learn;rm'
expect "expected BENCH_ROUNDS of at least 1, found '0'" env BENCH_ROUNDS=0 "$script" HEAD learn
[ "$failures" = 0 ] && echo "bench_compare_args: 4 refusals as expected"
exit $((failures > 0))
