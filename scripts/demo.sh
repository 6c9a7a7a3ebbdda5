#!/usr/bin/env bash
# The main job: set up, build, and show what mgrl finds in the CMU shadow-boxing capture.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
data="${MGRL_DATA:-$root/../shared/mocap}"
"$root/build/app/mgrl" inspect "$data/cmu/bvh/13_17_boxing.bvh" "$data/cmu/bvh/13_18_boxing.bvh" "$@"
