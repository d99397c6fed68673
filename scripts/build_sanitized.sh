#!/usr/bin/env bash
# Configures and builds the sanitizer build in ./build-asan: clang, -O1, AddressSanitizer and
# UndefinedBehaviorSanitizer (undefined behaviour stops the program), and the libFuzzer harnesses
# (tests/fuzz). NDEBUG as in the release build: the sanitizers check the code as it ships (Eigen's
# own debug assertions stop in Eigen 3.4.0's BDCSVD, whose perturbCol0 reads perm(l-1) at l = 0,
# an upstream defect; ASan still reports it if the read leaves the allocation). Usage: scripts/build_sanitized.sh [targets...] (default: everything). The
# compiler's output goes to build-asan/build.log and is shown only when the build fails.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
mkdir -p build-asan
targets=()
for t in "$@"; do targets+=(--target "$t"); done
echo "tolver: building with the sanitizers in build-asan/ ..." >&2
generator=()
if [ ! -f build-asan/CMakeCache.txt ] && command -v ninja > /dev/null; then generator=(-G Ninja); fi
if ! { cmake -S . -B build-asan "${generator[@]}" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
         -DCMAKE_BUILD_TYPE=None "-DCMAKE_CXX_FLAGS=-O1 -gline-tables-only -DNDEBUG" \
         -DTOLVER_FUZZ=ON -DTOLVER_BENCHMARKS=OFF &&
       cmake --build build-asan -j"$(nproc)" "${targets[@]}"; } > build-asan/build.log 2>&1; then
  tail -n 60 build-asan/build.log >&2
  echo "tolver: sanitizer build failed; full log in build-asan/build.log" >&2
  exit 1
fi
