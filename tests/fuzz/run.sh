#!/usr/bin/env bash
# Runs the libFuzzer harnesses (clang, AddressSanitizer + UndefinedBehaviorSanitizer; built in
# build-asan by scripts/build_sanitized.sh, here if missing or stale) each for the given number of
# seconds on its seed corpus (the project's own fixtures and samples) plus what it finds.
# Usage: tests/fuzz/run.sh [seconds per harness] [names]
# A crash leaves crash-* files in build/fuzz/<name>/ and exits non-zero.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
seconds="${1:-30}"
shift || true
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(apt gcode machine setup ballbar zones tolerances probe jobs mesh)
out="$here/build/fuzz"
mkdir -p "$out"
targets=()
for n in "${names[@]}"; do targets+=("fuzz_$n"); done
"$here/scripts/build_sanitized.sh" "${targets[@]}"
declare -A corpus=([apt]="tests/fixtures/cl samples/*.apt" [gcode]="tests/fixtures/gcode samples/gcode/*.nc samples/gcode/*.ngc"
                   [machine]="resources/machines tests/fixtures/machines samples/machines" [setup]="samples/*setup*.txt samples/gcode/*.txt"
                   [ballbar]="samples/ballbar/*.csv" [zones]="samples/sculptured_zones.csv"
                   [tolerances]="resources/allocation" [probe]="samples/matsuura_probed.csv"
                   [jobs]="samples/verify_jobs.csv" [mesh]="tests/fuzz/mesh_corpus")
status=0
for n in "${names[@]}"; do
  bin="$here/build-asan/tests/fuzz/fuzz_$n"
  mkdir -p "$out/$n/corpus"
  for c in ${corpus[$n]}; do
    if [ -d "$here/$c" ]; then cp -n "$here/$c"/* "$out/$n/corpus/" 2>/dev/null || true;
    else cp -n $here/$c "$out/$n/corpus/" 2>/dev/null || true; fi
  done
  echo "fuzz $n: ${seconds} s" >&2
  touch "$out/$n/.started"
  if ! (cd "$out/$n" && "$bin" -max_total_time="$seconds" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
          -print_final_stats=1 corpus > log.txt 2>&1); then
    echo "fuzz $n: FAILED, see $out/$n/log.txt" >&2
    status=1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov: " "$out/$n/log.txt" | tail -3 >&2 || true
  # One line per run, so the totals over many runs can be summed (tests/fuzz/totals.sh).
  execs=$(grep -oE "stat::number_of_executed_units: [0-9]+" "$out/$n/log.txt" | grep -oE "[0-9]+$" || echo 0)
  cov=$(grep -oE "cov: [0-9]+" "$out/$n/log.txt" | tail -1 | grep -oE "[0-9]+$" || echo 0)
  crashes=$(find "$out/$n" -maxdepth 1 -newer "$out/$n/.started" -regextype egrep -regex ".*/(crash|leak|timeout|oom)-.*" | wc -l)
  printf "%s\t%s\t%s\t%s\t%s\t%s\n" "$(date -u +%FT%TZ)" "$n" "$seconds" "$execs" "$cov" "$crashes" >> "$out/history.tsv"
done
exit $status
