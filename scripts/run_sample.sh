#!/usr/bin/env bash
# One command: install what is missing, build, run the main job on the bundled sample:
# verify the five-axis ball-end finish of the sculptured part on the measured Matsuura machine.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/scripts/install_deps.sh"
"$here/scripts/build.sh"
cd "$here"
./build/app/tolver verify \
  --machine samples/machines/matsuura_mc760vx_measured.xml \
  --setup samples/matsuura_setup.txt \
  --cl samples/sculptured_finish.apt \
  --part samples/sculptured_part.obj \
  --tolerance 0.03 \
  --report-dir out/sculptured
echo "Report: out/sculptured/report.html (open it in a browser); machine-readable: out/sculptured/report.json"
