#!/usr/bin/env bash
# Builds with clang, -O2, AddressSanitizer and UndefinedBehaviorSanitizer (undefined behaviour
# stops the program):
#   scripts/build_sanitized.sh [targets...]         the test suite, in ./build-asan
#   scripts/build_sanitized.sh --fuzz [targets...]  the libFuzzer harnesses (tests/fuzz), in
#                                                   ./build-fuzz, every target also compiled with
#                                                   libFuzzer's coverage (default: the harnesses)
# Two folders because the coverage instrumentation (a call on every comparison) slows the suite
# 2.6x (Diagnosis.FindsReversal 41 s against 15.6 s) and the harnesses need it; one build was more
# than CI's hour. NDEBUG as in the release build: the sanitizers check the code as it ships
# (Eigen's own debug assertions stop in Eigen 3.4.0's BDCSVD, whose perturbCol0 reads perm(l-1)
# at l = 0, an upstream defect; ASan still reports it if the read leaves the allocation). -O2:
# Eigen's expression templates need the inlining. The compiler's output goes to <folder>/build.log
# and is shown only when the build fails.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
dir=build-asan
fuzz=OFF
if [ "${1:-}" = "--fuzz" ]; then
  dir=build-fuzz
  fuzz=ON
  shift
fi
targets=()
for t in "$@"; do targets+=(--target "$t"); done
if [ "$fuzz" = ON ] && [ ${#targets[@]} -eq 0 ]; then
  for n in apt gcode machine setup ballbar zones tolerances probe jobs mesh balls scene commands; do targets+=(--target "fuzz_$n"); done
fi
mkdir -p "$dir"
echo "tolver: building with the sanitizers in $dir/ ..." >&2
generator=()
if [ ! -f "$dir/CMakeCache.txt" ] && command -v ninja > /dev/null; then generator=(-G Ninja); fi
if ! { cmake -S . -B "$dir" "${generator[@]}" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
         -DCMAKE_BUILD_TYPE=None "-DCMAKE_CXX_FLAGS=-O2 -gline-tables-only -DNDEBUG" \
         -DTOLVER_SANITIZE=ON -DTOLVER_FUZZ="$fuzz" -DTOLVER_BENCHMARKS=OFF &&
       cmake --build "$dir" -j"$(nproc)" "${targets[@]}"; } > "$dir/build.log" 2>&1; then
  tail -n 60 "$dir/build.log" >&2
  echo "tolver: sanitizer build failed; full log in $dir/build.log" >&2
  exit 1
fi
