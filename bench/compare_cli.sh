#!/usr/bin/env bash
# Two builds of `voxfx` side by side (issue #39): the voxelize step and the total of the time line,
# medians of 5 rounds in which the two alternate, and whether the two .binvox files are the same
# bytes; then .vdb against .binvox for both. Usage:
#   bench/compare_cli.sh BASE_VOXFX NEW_VOXFX [DATA_DIR]
set -euo pipefail
base="$1" new="$2" data="${3:-data/meshes}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
median() { sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
step() { sed -E 's/.*voxelize ([0-9.]+) ms.*/\1/'; }
total() { sed -E 's/.*total ([0-9.]+) ms.*/\1/'; }
run() { "$1" voxelize "$data/$2.off" -r "$3" -o "$4" | grep '^time'; }
for spec in "bunny00 512" "bunny00 1024" "armadillo 512" "armadillo 1024"; do
  read -r mesh res <<<"$spec"
  for k in base.binvox new.binvox base.vdb new.vdb; do : >"$out/$k.step"; : >"$out/$k.total"; done
  for _ in 1 2 3 4 5; do
    for k in base.binvox new.binvox base.vdb new.vdb; do
      exe="$base"; [ "${k%%.*}" = new ] && exe="$new"
      line="$(run "$exe" "$mesh" "$res" "$out/$k")"
      step <<<"$line" >>"$out/$k.step"
      total <<<"$line" >>"$out/$k.total"
    done
  done
  same=different; cmp -s "$out/base.binvox" "$out/new.binvox" && same=identical
  printf '%s %s voxelize (binvox): base %s new %s | total: base %s new %s | %s\n' "$mesh" "$res" \
    "$(median <"$out/base.binvox.step")" "$(median <"$out/new.binvox.step")" \
    "$(median <"$out/base.binvox.total")" "$(median <"$out/new.binvox.total")" "$same"
  printf '%s %s voxelize (vdb): base %s new %s | total: base %s new %s\n' "$mesh" "$res" \
    "$(median <"$out/base.vdb.step")" "$(median <"$out/new.vdb.step")" \
    "$(median <"$out/base.vdb.total")" "$(median <"$out/new.vdb.total")"
done
