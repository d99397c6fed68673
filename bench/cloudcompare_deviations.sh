#!/usr/bin/env bash
# Point-to-surface deviations: tolver against CloudCompare, the tool a metrologist would use
# instead, on the same points and in the same run.
#   bench/cloudcompare_deviations.sh            (after scripts/build.sh; installs CloudCompare)
# 1. tolver verify on the bundled sample (sculptured part, 0.4 mm samples as verify_benchmark's, ball-end finish on the
#    measured Matsuura) writes the predicted swept surface (swept_predicted.ply) and each
#    sample's deviation (deviations.csv, total_um).
# 2. CloudCompare 2.11 computes the signed cloud-to-mesh distance (C2M) of the same sample points
#    to that surface, on both cores and on one; its own timers ([computeApproxDistances],
#    [ComputeDistances]) give the distance work without the file loading.
# 3. tolver's own distance work on the same points: one sweep (verify_benchmark,
#    BM_SweepSculptured), on both cores and on one (taskset).
# 4. The answers: the largest difference between CloudCompare's distance and tolver's deviation
#    over the samples where both exist.
# Prints each time and tolver's speed as a multiple of CloudCompare's (issue 18's goal: >= 3x).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/bench/install_peers.sh"
tolver="$here/build/app/tolver"
bench="$here/build/bench/verify_benchmark"
[ -x "$tolver" ] && [ -x "$bench" ] || { echo "build first: scripts/build.sh" >&2; exit 1; }
work="$(mktemp -d)"; [ -n "${TOLVER_BENCH_KEEP:-}" ] && echo "files kept in $work" >&2
[ -n "${TOLVER_BENCH_KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
cd "$here"
"$tolver" verify --machine samples/machines/matsuura_mc760vx_measured.xml \
  --setup samples/matsuura_setup.txt --cl samples/sculptured_finish.apt \
  --part samples/sculptured_part.obj --tolerance 0.03 --spacing 0.4 --report-dir "$work/report" > /dev/null || true
[ -f "$work/report/swept_predicted.ply" ] || { echo "tolver verify wrote no swept surface" >&2; exit 1; }
# x y z of every sample with a total deviation, and that deviation (um).
awk -F, '/^#/ || /^sample,/ { next } $11 != "" { print $2, $3, $4 > "'"$work"'/pts.xyz"; print $11 > "'"$work"'/tolver_um.txt" }' \
  "$work/report/deviations.csv"
points=$(wc -l < "$work/pts.xyz")

cc_time() {  # $1: threads; prints the distance computation's seconds
  rm -f "$work"/pts_C2M_DIST*.asc
  (cd "$work" && QT_QPA_PLATFORM=offscreen XDG_RUNTIME_DIR="$work" taskset -c "$2" \
     CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF -C_EXPORT_FMT ASC -PREC 12 \
     -O pts.xyz -O report/swept_predicted.ply -C2M_DIST -MAX_TCOUNT "$1" -SAVE_CLOUDS > cc.log 2>&1)
  awk '/\[computeApproxDistances\] Time:|\[ComputeDistances\] Time:/ { s += $(NF-1) } END { printf "%.3f", s }' "$work/cc.log"
}
sweep_time() {  # $1: cpus for taskset; prints one sweep's seconds
  taskset -c "$1" "$bench" --benchmark_filter=BM_SweepSculptured --benchmark_format=csv 2> /dev/null |
    awk -F, '/BM_SweepSculptured/ { printf "%.3f", $3 / 1000 }'
}
cc2=$(cc_time 2 0,1)
cc1=$(cc_time 1 0)
ours2=$(sweep_time 0,1)
ours1=$(sweep_time 0)
# CloudCompare's last column is the C2M distance (mm), positive on the side the surface's normals
# point to (out of the material); tolver's total is positive where material is left (the design
# point lies outside the cut surface, on its other side): the same number with opposite signs.
# The points are read back from deviations.csv, written to 10 nm.
diff_um=$(paste -d' ' "$work"/pts_C2M_DIST*.asc "$work/tolver_um.txt" |
  awk '{ d = $4 * 1000 + $5; if (d < 0) d = -d; if ($4 !~ /nan/ && d > m) m = d } END { printf "%.3f", m }')
printf "points                         %d (sculptured sample, 0.4 mm)\n" "$points"
printf "CloudCompare C2M, 2 cores      %s s\n" "$cc2"
printf "CloudCompare C2M, 1 core       %s s\n" "$cc1"
printf "tolver sweep, 2 cores          %s s   %sx CloudCompare\n" "$ours2" "$(awk -v a="$cc2" -v b="$ours2" 'BEGIN { printf "%.2f", a / b }')"
printf "tolver sweep, 1 core           %s s   %sx CloudCompare\n" "$ours1" "$(awk -v a="$cc1" -v b="$ours1" 'BEGIN { printf "%.2f", a / b }')"
printf "largest |CloudCompare - tolver| %s um\n" "$diff_um"
