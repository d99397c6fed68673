#!/usr/bin/env bash
# Configures and builds tolver in ./build (Release). The compiler's output goes to
# build/build.log and is shown only when the build fails.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
build_type="${TOLVER_BUILD_TYPE:-Release}"
mkdir -p build
echo "tolver: building ($build_type) in build/ ..." >&2
# Ninja when there (it compiles the layers' libraries in parallel; make builds them one by one),
# unless build/ was configured with another generator.
generator=()
if [ ! -f build/CMakeCache.txt ] && command -v ninja > /dev/null; then generator=(-G Ninja); fi
if ! { cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE="$build_type" &&
       cmake --build build -j"$(nproc)"; } > build/build.log 2>&1; then
  tail -n 60 build/build.log >&2
  echo "tolver: build failed; full log in build/build.log" >&2
  exit 1
fi
