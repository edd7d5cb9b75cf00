#!/usr/bin/env bash
# Two builds of `voxfx` side by side on the render rows (issue #36: a refactoring must leave the
# frames' cost unchanged): each demo scene with its default shadows, with every glass method on
# the glass scene, and the deep-shadow demo with clustered deep shadows, at 1280x720 with every
# default (AA, ambient occlusion, sky). Medians of 5 rounds of the time line's total, the two
# builds alternating within a round, and new/base. Usage:
#   bench/compare_render.sh BASE_VOXFX NEW_VOXFX [DATA_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
base="$1" new="$2" data="${3:-$root/data/meshes}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
median() { sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
# The total of a time line in ms ("total 1.24 s" or "total 812.3 ms").
total() { sed -nE 's/.*total ([0-9.]+) (m?s).*/\1 \2/p' | awk '{print $2 == "s" ? $1 * 1000 : $1}'; }
"$new" demo --scenes all --shadows none --meshes "$data" --write-scenes "$out" -o "$out/png" \
  --width 64 --height 36 --supersample 1 -q
dsm="$root/examples/dsm-demo/scene.json"
cases=("tree $out/tree.glb" "bunny $out/bunny.glb" "cgal $out/cgal.glb"
  "glass-exact $out/glass.glb --glass exact" "glass-multi $out/glass.glb --glass multi"
  "glass-two-surface $out/glass.glb --glass two-surface" "glass-frosted $out/glass.glb --glass frosted"
  "dsm-deep-clustered $dsm --shadows deep --clusters 3")
printf '%-20s %10s %10s %9s\n' case "base ms" "new ms" new/base
for spec in "${cases[@]}"; do
  read -r name scene flags <<<"$spec"
  : >"$out/base.t"; : >"$out/new.t"
  for _ in 1 2 3 4 5; do
    for k in base new; do
      exe="$base"; [ "$k" = new ] && exe="$new"
      # shellcheck disable=SC2086
      "$exe" render "$scene" -o "$out/$k.png" --width 1280 --height 720 $flags | total >>"$out/$k.t"
    done
  done
  b="$(median <"$out/base.t")" n="$(median <"$out/new.t")"
  printf '%-20s %10.1f %10.1f %9.3f\n' "$name" "$b" "$n" "$(awk -v b="$b" -v n="$n" 'BEGIN {print n / b}')"
done
