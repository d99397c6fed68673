#!/usr/bin/env bash
# Regenerates samples/ballbar/: simulated three-set-up ball-bar tests of the Matsuura MC-760VX
# (bars of 100, 150 and 300 mm, one per set-up; 324 poses + a return to each set-up's first
# pose after every 9: 360 readings, 20 s a
# reading, 0.5 um noise, 10 um ball position errors) from the measured sample machine with one
# effect the base model lacks (truth_<name>.xml), two at once, and none (clean).
# Usage: tools/make_ballbar_samples.sh [path/to/tolver]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
tolver="${1:-$here/build/app/tolver}"
out="samples/ballbar"
base="samples/machines/matsuura_mc760vx_measured.xml"
mkdir -p "$out"
"$tolver" plan-ballbar --machine resources/machines/matsuura_mc760vx.xml \
  --length 100,150,300 --setups 3 --poses 324 --reference-every 9 --seed 5 -o "$out/plan.csv" \
  --gcode "$out/plan.nc" > /dev/null

# name | effect element(s) added to the measured machine (um, urad, um per hour)
effects=(
  "clean|"
  "chebyshev|<effect type=\"chebyshev\" axis=\"Y\" component=\"ex\" orders=\"4 5\" values=\"3 -2\"/>"
  "reversal|<effect type=\"reversal\" axis=\"Y\" component=\"ey\" values=\"4\"/>"
  "periodic|<effect type=\"periodic\" axis=\"X\" component=\"ex\" period_mm=\"16\" values=\"1.5 -2\"/>"
  "harmonics|<effect type=\"harmonics\" axis=\"C\" component=\"gz\" orders=\"2 4\" values=\"30 -20 12 0 0 0\"/>"
  "drift|<effect type=\"drift\" axis=\"Z\" component=\"ez\" values=\"2\"/>"
  "warmup|<effect type=\"warmup\" axis=\"Z\" component=\"ez\" tau_s=\"1500\" values=\"5\"/>"
  "bar_length|<effect type=\"bar_length\" values=\"3\"/>"
  "two_effects|<effect type=\"reversal\" axis=\"X\" component=\"ex\" values=\"3.5\"/><effect type=\"periodic\" axis=\"Y\" component=\"ey\" period_mm=\"10\" values=\"-1.5 2\"/>"
)
seed=11
for entry in "${effects[@]}"; do
  name="${entry%%|*}"
  effect="${entry#*|}"
  truth="$out/truth_$name.xml"
  sed -e "s#<machine name=\"Matsuura MC-760VX (measured sample)\"#<machine name=\"Matsuura MC-760VX (truth: $name)\"#" \
      -e "s#^  </errors>#    $effect\n  </errors>#" "$base" > "$truth"
  "$tolver" simulate-ballbar --machine "$truth" --plan "$out/plan.csv" --noise-um 0.5 \
    --ball-error-um 10 --seconds-per-reading 20 --seed "$seed" -o "$out/$name.csv" > /dev/null
  seed=$((seed + 1))
  echo "wrote $out/$name.csv (truth $truth)"
done
