#!/usr/bin/env bash
# Verify at scale (issue 18): about a million surface samples and 120 801 CL points.
#   bench/verify_large.sh [spacing mm, default 0.115]     (after scripts/build.sh)
# The sculptured part (80 x 60 mm block, 13 067 mm2 of surface) and a five-axis ball-end finish of
# its top with a 0.1 mm step-over and a point every 0.4 mm (tools/make_samples --large), verified
# on the measured Matsuura with both cores. Prints the sample and placement counts, the wall time
# and peak memory, and the phase table verify records in report.json.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
spacing="${1:-0.115}"
tolver="$here/build/app/tolver"
make_samples="$here/build/tools/make_samples"
[ -x "$tolver" ] && [ -x "$make_samples" ] || { echo "build first: scripts/build.sh" >&2; exit 1; }
work="$(mktemp -d)"; [ -n "${TOLVER_BENCH_KEEP:-}" ] && echo "files kept in $work" >&2
[ -n "${TOLVER_BENCH_KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
"$make_samples" --large "$work"
cd "$here"
timer=()
[ -x /usr/bin/time ] && timer=(/usr/bin/time -f "%e s wall, %U s user, %S s sys, %M kB peak" -o "$work/time.txt")
start=$(date +%s.%N)
"${timer[@]}" "$tolver" verify --machine samples/machines/matsuura_mc760vx_measured.xml \
  --setup samples/matsuura_setup.txt --cl "$work/sculptured_finish_large.apt" \
  --part "$work/sculptured_part.obj" --tolerance 0.03 --spacing "$spacing" \
  --report-dir "$work/report" > "$work/verify.txt" || true
end=$(date +%s.%N)
grep -E "program|part " "$work/verify.txt" | head -2
awk -v s="$start" -v e="$end" 'BEGIN { printf "verify: %.1f s wall\n", e - s }'
[ -f "$work/time.txt" ] && cat "$work/time.txt"
# The phase table: the "timings_s" object of report.json, largest first.
# (A phase named *_concurrent ran beside others and is not part of the sum.)
sed -n '/"timings_s": {/,/}/p' "$work/report/report.json" | grep -E '^ +"[a-z0-9_]+": [0-9]' | tr -d '",:' |
  awk '{ t[$1] = $2; if ($1 !~ /concurrent/) total += $2 }
       END { for (k in t) printf "  %-26s %7.2f s  %5.1f %%\n", k, t[k], 100 * t[k] / total }' |
  sort -k2 -rn
