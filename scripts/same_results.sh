#!/usr/bin/env bash
# Checks that this checkout trains, evaluates and simulates as another revision does: the
# rule a refactor keeps (tables byte for byte, reports equal but for their timings).
#
# Usage: scripts/same_results.sh REV [SCENARIO...]
#   REV       a commit, tag or branch (its mgrl built in a temporary worktree, removed after)
#   SCENARIO  names under scenarios/ (default: boxing out_boxing intercept dodge kick
#             spar_learned; spar_learned on a small grid, two self-play rounds)
# For each scenario and each build, with one fresh cache per build: `mgrl train --json --out`,
# `mgrl eval --policy --json` (100 trials) and `mgrl simulate --policy --avatars 4 --seconds 20
# --json`. Then every table (.npy) is compared byte for byte and every eval and simulate report
# key by key, leaving out what measures time and where files went. Prints each difference and
# exits 1 if there is any. Both builds read this checkout's scenario files.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
if [ $# -lt 1 ]; then
  echo "usage: scripts/same_results.sh REV [SCENARIO...]" >&2
  exit 2
fi
rev="$1"
shift
scenarios=("$@")
((${#scenarios[@]})) || scenarios=(boxing out_boxing intercept dodge kick spar_learned)
for name in "${scenarios[@]}"; do
  [ -f "$root/scenarios/$name.yaml" ] ||
    { echo "same_results.sh: expected a scenario name under scenarios/, found '$name'" >&2; exit 2; }
done
commit="$(git -C "$root" rev-parse --verify --quiet "$rev^{commit}")" ||
  { echo "same_results.sh: expected a revision of this repository, found '$rev'" >&2; exit 2; }
export MGRL_DATA="${MGRL_DATA:-$(cd "$root/.." && pwd)/shared/mocap}"

scratch="$(mktemp -d "${TMPDIR:-/tmp}/mgrl-same-results.XXXXXX")"
cleanup() {
  git -C "$root" worktree remove --force "$scratch/rev" >/dev/null 2>&1 || true
  rm -rf "$scratch"
}
trap cleanup EXIT
git -C "$root" worktree add --detach --quiet "$scratch/rev" "$commit"
launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
echo "same_results: building mgrl at ${commit:0:12} ($rev) and in this checkout" >&2
for side in rev now; do
  source="$scratch/rev" build="$scratch/rev/build"
  [ "$side" = now ] && source="$root" build="$root/build"
  if [ "$side" = rev ] || [ ! -f "$build/CMakeCache.txt" ]; then
    CCACHE_BASEDIR="$source" cmake -S "$source" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" \
      >"$scratch/build-$side.log" 2>&1 || { tail -20 "$scratch/build-$side.log" >&2; exit 1; }
  fi
  CCACHE_BASEDIR="$source" cmake --build "$build" -j "$(nproc)" --target mgrl >>"$scratch/build-$side.log" 2>&1 ||
    { tail -20 "$scratch/build-$side.log" >&2; echo "same_results.sh: mgrl does not build ($side)" >&2; exit 1; }
done

small=(--set behaviors.spar.discretizer.sectors=2 --set behaviors.spar.discretizer.rings=2
  --set behaviors.spar.discretizer.headings=2 --set behaviors.spar.environment.phases=1
  --set behaviors.spar.environment.rounds=2)
run() {  # SIDE MGRL
  local out="$scratch/out-$1" name extra
  mkdir -p "$out"
  for name in "${scenarios[@]}"; do
    extra=()
    [ "$name" = spar_learned ] && extra=("${small[@]}")
    local scenario="$root/scenarios/$name.yaml"
    echo "same_results: $1: $name" >&2
    MGRL_CACHE="$out/cache" "$2" train "$scenario" "${extra[@]}" --json --out "$out/$name" >"$out/$name.train.json" 2>"$out/$name.err" &&
      MGRL_CACHE="$out/cache" "$2" eval "$scenario" "${extra[@]}" --policy "$out/$name" --json >"$out/$name.eval.json" 2>>"$out/$name.err" &&
      MGRL_CACHE="$out/cache" "$2" simulate "$scenario" "${extra[@]}" --policy "$out/$name" --avatars 4 --seconds 20 \
        --json >"$out/$name.simulate.json" 2>>"$out/$name.err" ||
      { tail -5 "$out/$name.err" >&2; echo "same_results.sh: $name failed ($1)" >&2; exit 1; }
  done
}
run rev "$scratch/rev/build/app/mgrl"
run now "$root/build/app/mgrl"

python3 - "$scratch/out-rev" "$scratch/out-now" "${commit:0:12}" "${scenarios[@]}" <<'EOF'
import filecmp, json, pathlib, sys
rev, now, commit, names = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]), sys.argv[3], sys.argv[4:]

def kept(key):  # what measures time or names a file is not compared
    return not (key.endswith("seconds") or key.endswith("per_second") or key in ("cache", "policy", "out", "scenario"))

def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if kept(k)}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x

differences = 0
for name in names:
    tables = sorted(p.name for p in (rev / name).glob("*.npy"))
    if tables != sorted(p.name for p in (now / name).glob("*.npy")):
        print(f"{name}: expected the tables {tables}, found {sorted(p.name for p in (now / name).glob('*.npy'))}")
        differences += 1
    for table in tables:
        if (now / name / table).exists() and not filecmp.cmp(rev / name / table, now / name / table, shallow=False):
            print(f"{name}: {table} differs")
            differences += 1
    for kind in ("eval", "simulate"):
        a = strip(json.loads((rev / f"{name}.{kind}.json").read_text()))
        b = strip(json.loads((now / f"{name}.{kind}.json").read_text()))
        for key in sorted(set(a) | set(b)):
            if a.get(key) != b.get(key):
                print(f"{name}: {kind} {key}: {commit} {json.dumps(a.get(key))[:80]}, this checkout {json.dumps(b.get(key))[:80]}")
                differences += 1
    print(f"same_results: {name}: {len(tables)} tables, eval and simulate compared")
print(f"same_results: {differences} difference(s) against {commit}")
sys.exit(1 if differences else 0)
EOF
