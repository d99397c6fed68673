#!/usr/bin/env bash
# One command: install what is missing, build, run the main job on the bundled sample.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/scripts/install_deps.sh"
"$here/scripts/build.sh"
cd "$here"
mkdir -p out
./build/app/tolver predict \
  --machine samples/machines/matsuura_mc760vx_measured.xml \
  --cl samples/nas979_cone.apt \
  --setup samples/matsuura_setup.txt \
  --errors out/predicted_points.csv \
  -o out/predicted.apt
echo "Predicted CL: out/predicted.apt   per-point table: out/predicted_points.csv"
