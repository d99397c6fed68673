#!/usr/bin/env bash
# The project's C++ style (.clang-format: Google, 100 columns), checked by clang-format 14.
#   scripts/check_format.sh            every tracked C++ file (CI runs this: the tree is formatted)
#   scripts/check_format.sh BASE       the files changed since the commit BASE (e.g. origin/main)
#   scripts/check_format.sh --fix ...  format them in place instead
# Exit 1 naming each file and line that clang-format would change.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
fix=0
if [ "${1:-}" = --fix ]; then fix=1; shift; fi
if [ $# -gt 0 ]; then
  mapfile -t files < <(git diff --name-only --diff-filter=d "$1" -- '*.cpp' '*.h' | grep -v '^tests/fixtures/' || true)
elif git rev-parse --git-dir >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.h' | grep -v '^tests/fixtures/')
else  # not a clone (an unpacked archive): the source folders
  mapfile -t files < <(find app bench core geometry io pipeline tests tools -name '*.cpp' -o -name '*.h' |
                       grep -v '^tests/fixtures/' | sort)
fi
[ ${#files[@]} -gt 0 ] || { echo "format: no C++ files to check"; exit 0; }
if [ $fix = 1 ]; then
  clang-format -i "${files[@]}"
  echo "format: ${#files[@]} files formatted"
  exit 0
fi
if clang-format --dry-run --Werror "${files[@]}" 2>/tmp/format.$$; then
  echo "format: ${#files[@]} files as clang-format writes them"
  rm -f /tmp/format.$$
else
  grep -E '^[^ ].*(warning|error): code should' /tmp/format.$$ | sed -E 's/: (warning|error): code should be clang-formatted.*//' | head -n 40
  echo "format: $(grep -cE '(warning|error): code should' /tmp/format.$$) places differ from clang-format (scripts/check_format.sh --fix)"
  rm -f /tmp/format.$$
  exit 1
fi
