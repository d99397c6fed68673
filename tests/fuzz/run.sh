#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang, AddressSanitizer + UndefinedBehaviorSanitizer) into
# build/fuzz and runs each for the given number of seconds on its seed corpus (the project's own
# fixtures and samples) plus what it finds. Usage: tests/fuzz/run.sh [seconds per harness] [names]
# Needs clang and its runtime (Debian: clang, libclang-rt-14-dev). A crash leaves crash-* files in
# build/fuzz/<name>/ and exits non-zero.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
seconds="${1:-30}"
shift || true
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(apt gcode machine setup ballbar zones tolerances probe jobs)
out="$here/build/fuzz"
mkdir -p "$out/obj"
flags=(-std=c++20 -O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
       -I"$here" -I/usr/include/eigen3 -DTOLVER_SOURCE_DIR="\"$here\"" -w)
sources=("$here"/core/*/*.cpp "$here"/io/common/text_util.cpp "$here"/io/common/io_error.cpp "$here"/io/program/apt_reader.cpp
         "$here"/io/program/gcode_reader.cpp "$here"/io/machine/machine_file.cpp "$here"/io/program/setup_file.cpp
         "$here"/io/machine/ballbar_file.cpp "$here"/io/machine/zone_file.cpp "$here"/io/machine/tolerance_file.cpp
         "$here"/io/program/probe_file.cpp "$here"/io/program/jobs_file.cpp "$here"/geometry/tolerance_zone.cpp)
objs=()
# An object is rebuilt when its source or any header is newer (a header change reaches every
# object that includes it).
newest_header=$(find "$here/core" "$here/io" "$here/geometry" -name '*.h' -printf '%T@ %p\n' | sort -n | tail -1 | cut -d' ' -f2)
for s in "${sources[@]}"; do
  case "$s" in *tolerance_allocation.cpp) continue ;; esac
  o="$out/obj/$(basename "$(dirname "$s")")_$(basename "$s" .cpp).o"
  if [ ! -f "$o" ] || [ "$s" -nt "$o" ] || [ "$newest_header" -nt "$o" ]; then clang++ "${flags[@]}" -c "$s" -o "$o"; fi
  objs+=("$o")
done
declare -A target=([apt]=1 [gcode]=2 [machine]=3 [setup]=4 [ballbar]=5 [zones]=6 [tolerances]=7 [probe]=8 [jobs]=9)
declare -A corpus=([apt]="tests/fixtures/cl samples/*.apt" [gcode]="tests/fixtures/gcode samples/gcode/*.nc samples/gcode/*.ngc"
                   [machine]="resources/machines tests/fixtures/machines samples/machines" [setup]="samples/*setup*.txt samples/gcode/*.txt"
                   [ballbar]="samples/ballbar/*.csv" [zones]="samples/sculptured_zones.csv"
                   [tolerances]="resources/allocation" [probe]="samples/matsuura_probed.csv"
                   [jobs]="samples/verify_jobs.csv")
status=0
for n in "${names[@]}"; do
  bin="$out/fuzz_$n"
  clang++ "${flags[@]/-fsanitize=fuzzer-no-link,address,undefined/-fsanitize=fuzzer,address,undefined}" \
    -DTOLVER_FUZZ_TARGET="${target[$n]}" "$here/tests/fuzz/fuzz_readers.cpp" "${objs[@]}" -ltinyxml2 -o "$bin"
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
