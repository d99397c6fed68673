#!/usr/bin/env bash
# The commands as a user runs them (issue 36): wall time, CPU time (user + system) and peak memory
# of each, one command at a time, with the machine and its load. The README's and
# docs/benchmarks.md's end-to-end table is this script's output.
#   bench/end_to_end.sh [--quick]        (after scripts/build.sh; --quick: the smaller half)
# The inputs are made here, from the repository's samples (nothing downloaded):
#   * a 1.01 M-point five-axis APT program (the sculptured finish's 9 801 points repeated 103
#     times, 73 MB) and a 3.03 M-point one (309 times, 218 MB); predict on both, with the
#     per-point table and without (--no-errors), on both cores and on one (taskset -c 0);
#   * ball-bar readings simulated on the measured Matsuura: 600 poses, and a 2 000-pose plan
#     measured five times (10 000 and more readings); calibrate on both, diagnose on the second;
#   * compensate on both programs and on a 1.03 M-line five-axis G-code program (LinuxCNC's boat);
#   * verify at scale: bench/verify_large.sh's part and 120 802-point finish at 0.115 mm;
#   * setup on the largest program of ../shared/data/corpus, when that directory is there.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tolver="$here/build/app/tolver"
make_samples="$here/build/tools/make_samples"
[ -x "$tolver" ] && [ -x "$make_samples" ] || { echo "build first: scripts/build.sh" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (Debian package time)" >&2; exit 1; }
quick=0
[ "${1:-}" = "--quick" ] && quick=1
work="$(mktemp -d)"
[ -n "${TOLVER_BENCH_KEEP:-}" ] && echo "files kept in $work" >&2
[ -n "${TOLVER_BENCH_KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
cd "$here"
m_nominal=resources/machines/matsuura_mc760vx.xml
m_measured=samples/machines/matsuura_mc760vx_measured.xml

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), \
$(awk '/MemTotal/ { printf "%.1f GB", $2 / 1048576 }' /proc/meminfo)"
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg) (1, 5, 15 min)"
echo
printf '| %-62s | %8s | %8s | %9s |\n' "command" "wall s" "CPU s" "peak MB"
printf '|%s|%s|%s|%s|\n' "$(printf -- '-%.0s' {1..64})" "----------" "----------" "-----------"

# run LABEL COMMAND...: one row (the command's output goes to $work/out.txt; a failure is named).
run() {
  local label="$1"
  shift
  if ! /usr/bin/time -f "%e %U %S %M" -o "$work/time.txt" "$@" > "$work/out.txt" 2>&1; then
    echo "| $label | failed: $(grep -m1 'error' "$work/out.txt" || tail -1 "$work/out.txt") |"
    return
  fi
  awk -v l="$label" '{ printf "| %-62s | %8.2f | %8.2f | %9.0f |\n", l, $1, $2 + $3, $4 / 1024 }' \
    "$work/time.txt"
}

# Programs: the sculptured finish's motion repeated (header once, FINI once).
repeat_program() {
  local times="$1" out="$2"
  awk -v n="$times" 'NR <= 9 { head = head $0 "\n"; next } /^FINI/ { next } { body = body $0 "\n" }
    END { printf "%s", head; for (k = 0; k < n; ++k) printf "%s", body; print "FINI" }' \
    samples/sculptured_finish.apt > "$out"
}
repeat_program 103 "$work/finish_1M.apt"
sizes=(1M)
if [ "$quick" = 0 ]; then
  repeat_program 309 "$work/finish_3M.apt"
  sizes+=(3M)
fi
for s in "${sizes[@]}"; do
  p="$work/finish_$s.apt"
  mb=$(du -m "$p" | cut -f1)
  base=(predict --machine "$m_measured" --setup samples/matsuura_setup.txt --cl "$p" --quiet)
  run "predict, $s points ($mb MB), with the table" "$tolver" "${base[@]}" -o "$work/p.apt"
  run "predict, $s points, predicted CL alone" "$tolver" "${base[@]}" --no-errors -o "$work/p.apt"
  if command -v taskset > /dev/null; then
    run "predict, $s points, with the table, one core" taskset -c 0 "$tolver" "${base[@]}" \
      -o "$work/p.apt"
    run "predict, $s points, CL alone, one core" taskset -c 0 "$tolver" "${base[@]}" \
      --no-errors -o "$work/p.apt"
  fi
