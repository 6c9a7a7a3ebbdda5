#!/usr/bin/env bash
# Checks what scripts/demo.sh printed and wrote: every step ran and said what it made.
# Usage: scripts/check_demo.sh STDOUT_FILE STDERR_FILE DEMO_OUTPUT_DIR
set -euo pipefail
stdout="$1" stderr="$2" dir="$3"
fail() {
  echo "check_demo: $*" >&2
  exit 1
}
expect() {  # FILE REGEX WHAT
  grep -Eq "$2" "$1" || fail "expected $3 in $(basename "$1"), found none (regex: $2)"
}
expect "$stdout" '^[^ ]*13_17_boxing\.bvh$' "the inspect report of 13_17_boxing.bvh"
expect "$stdout" '^states +[0-9]+' "the graph's state count"
expect "$stdout" '^policy bundle: ' "the trained policy bundle's path"
expect "$stdout" 'success rate [0-9.]+ %' "the evaluation's success rate"
# The trained boxer must actually hit: with the quick budgets it lands in most trials, far
# more often than random actions on the same starts.
policy="$(sed -nE 's/^controller policy: .*success rate ([0-9.]+) %.*/\1/p' "$stdout")"
random="$(sed -nE 's/^random baseline .*success rate ([0-9.]+) %.*/\1/p' "$stdout")"
[ -n "$policy" ] && [ -n "$random" ] || fail "expected the policy's and the random baseline's success rates, found '$policy' and '$random'"
awk -v p="$policy" -v r="$random" -v min="${MGRL_DEMO_MIN_SUCCESS:-50}" 'BEGIN { exit !(p >= min && p >= r + 20) }' ||
  fail "expected the trained policy to succeed in at least ${MGRL_DEMO_MIN_SUCCESS:-50} % of trials and 20 points more than random actions, found $policy % against $random %"
hits="$(sed -nE 's/^hits: ([0-9]+) .*/\1/p' "$stdout" | head -1)"
[ -n "$hits" ] || fail "expected the two-boxer bout to report its hits, found no 'hits:' line"
expect "$stdout" '2 avatars x [0-9]+ frames' "the two-boxer bout"
# The bout is boxing_spar.yaml's: the boxers keep a fighting distance (about 1.2 m between
# pelvises), where the paper's target behaviours close in to 0.66 m. mgrl stats
# prints the real capture's column first when it compares.
distance="$(awk '/^pelvis distance, median \(m\)/ { print (NF == 7 ? $(NF - 1) : $NF); exit }' "$stdout")"
[ -n "$distance" ] || fail "expected mgrl stats' median pelvis distance of the bout, found none"
awk -v d="$distance" 'BEGIN { exit !(d >= 0.9) }' ||
  fail "expected the bout's boxers at a fighting distance (median pelvis distance at least 0.9 m), found $distance m"
# They punch: real sparring fighters throw about 48 strikes a minute and land almost none
# (0.7), so the bout's boxers must strike, not land (a 10 s bout may land nothing).
strikes="$(awk '/^strikes \/ fighter-min/ { print $NF; exit }' "$stdout")"
[ -n "$strikes" ] || fail "expected mgrl stats' strikes per fighter-minute of the bout, found none"
awk -v s="$strikes" 'BEGIN { exit !(s >= 10) }' ||
  fail "expected the bout's boxers to throw at least 10 strikes per fighter-minute, found $strikes"
expect "$stdout" '30 avatars x [0-9]+ frames' "the 30-boxer crowd"
expect "$stderr" 'demo: \[[0-9]+ s\] done' "the demo's last step"
expect "$stderr" 'watch it in the browser: scripts/demo.sh --serve' "the command that opens the viewer"
for f in avatar_000.bvh avatar_001.bvh hits.jsonl; do
  [ -f "$dir/$f" ] || fail "expected $dir/$f, found none"
done
head -c 9 "$dir/avatar_000.bvh" | grep -q '^HIERARCHY' || fail "expected $dir/avatar_000.bvh to start with HIERARCHY"
grep -q '^MOTION' "$dir/avatar_001.bvh" || fail "expected a MOTION section in $dir/avatar_001.bvh, found none"
echo "check_demo: every step of the main job ran and wrote its files" >&2
