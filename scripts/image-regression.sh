#!/usr/bin/env bash
# Renders a fixed set of images and grids with one voxfx binary, so that a refactoring can show
# that every picture and grid the CLI produces is unchanged, pixel for pixel and bit for bit:
#
#   scripts/image-regression.sh OLD/voxfx before/      # e.g. a build of main
#   scripts/image-regression.sh build/voxfx after/
#   scripts/image-regression.sh --compare before/ after/   # a differing .pfm: by how much (pfm-diff.py)
#
# The set: every demo scene (tree, bunny, cgal, glass) with every shadow kind that renders it,
# every glass method, the jade dragon, the deep-shadow demo (plain, clustered, fixed storage, no empty-space
# skipping, supersampled; the CT skull and smoke as volumes), and grids of every voxelization
# mode and fill.
# Images are written as PFM (linear floats: no sRGB rounding hides a change) at a small size;
# the run takes seconds on 2 cores. Needs the test data (scripts/fetch-data.sh).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"

if [ "${1-}" = "--compare" ]; then
  [ $# -eq 3 ] || { echo "usage: $0 --compare DIR_A DIR_B" >&2; exit 2; }
  a="$2" b="$3" bad=0 n=0
  while IFS= read -r name; do
    n=$((n + 1))
    if [ ! -f "$b/$name" ]; then
      echo "missing in $b: $name"; bad=$((bad + 1))
    elif ! cmp -s "$a/$name" "$b/$name"; then
      case "$name" in
        *.pfm) echo "differs: $name: $("$root/scripts/pfm-diff.py" "$a/$name" "$b/$name" 2>&1)" ;;
        *) echo "differs: $name" ;;
      esac
      bad=$((bad + 1))
    fi
  done < <(cd "$a" && find . -type f ! -name '*.log' | sort)
  while IFS= read -r name; do
    [ -f "$a/$name" ] || { echo "only in $b: $name"; bad=$((bad + 1)); }
  done < <(cd "$b" && find . -type f ! -name '*.log' | sort)
  echo "$n files compared, $bad differ"
  [ "$bad" -eq 0 ]
  exit
fi

[ $# -eq 2 ] || { echo "usage: $0 VOXFX_BINARY OUT_DIR | --compare DIR_A DIR_B" >&2; exit 2; }
bin="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
out="$(mkdir -p "$2" && cd "$2" && pwd)"
data="$root/data/meshes"
[ -f "$data/bunny00.off" ] || { echo "no test data: run scripts/fetch-data.sh" >&2; exit 1; }
scenes="$out/scenes"
mkdir -p "$scenes"
log="$out/run.log"
: >"$log"
# Each command's exit status and messages are outputs too ($out/status), so a case that is refused
# (shadow volumes on open casters) must stay refused with the same message.
status="$out/status"
: >"$status"
run() {
  echo "+ $*" >>"$log"
  local rc=0 msg
  msg="$("$@" 2>&1)" || rc=$?
  printf '%s\n' "$msg" >>"$log"
  printf '%s -> %d %s\n' "${*:2:3}" "$rc" "$(printf '%s' "$msg" | grep -i error)" |
    sed -e "s|$out/||g" -e "s|$root/||g" >>"$status"
}

# The demo scenes as glTF (their geometry is part of what must not change), then each rendered.
run "$bin" demo --scenes all --shadows none --meshes "$data" --write-scenes "$scenes" -o "$scenes/png" \
  --width 64 --height 36 --supersample 1 -q
# The filmic curve named: .pfm is linear by default since #37, and a build from before it wrote
# the curve; naming it keeps the set comparable across that change.
size=(--width 200 --height 112 --tone-map filmic)
for s in tree bunny cgal glass; do
  for k in none map transmittance absorption translucency exact deep; do
    run "$bin" render "$scenes/$s.glb" -o "$out/$s-$k.pfm" "${size[@]}" --shadows "$k" -q
  done
done
for s in bunny cgal glass; do
  run "$bin" render "$scenes/$s.glb" -o "$out/$s-volumes.pfm" "${size[@]}" --shadows volumes -q
done
run "$bin" render "$scenes/tree.glb" -o "$out/tree-transmittance-local-bilinear.pfm" "${size[@]}" \
  --shadows transmittance --slicing local --bilinear -q
run "$bin" render "$scenes/tree.glb" -o "$out/tree-transmittance-conservative.pfm" "${size[@]}" \
  --shadows transmittance --voxel-mode conservative -q
run "$bin" render "$scenes/bunny.glb" -o "$out/bunny-map-ss2.pfm" "${size[@]}" --supersample 2 --pcf 2 -q
for g in exact multi two-surface frosted; do
  run "$bin" render "$scenes/glass.glb" -o "$out/glass-$g.pfm" "${size[@]}" --glass "$g" --glass-grid 96 -q
done
run "$bin" render "$scenes/glass.glb" -o "$out/glass-multi-transmittance.pfm" "${size[@]}" --glass multi \
  --glass-grid 96 --shadows transmittance -q

# The jade dragon (a translucent solid seen through, #37: blurred by the matter crossed).
for j in scene translucent; do
  run "$bin" render "$root/examples/jade-dragon/$j.json" -o "$out/jade-$j.pfm" "${size[@]}" --shadows translucency -q
done

# The deep-shadow demo: mixed meshes, volumes and Boolean shapes.
dsm="$root/examples/dsm-demo/scene.json"
for k in none map deep volumes exact; do
  run "$bin" render "$dsm" -o "$out/dsm-$k.pfm" "${size[@]}" --shadows "$k" -q
done
run "$bin" render "$dsm" -o "$out/dsm-deep-clustered.pfm" "${size[@]}" --shadows deep --clusters 3 -q
run "$bin" render "$dsm" -o "$out/dsm-deep-fixed.pfm" "${size[@]}" --shadows deep --dsm-storage fixed \
  --dsm-resolution 256 --epsilon 0.02 -q
run "$bin" render "$dsm" -o "$out/dsm-deep-noskip.pfm" "${size[@]}" --shadows deep --no-empty-space-skipping -q

run "$bin" render "$dsm" -o "$out/dsm-deep-ss2.pfm" --width 320 --height 180 --tone-map filmic --supersample 2 --shadows deep -q

# Grids: every mode and fill on the bunny and the (open) dragon.
for m in surface conservative solid solid-conservative interior; do
  run "$bin" voxelize "$data/bunny00.off" -o "$out/bunny-$m.binvox" -r 96 --mode "$m" -q
done
for f in parity flood vote winding gwn auto; do
  run "$bin" voxelize "$data/ChineseDragon-10kv.off" -o "$out/dragon-$f.binvox" -r 80 --fill "$f" -q
done
echo "$(find "$out" -type f ! -name '*.log' | wc -l) files in $out (commands and messages in $log)"
