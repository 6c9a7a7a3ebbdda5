#!/usr/bin/env bash
# Builds mgrl (scripts/build.sh) and installs its Python module for this user with pip,
# offline: `python3 -c "import mgrl"` then works from any folder with Debian's
# /usr/bin/python3, and `python3 -m pip uninstall --break-system-packages mgrl` removes it.
# (Debian marks its Python as externally managed: pip's --user installs need
# --break-system-packages, which touches only your ~/.local. A venv needs neither:
# python3 -m venv --system-site-packages V && V/bin/pip install --no-build-isolation .)
#   scripts/install_python.sh [BUILD_DIR]    (default: build/)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
"$root/scripts/setup.sh" --python
"$root/scripts/build.sh" "$build"
site="$(/usr/bin/python3 -m site --user-site)"
# A copy this script made before pip installed it (a folder without pip's record) goes first.
if [ -d "$site/mgrl" ] && ! compgen -G "$site/mgrl-*.dist-info" >/dev/null; then rm -rf "$site/mgrl"; fi
MGRL_BUILD_DIR="$build" /usr/bin/python3 -m pip install --user --break-system-packages --no-index \
  --no-build-isolation "$root"
(cd / && /usr/bin/python3 -c "import mgrl; print('install_python: import mgrl works:', mgrl.__file__, mgrl.__version__)")
