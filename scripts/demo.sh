#!/usr/bin/env bash
# The main job: set up, build the `mgrl` program, inspect the CMU shadow-boxing capture,
# build the boxing scenario's motion graph (cached after the first run), train its
# approach and hit behaviours with the paper's Q-learning, evaluate the combined policy
# against a random controller, then train boxing_spar.yaml's sparring behaviour (value
# iteration, seconds) and run a two-boxer bout at a fighting distance (BVH files and hits
# in build/demo/), measure it against the SNU sparring capture (mgrl stats), and run the
# paper's 30-boxer crowd with the paper's behaviours.
#
# Usage: scripts/demo.sh [--quick] [--serve] [extra `mgrl graph` arguments]
#   --quick   small training budgets and short runs (about 1 minute after the build): the
#             same steps, used by scripts/test.sh from a fresh clone so a broken main job
#             cannot land.
#   --serve   then start the browser viewer on the trained policy (mgrl serve; Ctrl-C
#             stops it).
# Environment: MGRL_DATA (motion capture, default ../shared/mocap), MGRL_CACHE (graphs and
# policies, default ~/.cache/mgrl), MGRL_BUILD_DIR (default build/).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
quick=0
serve=0
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --serve) serve=1 ;;
    *) break ;;
  esac
  shift
done
build="${MGRL_BUILD_DIR:-$root/build}"
out="$build/demo"
data="${MGRL_DATA:-$root/../shared/mocap}"
mgrl="$build/app/mgrl"
start=$SECONDS

say() { echo "demo: $*" >&2; }
step() { say "[$((SECONDS - start)) s] $*"; }

if [ ! -d "$data/cmu/bvh" ]; then
  say "expected the motion capture in $data (with cmu/bvh/ inside), found none: set MGRL_DATA"
  exit 1
fi
if [ -x "$mgrl" ]; then
  say "about 1 minute with the program already built (training takes about 15 s of it)"
else
  say "about 10 minutes on a 2-core machine: the build takes most of it, training about 15 s"
fi

step "set-up (installs missing Debian packages)"
"$root/scripts/setup.sh"

step "building mgrl into $build (log: $build/demo-build.log)"
mkdir -p "$build"
if ! "$root/scripts/build.sh" "$build" --target mgrl >"$build/demo-build.log" 2>&1; then
  tail -n 30 "$build/demo-build.log" >&2
  say "the build failed; the whole log is $build/demo-build.log"
  exit 1
fi

# Quick mode: the same commands with budgets small enough for CI.
train_sets=()
trials=200
bout=60
crowd=33.3
if ((quick)); then
  train_sets=(--set behaviors.approach.learner.budget=200000 --set behaviors.hit.learner.budget=400000)
  trials=20
  bout=10
  crowd=3
fi

mkdir -p "$out"
step "inspect: the CMU shadow-boxing capture"
"$mgrl" inspect "$data/cmu/bvh/13_17_boxing.bvh" "$data/cmu/bvh/13_18_boxing.bvh"
step "graph: the boxing scenario's motion graph"
"$mgrl" graph "$root/scenarios/boxing.yaml" --data "$data" "$@"
step "train: approach and hit (Q-learning, paper sec. 4)"
"$mgrl" train "$root/scenarios/boxing.yaml" --data "$data" "${train_sets[@]}"
step "eval: the combined policy against a random controller"
"$mgrl" eval "$root/scenarios/boxing.yaml" --data "$data" --trials "$trials" "${train_sets[@]}"
# The bout: the paper's behaviours, made for a target, close in until the boxers stand
# chest to chest (pelvises about 0.66 m apart); boxing_spar.yaml's behaviours keep a
# fighting distance (about 1.2 m), stand in stances learned from real sparring and punch
# from there, on the same graph.
step "train: boxing_spar's sparring behaviours, one per stance (value iteration, paper sec. 4.2)"
"$mgrl" train "$root/scenarios/boxing_spar.yaml" --data "$data"
step "simulate: a two-boxer bout of $bout s at a fighting distance (BVH and hits in $out)"
"$mgrl" simulate "$root/scenarios/boxing_spar.yaml" --data "$data" --avatars 2 --seconds "$bout" \
  --bvh-out "$out" --events-out "$out/hits.jsonl"
if [ -d "$data/snu_martial_arts/motion" ]; then
  step "stats: the bout against the SNU sparring capture (real fighters)"
  "$mgrl" stats --data "$data" --compare --snu -- "$out"
else
  step "stats: the bout (no SNU capture in $data to compare it with)"
  "$mgrl" stats --data "$data" "$out"
fi
step "simulate: the paper's crowd of 30 sparring boxers"
"$mgrl" simulate "$root/scenarios/boxing.yaml" --data "$data" --avatars 30 --seconds "$crowd" "${train_sets[@]}"
step "done: BVH files and hits in $out"
if ((serve)); then
  step "serve: the viewer (drag the target; sparring and crowds play boxing_spar.yaml); Ctrl-C stops it"
  exec "$mgrl" serve "$root/scenarios/boxing.yaml" --data "$data" "${train_sets[@]}"
fi
say "watch it in the browser: scripts/demo.sh --serve, or $mgrl serve scenarios/boxing.yaml$(
  ((quick)) && printf ' %s' "${train_sets[@]}") and open http://127.0.0.1:8080/"
