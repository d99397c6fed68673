#!/usr/bin/env bash
# Runs the libFuzzer harnesses (clang, AddressSanitizer + UndefinedBehaviorSanitizer; built in
# build-fuzz by scripts/build_sanitized.sh --fuzz, here if missing or stale) each for the given
# number of seconds on its seed corpus (the project's own fixtures and samples) plus what it
# finds, as many at a time as there are cores (TOLVER_FUZZ_JOBS to change it).
# Usage: tests/fuzz/run.sh [seconds per harness] [names]; TOLVER_FUZZ_SEED fixes libFuzzer's seed.
# A crash leaves crash-* files in build/fuzz/<name>/ and exits non-zero.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
seconds="${1:-30}"
shift || true
names=("$@")
# The default list (CI's): every harness, the part scenes (glTF, 3MF) and the commands included.
[ ${#names[@]} -eq 0 ] && names=(apt gcode machine setup ballbar zones tolerances probe jobs mesh balls scene measured commands)
out="$here/build/fuzz"
# As for the sanitized suite (scripts/run_sanitized.sh): leaks are checked (LeakSanitizer), with
# tests/lsan.supp naming the third-party libraries that keep allocations to the end by design.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:intercept_tls_get_addr=0}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$here/tests/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
mkdir -p "$out"
# TOLVER_FUZZ_COMMANDS_FROM_ASAN=1 (CI): the commands harness as built in build-asan (its own file
# instrumented for coverage, the libraries not; tests/CMakeLists.txt), not built again here.
from_asan="${TOLVER_FUZZ_COMMANDS_FROM_ASAN:-}"
targets=()
for n in "${names[@]}"; do
  [ "$n" = commands ] && [ -n "$from_asan" ] && continue
  targets+=("fuzz_$n")
done
# TOLVER_FUZZ_NO_BUILD=1: use the harnesses as built (several runs at once share build-fuzz/).
[ -n "${TOLVER_FUZZ_NO_BUILD:-}" ] || [ ${#targets[@]} -eq 0 ] ||
  "$here/scripts/build_sanitized.sh" --fuzz "${targets[@]}"
declare -A corpus=([apt]="tests/fixtures/cl samples/*.apt" [gcode]="tests/fixtures/gcode tests/fuzz/gcode_corpus samples/gcode/*.nc samples/gcode/*.ngc"
                   [machine]="resources/machines tests/fixtures/machines samples/machines" [setup]="samples/*setup*.txt samples/gcode/*.txt"
                   [ballbar]="samples/ballbar/*.csv" [zones]="samples/sculptured_zones.csv"
                   [tolerances]="resources/allocation" [probe]="samples/matsuura_probed.csv"
                   [jobs]="samples/verify_jobs.csv" [mesh]="tests/fuzz/mesh_corpus"
                   [scene]="tests/fuzz/scene_corpus" [balls]="tests/fuzz/balls_corpus"
                   [measured]="samples/measured/cmm_points.csv tests/fuzz/measured_corpus"
                   [commands]="tests/fuzz/commands_corpus")
# One harness: its corpus seeded, its run, one line in history.tsv; a failure leaves a file.
run_one() {
  local n="$1"
  local bin="$here/build-fuzz/tests/fuzz/fuzz_$n"
  # The time budget of one input: 10 s; the commands' 30 s, since a whole command (a calibration,
  # an identifiability analysis) runs 35 to 60 times slower under ASan and coverage than released
  # (0.35 s released is 12 s there): about 1 s of a user's time.
  local limit=10
  [ "$n" = commands ] && limit=30
  [ "$n" = commands ] && [ -n "$from_asan" ] && bin="$here/build-asan/tests/fuzz_commands"
  mkdir -p "$out/$n/corpus"
  for c in ${corpus[$n]}; do
    if [ -d "$here/$c" ]; then cp -n "$here/$c"/* "$out/$n/corpus/" 2>/dev/null || true;
    else cp -n $here/$c "$out/$n/corpus/" 2>/dev/null || true; fi
  done
  touch "$out/$n/.started"
  rm -f "$out/$n/.failed"
  local t0=$SECONDS
  # The CPU time it used (user + system), which is what the totals count: a harness run at a
  # low priority beside other work gets less than the wall time.
  local TIMEFORMAT='%3U %3S'
  if ! { time (cd "$out/$n" && "$bin" -max_total_time="$seconds" -max_len=65536 -timeout="$limit" -rss_limit_mb=2048 \
          -print_final_stats=1 ${TOLVER_FUZZ_SEED:+-seed=$TOLVER_FUZZ_SEED} corpus > log.txt 2>&1); } 2> "$out/$n/cpu.txt"; then
    touch "$out/$n/.failed"
  fi
  # A timeout whose input runs within the limit on replay was the process being paused (SIGSTOP
  # while a benchmark ran, a suspended machine: libFuzzer's timer counts wall time). Its input
  # is kept aside in spurious/ and the run is not a finding.
  if [ -f "$out/$n/.failed" ]; then
    local real=0 found=0 f
    while read -r f; do
      found=1
      case "$f" in
        */timeout-*)
          if (cd "$out/$n" && timeout "$limit" "$bin" "$f" > /dev/null 2>&1); then
            mkdir -p "$out/$n/spurious" && mv "$f" "$out/$n/spurious/"
          else
            real=1
          fi ;;
        *) real=1 ;;
      esac
    done < <(find "$out/$n" -maxdepth 1 -newer "$out/$n/.started" -regextype egrep -regex ".*/(crash|leak|timeout|oom)-.*")
    [ "$found" = 1 ] && [ "$real" = 0 ] && rm -f "$out/$n/.failed"
  fi
  # One line per run, so the totals over many runs can be summed (tests/fuzz/totals.sh).
  local execs cov crashes
  execs=$(grep -oE "stat::number_of_executed_units: [0-9]+" "$out/$n/log.txt" | tail -1 | grep -oE "[0-9]+$" || echo 0)
  cov=$(grep -oE "cov: [0-9]+" "$out/$n/log.txt" | tail -1 | grep -oE "[0-9]+$" || echo 0)
  crashes=$(find "$out/$n" -maxdepth 1 -newer "$out/$n/.started" -regextype egrep -regex ".*/(crash|leak|timeout|oom)-.*" | wc -l)
  # Columns: when, harness, CPU seconds, executions, coverage, crash files, wall seconds (a
  # finding stops it before the time asked for).
  local cpu
  cpu=$(awk 'NF >= 2 { c = $1 + $2 } END { printf "%d", c + 0.5 }' "$out/$n/cpu.txt")
  printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\n" "$(date -u +%FT%TZ)" "$n" "$cpu" "$execs" "$cov" "$crashes" \
    "$((SECONDS - t0))" >> "$out/history.tsv"
  printf "fuzz %-10s %4s s  %9s executions  coverage %5s  %s\n" "$n" "$seconds" "$execs" "$cov" \
    "$([ -f "$out/$n/.failed" ] && echo "FAILED, see $out/$n/log.txt" || echo ok)" >&2
}
jobs_max="${TOLVER_FUZZ_JOBS:-$(nproc)}"
for n in "${names[@]}"; do
  run_one "$n" &
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
done
wait
status=0
for n in "${names[@]}"; do
  [ -f "$out/$n/.failed" ] || continue
  status=1
  # What a failure was, said where CI shows it (the log stays on the machine that ran it): the
  # sanitizer's or libFuzzer's own lines, and each input it left, in base64 when small, so that
  # it can be replayed elsewhere (base64 -d > input; build-fuzz/tests/fuzz/fuzz_<name> input).
  {
    echo "fuzz $n: what it reported (whole log: $out/$n/log.txt)"
    grep -E "^==[0-9]+==|^SUMMARY|^(ERROR|MS):|^    #[0-9] " "$out/$n/log.txt" | head -24 | sed 's/^/  /' || true
    find "$out/$n" -maxdepth 1 -newer "$out/$n/.started" -regextype egrep \
      -regex ".*/(crash|leak|timeout|oom)-.*" | while read -r f; do
      echo "  input $(basename "$f"), $(stat -c %s "$f") bytes"
      if [ "$(stat -c %s "$f")" -le 16384 ]; then echo "  base64: $(base64 -w0 "$f")"; fi
    done || true
  } >&2
done
exit $status
