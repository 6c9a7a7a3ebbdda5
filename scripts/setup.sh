#!/usr/bin/env bash
# Installs what mgrl needs to build and test, from Debian 12 packages, if missing.
set -euo pipefail

packages=(g++ cmake ninja-build pkg-config git python3 libeigen3-dev libfmt-dev libcli11-dev nlohmann-json3-dev libyaml-cpp-dev catch2)

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
