#!/bin/bash
# The standing mutations (tests/mutations/*.patch): each is a small change to the product
# code that a test must catch. Each patch starts with three lines, then the diff:
#   Mutation: what the change does
#   Build: the targets its test needs
#   Catches: the shell command that must fail on it ($SOURCE: the tree, $BUILD: its build)
# This script copies the committed tree (a git worktree in $MGRL_MUTATIONS_DIR, default
# build-mutations/), builds it once and checks that every Catches command passes there
# (a command that fails anyway proves nothing), then applies each patch in turn, builds
# incrementally (ccache) and runs its command. It fails, naming them, if any mutation
# survives (its command passes) or does not apply or build.
# Usage: scripts/mutations.sh [NAME...]   (NAME: a patch's file name without .patch; default all)
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
work="${MGRL_MUTATIONS_DIR:-$root/build-mutations}"
tree="$work/tree"
# The build inside the tree, as build/ is in a checkout: ccache then hits what the
# checkout's own builds compiled (paths are hashed relative to the build folder).
export SOURCE="$tree" BUILD="$tree/build"
export MGRL_DATA="${MGRL_DATA:-$(cd "$root/.." && pwd)/shared/mocap}"
export PYTHONPATH="$BUILD/python" MGRL_SOURCE="$tree" MGRL_BIN="$BUILD/app/mgrl"
start=$SECONDS

patches=()
if [ $# -eq 0 ]; then
  patches=("$root"/tests/mutations/*.patch)
else
  for name in "$@"; do
    [ -f "$root/tests/mutations/$name.patch" ] ||
      { echo "mutations.sh: expected a patch tests/mutations/$name.patch, found none" >&2; exit 2; }
    patches+=("$root/tests/mutations/$name.patch")
  done
fi
[ -e "${patches[0]}" ] || { echo "mutations.sh: expected patches in tests/mutations/, found none" >&2; exit 2; }

field() { sed -n "s/^$2: //p" "$1" | head -1; }
for patch in "${patches[@]}"; do
  for key in Mutation Build Catches; do
    [ -n "$(field "$patch" $key)" ] ||
      { echo "mutations.sh: ${patch#"$root"/}: expected a '$key:' line before the diff, found none" >&2; exit 2; }
  done
done

# The committed tree, fresh: the worktree is reset to HEAD (what is not committed is not
# tested here).
mkdir -p "$work"
if [ ! -d "$tree/.git" ] && [ ! -f "$tree/.git" ]; then
  git -C "$root" worktree prune
  git -C "$root" worktree add --detach --quiet "$tree" HEAD || { echo "mutations.sh: cannot make $tree" >&2; exit 1; }
fi
git -C "$tree" checkout --quiet --detach "$(git -C "$root" rev-parse HEAD)"
git -C "$tree" reset --quiet --hard && git -C "$tree" clean --quiet -fd
# The tree's ../shared is the checkout's (the README's commands name ../shared/mocap).
[ -e "$work/shared" ] || ln -s "$(cd "$root/.." && pwd)/shared" "$work/shared"
# ...and so is the page's web/node_modules (npm ci's three.js, which cmake --install copies).
[ -e "$tree/web/node_modules" ] || [ ! -d "$root/web/node_modules" ] || ln -s "$root/web/node_modules" "$tree/web/node_modules"

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
build() {  # TARGETS...
  CCACHE_BASEDIR="$tree" cmake -S "$tree" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" \
    >"$work/configure.log" 2>&1 || { tail -20 "$work/configure.log" >&2; return 1; }
  # shellcheck disable=SC2068
  CCACHE_BASEDIR="$tree" cmake --build "$BUILD" -j "$(nproc)" --target $@ >"$work/build.log" 2>&1 ||
    { grep -m 5 -E "error" "$work/build.log" >&2; return 1; }
}
catches() {  # PATCH: runs its command, output in $work/last.log; returns its status
  (cd "$tree" && timeout 900 bash -c "$(field "$1" Catches)") >"$work/last.log" 2>&1 || return 1
  # A selection that matches nothing passes (Catch2 v2, unittest): it proves nothing.
  if grep -qE "No test cases matched|No tests ran|Ran 0 tests|No tests were found" "$work/last.log"; then
    echo "mutations.sh: $(basename "$1" .patch): its command selects no test: $(field "$1" Catches)" >&2
    return 2
  fi
}

targets="$(for p in "${patches[@]}"; do field "$p" Build; done | tr ' ' '\n' | sort -u | tr '\n' ' ')"
echo "mutations: building $targets at $(git -C "$tree" rev-parse --short HEAD) in $BUILD" >&2
build $targets || { echo "mutations.sh: the unmutated tree does not build" >&2; exit 1; }
for patch in "${patches[@]}"; do
  catches "$patch"
  status=$?
  if [ $status -eq 2 ]; then
    exit 1
  elif [ $status -ne 0 ]; then
    tail -20 "$work/last.log" >&2
    echo "mutations.sh: $(basename "$patch" .patch): its test fails on the unmutated tree: $(field "$patch" Catches)" >&2
    exit 1
  fi
done

survived=()
for patch in "${patches[@]}"; do
  name="$(basename "$patch" .patch)"
  t0=$SECONDS
  if ! git -C "$tree" apply "$patch"; then
    survived+=("$name (does not apply: refresh the patch)")
    continue
  fi
  if ! build "$(field "$patch" Build)"; then
    survived+=("$name (does not build)")
  else
    catches "$patch"
    case $? in
      0) survived+=("$name")
         echo "mutation $name SURVIVED ($((SECONDS - t0)) s): $(field "$patch" Mutation)" >&2 ;;
      2) survived+=("$name (its command selects no test)") ;;
      *) echo "mutation $name caught ($((SECONDS - t0)) s): $(field "$patch" Mutation)" >&2 ;;
    esac
  fi
  git -C "$tree" checkout --quiet -- .
done
# Leave the build matching the tree for the next run.
build $targets >/dev/null 2>&1 || true

if [ ${#survived[@]} -gt 0 ]; then
  echo "mutations.sh: ${#survived[@]} of ${#patches[@]} mutations not caught in $((SECONDS - start)) s:" >&2
  printf '  %s\n' "${survived[@]}" >&2
  exit 1
fi
echo "mutations.sh: all ${#patches[@]} mutations caught in $((SECONDS - start)) s" >&2
