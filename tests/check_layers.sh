#!/bin/bash
# The layers as built (ARCHITECTURE.md): core (numerics < model < kinematics < path < calibration
# < diagnosis; allocation above kinematics) < geometry < io < pipeline < app. Fails when a target
# links a layer above it (links file: cmake/layer_links.cmake) or a source file includes a header
# of a layer above its own.
# Usage: check_layers.sh LINKS_FILE SOURCE_DIR
set -u
links=$1
src=$2
rank() {
  case $1 in
    tolver_core_numerics | core/numerics) echo 1 ;;
    tolver_core_model | core/model) echo 2 ;;
    tolver_core_kinematics | core/kinematics) echo 3 ;;
    tolver_core_path | core/path | tolver_core_allocation | core/allocation) echo 4 ;;
    tolver_core_calibration | core/calibration) echo 5 ;;
    tolver_core_diagnosis | core/diagnosis) echo 6 ;;
    tolver_core) echo 7 ;;
    tolver_geometry | geometry) echo 8 ;;
    tolver_io | io) echo 9 ;;
    tolver_pipeline | pipeline) echo 10 ;;
    tolver | app) echo 11 ;;
    *) echo 0 ;;  # not a tolver layer (Eigen, CGAL, ...)
  esac
}
failed=0
[ -s "$links" ] || { echo "no links file: $links"; exit 1; }
while IFS=: read -r target deps; do
  [ -n "$target" ] || continue
  r=$(rank "$target")
  [ "$r" -gt 0 ] || { echo "unknown target $target"; failed=1; continue; }
  IFS=';' read -ra list <<<"$(echo "$deps" | tr -d ' ')"
  for d in "${list[@]}"; do
    rd=$(rank "$d")
    # allocation and path share a rank but neither may link the other
    if [ "$rd" -gt 0 ] && { [ "$rd" -ge "$r" ] && [ "$d" != "$target" ]; }; then
      if ! { [ "$target" = tolver_core ] && [ "$rd" -lt 7 ]; }; then
        echo "layer violation: $target links $d (a layer at or above its own)"
        failed=1
      fi
    fi
  done
done <"$links"
# Includes: a file of a layer includes no header of a layer above it.
for dir in core/numerics core/model core/kinematics core/path core/calibration core/diagnosis core/allocation geometry io pipeline app; do
  [ -d "$src/$dir" ] || continue
  r=$(rank "$dir")
  while IFS= read -r line; do
    file=${line%%:*}
    inc=$(echo "$line" | sed -E 's/.*#include "([^"]+)".*/\1/')
    top=${inc%%/*}
    if [ "$top" = core ]; then
      sub=${inc#core/}
      layer="core/${sub%%/*}"
    else
      layer=$top
    fi
    ri=$(rank "$layer")
    if [ "$ri" -gt "$r" ] || { [ "$ri" -eq "$r" ] && [ "$layer" != "$dir" ] && [ "$ri" -gt 0 ]; }; then
      echo "layer violation: $file includes $inc"
      failed=1
    fi
  done < <(grep -rHn '#include "' "$src/$dir" --include='*.h' --include='*.cpp' | sed -E 's/^([^:]+):[0-9]+:/\1:/')
done
if [ $failed = 0 ]; then echo "layers: every target and include points down"; fi
exit $failed
