#!/usr/bin/env bash
# The main job: set up, build, inspect the CMU shadow-boxing capture, build the boxing
# scenario's motion graph (cached after the first run), train its approach and hit
# behaviours with the paper's Q-learning, evaluate the combined policy, then run a
# two-boxer bout (BVH files and hits in build/demo/) and the paper's 30-boxer crowd.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
data="${MGRL_DATA:-$root/../shared/mocap}"
"$root/build/app/mgrl" inspect "$data/cmu/bvh/13_17_boxing.bvh" "$data/cmu/bvh/13_18_boxing.bvh"
"$root/build/app/mgrl" graph "$root/scenarios/boxing.yaml" --data "$data" "$@"
"$root/build/app/mgrl" train "$root/scenarios/boxing.yaml" --data "$data"
"$root/build/app/mgrl" eval "$root/scenarios/boxing.yaml" --data "$data" --trials 200
"$root/build/app/mgrl" simulate "$root/scenarios/boxing.yaml" --data "$data" --avatars 2 --seconds 60 \
  --bvh-out "$root/build/demo" --events-out "$root/build/demo/hits.jsonl"
"$root/build/app/mgrl" simulate "$root/scenarios/boxing.yaml" --data "$data" --avatars 30 --seconds 33.3
