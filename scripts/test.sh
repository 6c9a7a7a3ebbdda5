#!/usr/bin/env bash
# Sets up, builds and runs every test: the full suite in a Release build, then again under
# AddressSanitizer and UndefinedBehaviorSanitizer.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
jobs="$(nproc)"
"$root/scripts/setup.sh"

echo "== Release build and full test suite" >&2
"$root/scripts/build.sh" "$root/build"
(cd "$root/build" && ctest --output-on-failure -j "$jobs")

echo "== ASan/UBSan build and full test suite" >&2
"$root/scripts/build.sh" "$root/build-asan" -DMGRL_SANITIZE=ON -DMGRL_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo
(cd "$root/build-asan" && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j "$jobs")
