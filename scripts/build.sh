#!/usr/bin/env bash
# Configures and builds mgrl.
# Usage: scripts/build.sh [BUILD_DIR [--target NAME] [extra cmake configure args...]]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
shift || true
target=()
if [ "${1:-}" = "--target" ]; then
  target=(--target "$2")
  shift 2
fi
# ccache (scripts/setup.sh installs it) keeps compiled objects between builds and
# checkouts: paths under this checkout are hashed relative to the build folder
# (CCACHE_BASEDIR), so a fresh clone's build of the same sources hits what another
# checkout's build put there. MGRL_CCACHE=0 builds without it.
launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=)
if [ "${MGRL_CCACHE:-1}" != 0 ] && command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}"
  # The test files compiled with the precompiled header (tests/CMakeLists.txt) are cached too.
  export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@" >/dev/null
cmake --build "$build" -j "$(nproc)" "${target[@]}"
