#!/usr/bin/env bash
# Compares a benchmark of this checkout with the same benchmark built from another revision,
# run alternately on this machine, so that a slow drift shows as a ratio (DESIGN.md sec. 7:
# the machine is shared and noisy, so medians of alternating runs, never one run each).
#
# Usage: scripts/bench_compare.sh REV BENCH [ARGS...]
#   REV    a commit, tag or branch (built in a temporary worktree, removed afterwards)
#   BENCH  a benchmark target of bench/: learn, runtime, graph, load, memory, adaptive, serve
#   ARGS   passed to both, e.g. --approach-actions 10000000 --hit-actions 10000000 --runs 1 --no-growth
# Environment: BENCH_ROUNDS=N alternations (default 3); MGRL_DATA as for the benchmarks;
#   GLIBC_TUNABLES (default glibc.malloc.hugetlb=1: the heap on huge pages, see below);
#   BENCH_CMAKE_ARGS="-DMGRL_UNITY=OFF ..." configure options for both builds (this checkout is
#   then built in a scratch folder, so build/ keeps its own configuration): code layout
#   apart from unity batches, say, to tell a real slowdown from a moved one.
# Prints, for every output line whose text (numbers aside) both builds print, the median of
# each number over the rounds for REV and for this checkout and their ratio (this / REV),
# then where both outputs are kept.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
if [ $# -lt 2 ]; then
  echo "usage: scripts/bench_compare.sh REV BENCH [ARGS...]  (BENCH: learn, runtime, graph, load, memory, adaptive, serve)" >&2
  exit 2
fi
rev="$1" bench="$2"
shift 2
rounds="${BENCH_ROUNDS:-3}"
[[ "$rounds" =~ ^[1-9][0-9]*$ ]] || { echo "bench_compare.sh: expected BENCH_ROUNDS of at least 1, found '$rounds'" >&2; exit 2; }
[[ "$bench" =~ ^[a-z_]+$ ]] || { echo "bench_compare.sh: expected a benchmark name such as learn, found '$bench'" >&2; exit 2; }
target="mgrl_bench_$bench"
commit="$(git -C "$root" rev-parse --verify --quiet "$rev^{commit}")" ||
  { echo "bench_compare.sh: expected a revision of this repository, found '$rev'" >&2; exit 2; }

# The heap on transparent huge pages for both builds (glibc's malloc tunable; an explicit
# GLIBC_TUNABLES is kept). On this 2-core VM a loop streaming tens of megabytes (forward
# kinematics over the capture, a Q table) ran 7-10x slower in some processes than in others
# of the same binary: which depended on where its 4 KiB pages fell (ASLR and the
# environment's size moved it, ASLR off fixed it), so two builds differing in an unrelated
# file could read 0.1x. With huge pages every run of either build was fast
# (docs/development.md).
export GLIBC_TUNABLES="${GLIBC_TUNABLES:-glibc.malloc.hugetlb=1}"

# The capture this checkout reads by default (../shared/mocap beside it), for both builds:
# the other revision's worktree lives elsewhere.
export MGRL_DATA="${MGRL_DATA:-$(cd "$root/.." && pwd)/shared/mocap}"
scratch="$(mktemp -d "${TMPDIR:-/tmp}/mgrl-bench-compare.XXXXXX")"
worktree="$scratch/rev"
cleanup() {
  git -C "$root" worktree remove --force "$worktree" >/dev/null 2>&1 || true
  rm -rf "$scratch"
}
trap cleanup EXIT
git -C "$root" worktree add --detach --quiet "$worktree" "$commit"

echo "bench_compare: building $target at ${commit:0:12} ($rev) and in this checkout" >&2
# Both Release, configured alike here (an older scripts/build.sh may take other arguments);
# ccache shares what is the same.
build() {  # SOURCE BUILD_DIR LOG
  local launcher=()
  if [ "${MGRL_CCACHE:-1}" != 0 ] && command -v ccache >/dev/null 2>&1; then
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  fi
  local extra=()
  read -r -a extra <<<"${BENCH_CMAKE_ARGS:-}"
  CCACHE_BASEDIR="$1" cmake -S "$1" -B "$2" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "${extra[@]}" >"$3" 2>&1 &&
    CCACHE_BASEDIR="$1" cmake --build "$2" -j "$(nproc)" --target "$target" >>"$3" 2>&1
}
build "$worktree" "$worktree/build" "$scratch/build-rev.log" ||
  { tail -30 "$scratch/build-rev.log" >&2; echo "bench_compare.sh: $target does not build at $rev" >&2; exit 1; }
now_build="$root/build"
[ -n "${BENCH_CMAKE_ARGS:-}" ] && now_build="$scratch/now"
build "$root" "$now_build" "$scratch/build-now.log" ||
  { tail -30 "$scratch/build-now.log" >&2; echo "bench_compare.sh: $target does not build here" >&2; exit 1; }

out="$root/build/bench-compare"
mkdir -p "$out"
for ((r = 1; r <= rounds; r++)); do
  echo "bench_compare: round $r of $rounds" >&2
  "$worktree/build/bench/$target" "$@" >"$out/rev-$r.txt" 2>&1 || { cat "$out/rev-$r.txt" >&2; exit 1; }
  "$now_build/bench/$target" "$@" >"$out/now-$r.txt" 2>&1 || { cat "$out/now-$r.txt" >&2; exit 1; }
done

python3 - "$out" "$rounds" "${commit:0:12}" <<'EOF'
import re, statistics, sys
out, rounds, rev = sys.argv[1], int(sys.argv[2]), sys.argv[3]
number = re.compile(r'-?\d+(?:\.\d+)?(?:e[-+]?\d+)?')

def read(kind):
    runs = []
    for r in range(1, rounds + 1):
        with open(f"{out}/{kind}-{r}.txt") as f:
            runs.append([line.rstrip('\n') for line in f])
    return runs

def shapes(lines):
    # (text with numbers masked, occurrence) -> numbers of that line
    seen, result = {}, {}
    for line in lines:
        key = number.sub('#', line)
        n = seen.get(key, 0)
        seen[key] = n + 1
        result[(key, n)] = [float(x) for x in number.findall(line)]
    return result

rev_runs = [shapes(lines) for lines in read('rev')]
now_runs = [shapes(lines) for lines in read('now')]
order = [k for k in now_runs[0] if all(k in s for s in rev_runs + now_runs) and now_runs[0][k]]
print(f"median of {rounds} alternating rounds; ratio = this checkout / {rev}")
for key in order:
    width = min(len(s[key]) for s in rev_runs + now_runs)
    cells = []
    for i in range(width):
        a = statistics.median(s[key][i] for s in rev_runs)
        b = statistics.median(s[key][i] for s in now_runs)
        if a == b:
            continue  # a setting or a size, not a measurement
        ratio = b / a if a else float('inf')
        cells.append(f"{a:g} -> {b:g} ({ratio:.3f}x)")
    if cells:
        print(f"{key[0].strip()[:70]:<70}  " + "; ".join(cells))
print(f"outputs: {out}/rev-N.txt and {out}/now-N.txt")
EOF
