#!/usr/bin/env bash
# Fuzzes each named harness in 10-minute runs of tests/fuzz/run.sh until its recorded CPU time
# (build/fuzz/history.tsv, all runs so far) reaches the target, as many harnesses at a time as
# TOLVER_FUZZ_JOBS (default: the cores), at the lowest priority so that other work on the
# machine goes first. A finding stops that harness's loop and is reported at the end.
# Usage: tests/fuzz/campaign.sh <CPU hours per harness> [names]
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
target_s=$(awk -v h="${1:?CPU hours per harness}" 'BEGIN { printf "%d", h * 3600 }')
shift
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(apt gcode machine setup ballbar zones tolerances probe jobs mesh)
history="$here/build/fuzz/history.tsv"
"$here/scripts/build_sanitized.sh" --fuzz || exit 1
cpu_so_far() { awk -F'\t' -v h="$1" '$2 == h { s += $3 } END { printf "%d", s }' "$history" 2>/dev/null || echo 0; }
one() {
  local n="$1"
  while [ "$(cpu_so_far "$n")" -lt "$target_s" ]; do
    TOLVER_FUZZ_NO_BUILD=1 TOLVER_FUZZ_JOBS=1 nice -n 19 "$here/tests/fuzz/run.sh" 600 "$n" || return 1
  done
}
jobs_max="${TOLVER_FUZZ_JOBS:-$(nproc)}"
failed=()
for n in "${names[@]}"; do
  one "$n" &
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
done
wait
status=0
for n in "${names[@]}"; do
  if [ -f "$here/build/fuzz/$n/.failed" ]; then echo "fuzz $n: a finding, see build/fuzz/$n/" >&2; status=1; fi
done
"$here/tests/fuzz/totals.sh"
exit $status
