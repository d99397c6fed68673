#!/usr/bin/env bash
# Installs tolver's build and test dependencies from Debian 12 packages.
# Idempotent: installs only what is missing; runs apt-get update only then.
# Usage: scripts/install_deps.sh [packages...]
set -euo pipefail
packages=(
  build-essential cmake pkg-config ninja-build
  clang libclang-rt-14-dev clang-format
  libeigen3-dev libboost-dev libcgal-dev libassimp-dev libminizip-dev libvtk9-dev
  libtinyxml2-dev libcli11-dev nlohmann-json3-dev libtbb-dev
  libgtest-dev libgmock-dev libbenchmark-dev libpagmo-dev libx11-dev
  xvfb libgl1-mesa-dri
  chromium
  libocct-data-exchange-dev libocct-ocaf-dev occt-draw libocct-draw-dev libopenmesh-dev libjs-three
)
# Other packages instead, when given (bench/install_peers.sh): the same check and install.
[ $# -gt 0 ] && packages=("$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "tolver: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
