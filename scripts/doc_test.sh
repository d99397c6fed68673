#!/usr/bin/env bash
# The doc-test: every fenced block opened with "```sh runnable" in the README and docs/ runs, in
# order of the blocks, each under bash -e -o pipefail, in a scratch directory per file where
# build/, samples/, resources/ and tests/ are the repository's (so the commands run as a user
# types them from a clone; out/ is the scratch's own, and a later block of the same file may use
# what an earlier one wrote). A block that exits non-zero fails the test, naming its file and
# line.
# Usage: scripts/doc_test.sh SOURCE_DIR BUILD_DIR [FILE...]   (default: README.md docs/*.md)
set -uo pipefail
src=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
shift 2
if [ $# -gt 0 ]; then files=("$@"); else files=("$src/README.md" "$src"/docs/*.md); fi
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
blocks=0
failed=0
for f in "${files[@]}"; do
  work="$scratch/$(basename "$f" .md)"
  mkdir -p "$work"
  ln -s "$build" "$work/build"
  for d in samples resources tests; do ln -s "$src/$d" "$work/$d"; done
  # One script per block: blocks/<n>.sh, and its file:line in blocks/<n>.where.
  rm -rf "$work/blocks" && mkdir "$work/blocks"
  awk -v dir="$work/blocks" -v file="${f#"$src"/}" '
    /^```sh runnable[ \t]*$/ { n++; inblock = 1; out = dir "/" n ".sh"; print file ":" NR > (dir "/" n ".where"); next }
    inblock && /^```/ { inblock = 0; close(out); next }
    inblock { print > out }
  ' "$f"
  for s in $(ls "$work/blocks"/*.sh 2>/dev/null | sort -V); do
    blocks=$((blocks + 1))
    where=$(cat "${s%.sh}.where")
    start=$(date +%s%N)
    if (cd "$work" && bash -e -o pipefail "$s") >"$work/log" 2>&1; then
      ms=$((($(date +%s%N) - start) / 1000000))
      printf 'ok    %-28s %4d.%d s\n' "$where" $((ms / 1000)) $((ms % 1000 / 100))
    else
      failed=$((failed + 1))
      echo "FAIL  $where: the block exits non-zero; its last lines:"
      tail -n 15 "$work/log" | sed 's/^/      /'
    fi
  done
done
echo "doc-test: $blocks runnable blocks, $failed failed"
[ "$blocks" -gt 0 ] && [ "$failed" -eq 0 ]
