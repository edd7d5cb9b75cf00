#!/usr/bin/env bash
# Scale of `voxfx voxelize MESH -o x.vdb -r N --memory BUDGET` (tiled, into OpenVDB's sparse tree)
# on the bunny (75K triangles) and bunny1m (1.2M, bench/dense-meshes.sh), solid: the whole command,
# its voxelize and write times (from the summary line), peak memory (GNU time's maximum resident
# set) and the file's size. With DENSE="N1 N2 ...", also the path before tiles (--dense: the whole
# grid in memory, then the .vdb; no budget, as before) at those resolutions, in the same run.
# Needs GNU time.
#   bench/sparse_scale.sh [build-dir] [resolutions] [budget]   -> a markdown table on stdout
# e.g. DENSE="1024 2048 4096" bench/sparse_scale.sh build "1024 2048 4096 8192 16384" 4G
# Files go to a temporary folder ($TMPDIR; 2.6 GB at 16384^3), removed after each run.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
resolutions="${2:-1024 2048 4096 8192 16384}"
budget="${3:-4G}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
dense="${VOXFX_DENSE_DIR:-$root/data/dense}"
"$root/bench/dense-meshes.sh" >&2
secs() { sed -n "s/.*$1 \([0-9.]*\) \(m\?s\).*/\1 \2/p" "$out/log" | awk '{printf "%.2f", ($2=="s") ? $1 : $1/1000}'; }
run() { # mesh-file N extra-args...
  local file="$1" n="$2"
  shift 2
  /usr/bin/time -f "%e %M" -o "$out/time" "$build/voxfx" voxelize "$file" -o "$out/grid.vdb" -r "$n" "$@" \
    >"$out/log" 2>"$out/err" || { echo "| $(basename "$file" .off) | $n | $* | failed: $(tail -1 "$out/err") |||||"; return; }
  read -r wall kib <"$out/time"
  local mib=$(( $(stat -c %s "$out/grid.vdb") / 1048576 ))
  local path="tiled, --memory $budget"
  [ "$*" = "--dense" ] && path="dense (no budget)"
  echo "| $(basename "$file" .off) | $n | $path | $wall | $(secs voxelize) | $(secs write) | $((kib / 1024)) | $mib |"
  rm -f "$out/grid.vdb"
}
echo "| mesh | N | path | whole command (s) | voxelize (s) | write (s) | peak RSS (MiB) | file (MiB) |"
echo "|---|---|---|---|---|---|---|---|"
for file in "$root/data/meshes/bunny00.off" "$dense/bunny1m.off"; do
  for n in $resolutions; do run "$file" "$n" --memory "$budget"; done
  for n in ${DENSE:-}; do run "$file" "$n" --dense; done
done
