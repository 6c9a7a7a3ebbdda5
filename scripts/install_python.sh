#!/usr/bin/env bash
# Builds mgrl (scripts/build.sh) and installs its Python module for this user, offline:
# build/python/mgrl is copied to Python's user site-packages, so that `python3 -c "import
# mgrl"` works from any folder with Debian's /usr/bin/python3.
#   scripts/install_python.sh [BUILD_DIR]    (default: build/)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
"$root/scripts/setup.sh" --python
"$root/scripts/build.sh" "$build"
module="$build/python/mgrl"
compgen -G "$module/_core*.so" >/dev/null ||
  { echo "install_python: expected the module in $module (_core*.so), found none: is pybind11-dev installed?" >&2; exit 1; }
site="$(/usr/bin/python3 -m site --user-site)"
mkdir -p "$site"
rm -rf "$site/mgrl.tmp"
cp -r "$module" "$site/mgrl.tmp"
rm -rf "$site/mgrl"
mv "$site/mgrl.tmp" "$site/mgrl"
(cd / && /usr/bin/python3 -c "import mgrl; print('install_python: import mgrl works:', mgrl.__file__)")
