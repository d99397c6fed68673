#!/usr/bin/env bash
# Installs the peers the benchmarks compare against, from Debian 12 packages (not needed to build,
# test or run tolver): Orocos KDL (kinematics, bench/peer_benchmark), Ceres Solver (least squares,
# bench/peer_benchmark) and CloudCompare (point-to-mesh distances, bench/cloudcompare_deviations.sh).
# Reconfigure afterwards (scripts/build.sh) so that peer_benchmark is built.
set -euo pipefail
packages=(liborocos-kdl-dev libceres-dev cloudcompare xvfb)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "tolver: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
