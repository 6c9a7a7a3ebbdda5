#!/usr/bin/env bash
# Installs what mgrl needs to build and test, from Debian 12 packages, if missing, and the
# viewer's three.js (web/, from npm, exactly as web/package-lock.json says).
#   scripts/setup.sh          what building, the demo and `mgrl serve` need
#   scripts/setup.sh --python also matplotlib, nbconvert, a Jupyter kernel and Jupyter's
#                             notebook server for Debian's python3: the notebooks
#                             (notebooks/) and their plots
#   scripts/setup.sh --test   all of the above but the notebook server, Chromium, for the
#                             browser test (tests/web/),
#                             clang with its runtime libraries, for the fuzz smoke (libFuzzer),
#                             and Open MPI, for mpi_value_iteration's tests under mpirun
# Building installs pybind11 and NumPy too: `import mgrl` (python/) is part of the build.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"

packages=(g++ cmake ninja-build ccache pkg-config git python3 libeigen3-dev libfmt-dev libcli11-dev nlohmann-json3-dev
          libyaml-cpp-dev catch2 libboost-dev python3-dev pybind11-dev python3-numpy)
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)
# libclang-rt-dev holds libFuzzer and clang's sanitizer runtimes; clang only recommends
# it, and recommends are not installed below.
# clang-format, clang-tidy: the quick tier holds changed lines to .clang-format
# (scripts/format_check.sh) and changed sources to .clang-tidy (scripts/tidy_check.sh).
# openmpi-bin, libopenmpi-dev: mpirun and MPI's headers (without them the build
# still works and mpi_value_iteration runs as one process).
# dpkg-dev: dpkg-shlibdeps, which cpack -G DEB runs to declare the package's libraries;
# mkdocs: the documentation site (mkdocs.yml), built with --strict by the tests; curl:
# scripts/fetch_data.sh and the installed viewer's test.
[ "${1:-}" = "--test" ] && packages+=(chromium clang libclang-rt-dev clang-format clang-tidy openmpi-bin libopenmpi-dev
                                      dpkg-dev mkdocs curl)
# pip, setuptools, wheel and venv: pip install . (pyproject.toml), offline, with Debian's tools.
case "${1:-}" in --test | --python) packages+=(python3-matplotlib jupyter-nbconvert python3-ipykernel python3-pip
                                               python3-setuptools python3-wheel python3-venv) ;; esac
# Jupyter's notebook server (`jupyter notebook notebooks/`) for the Python set-up; the tests
# execute the notebooks with nbconvert alone.
[ "${1:-}" = "--python" ] && packages+=(jupyter-notebook)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# three.js and playwright-core, pinned by the lock file; again only when the lock changed.
stamp="$root/web/node_modules/.mgrl-lock"
if ! cmp -s "$root/web/package-lock.json" "$stamp" 2>/dev/null; then
  echo "setup: installing the viewer's packages (npm ci in web/)" >&2
  (cd "$root/web" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
  cp "$root/web/package-lock.json" "$stamp"
fi
