#!/usr/bin/env bash
# One command: install what is missing, build, run the main job on the bundled sample:
# verify the five-axis ball-end finish of the sculptured part on the measured Matsuura machine,
# then the NAS 979 cone read from its STEP file, its flank's zone named by the CAD face's colour.
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
printf 'region,tolerance\ncolour #e77c7c,0.02\n' > out/cone_flank.csv
# Exit 1 is the verdict (FAIL: the flank leaves its 20 um zone), not an error.
./build/app/tolver verify \
  --machine samples/machines/matsuura_mc760vx_measured.xml \
  --setup samples/matsuura_setup.txt \
  --cl samples/nas979_cone.apt \
  --part samples/nas979_cone.step \
  --zones out/cone_flank.csv --spacing 1 \
  --report-dir out/cone_step || [ $? -eq 1 ]
echo "Report: out/cone_step/report.html (the part from STEP; its 3D view: out/cone_step/report.html#view3d)"