done

# Compensate (in blocks: its memory does not grow with the program).
for s in "${sizes[@]}"; do
  run "compensate, $s points" "$tolver" compensate --machine "$m_measured" \
    --setup samples/matsuura_setup.txt --cl "$work/finish_$s.apt" -o "$work/c.apt"
done
# G-code: LinuxCNC's five-axis boat (TCP, arcs) repeated to 1.03 M lines, on its nominal machine.
boat=samples/gcode/boat-xyzac.ngc
{ head -13 "$boat"; for k in $(seq 1 555); do sed -n '14,1874p' "$boat"; done
  sed -n '1875,1881p' "$boat"; } > "$work/boat_1M.ngc"
run "compensate, 1.03M-line G-code (boat, TCP), nominal machine" "$tolver" compensate \
  --machine resources/machines/linuxcnc_xyzac_trt.xml --setup samples/gcode/linuxcnc_setup.txt \
  --nc "$work/boat_1M.ngc" -o "$work/c.ngc"

# Ball-bar readings.
"$tolver" plan-ballbar --machine "$m_nominal" --poses 600 --seed 3 -o "$work/plan600.csv" > /dev/null
"$tolver" simulate-ballbar --machine "$m_measured" --plan "$work/plan600.csv" --noise-um 0.5 \
  --seed 3 -o "$work/r600.csv" > /dev/null
n600=$(grep -vc '^#\|^setup' "$work/r600.csv")
run "calibrate, $n600 readings" "$tolver" calibrate --machine "$m_nominal" \
  --readings "$work/r600.csv" -o "$work/id600.xml"
if [ "$quick" = 0 ]; then
  "$tolver" plan-ballbar --machine "$m_nominal" --poses 2000 --seed 4 -o "$work/plan2000.csv" \
    > /dev/null
  for seed in 1 2 3 4 5; do
    "$tolver" simulate-ballbar --machine "$m_measured" --plan "$work/plan2000.csv" \
      --noise-um 0.5 --seed "$seed" -o "$work/r$seed.csv" > /dev/null
  done
  {
    grep -v '^#' "$work/r1.csv"
    for seed in 2 3 4 5; do grep -v '^#\|^setup' "$work/r$seed.csv"; done
  } > "$work/r10k.csv"
  n10k=$(grep -vc '^#\|^setup' "$work/r10k.csv")
  run "calibrate, $n10k readings (a 2 000-pose plan measured 5 times)" "$tolver" calibrate \
    --machine "$m_nominal" --readings "$work/r10k.csv" -o "$work/id10k.xml"
  run "diagnose, $n10k readings" "$tolver" diagnose --machine "$m_nominal" \
    --readings "$work/r10k.csv" -o "$work/d10k.xml" --report-dir "$work/d10k"
  if command -v taskset > /dev/null; then
    run "diagnose, $n10k readings, one core" taskset -c 0 "$tolver" diagnose \
      --machine "$m_nominal" --readings "$work/r10k.csv" -o "$work/d10k.xml" \
      --report-dir "$work/d10k"
  fi

  # Verify at scale (bench/verify_large.sh's inputs).
  "$make_samples" --large "$work" > /dev/null
  run "verify, 120 802 CL points, 0.115 mm spacing (1.06 M samples)" "$tolver" verify \
    --machine "$m_measured" --setup samples/matsuura_setup.txt \
    --cl "$work/sculptured_finish_large.apt" --part "$work/sculptured_part.obj" \
    --tolerance 0.03 --spacing 0.115 --quiet --report-dir "$work/report"
fi

# Setup on the largest program of the shared corpus, when there.
corpus="$here/../shared/data/corpus"
if [ -d "$corpus" ]; then
  largest=$(ls -S "$corpus"/*.apt "$corpus"/*.cls "$corpus"/*.ncl "$corpus"/*.clsf 2> /dev/null |
    head -1 || true)
  if [ -n "$largest" ]; then
    run "setup, $(basename "$largest") ($(du -m "$largest" | cut -f1) MB)" "$tolver" setup \
      --machine "$m_nominal" --cl "$largest" --gauge-length 100 -o "$work/setup.txt"
  fi
fi
echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
