#!/usr/bin/env bash
# Sums the fuzzing runs recorded by tests/fuzz/run.sh in build/fuzz/history.tsv:
# per harness, CPU time, executions, the largest coverage seen and the crash files left.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
awk -F'\t' '{ s[$2]+=$3; e[$2]+=$4; if ($5>c[$2]) c[$2]=$5; k[$2]=$6; n[$2]++ }
  END { for (h in s) printf "%-11s %5d %9.2f %13d %6d %7d\n", h, n[h], s[h]/3600, e[h], c[h], k[h] }' \
  "$here/build/fuzz/history.tsv" | sort | { printf "%-11s %5s %9s %13s %6s %7s\n" harness runs "CPU h" executions cov crashes; cat; }
