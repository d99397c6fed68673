#!/usr/bin/env bash
# Installs the peers the benchmarks compare against, from Debian 12 packages (not needed to build,
# test or run tolver): Orocos KDL (kinematics, bench/peer_benchmark), Ceres Solver (least squares,
# bench/peer_benchmark) and CloudCompare (point-to-mesh distances, bench/cloudcompare_deviations.sh).
# Reconfigure afterwards (scripts/build.sh) so that peer_benchmark is built.
set -euo pipefail
exec "$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/scripts/install_deps.sh" \
  liborocos-kdl-dev libceres-dev cloudcompare xvfb
