#!/usr/bin/env bash
# Whole-command timings and peak memory of `voxfx voxelize` (load + voxelize + write), for each
# mode and resolution on the CGAL meshes and on two meshes of about a million triangles
# (bench/dense-meshes.sh). Needs GNU time (apt-get install time).
#   bench/cli_bench.sh [build-dir] [resolutions]   -> a markdown table on stdout
# e.g. bench/cli_bench.sh build "512 1024". The VDB output is written to a temporary folder.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
resolutions="${2:-128 256 512 1024}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
data="$root/data/meshes"
dense="${VOXFX_DENSE_DIR:-$root/data/dense}"
"$root/bench/dense-meshes.sh"
echo "| mesh | file MB | mode | N | load (ms) | voxelize (ms) | write (ms) | whole command (ms) | peak RSS (MiB) |"
echo "|---|---|---|---|---|---|---|---|---|"
for file in "$data/bunny00.off" "$data/armadillo.off" "$data/ChineseDragon-10kv.off" "$dense/bunny1m.off" "$dense/dragon1m.off"; do
  mesh=$(basename "$file" .off)
  mb=$(du -m "$file" | cut -f1)
  for mode in surface conservative solid; do
    for n in $resolutions; do
      log="$out/log"
      /usr/bin/time -f "%e %M" -o "$out/time" "$build/voxfx" voxelize "$file" \
        -o "$out/grid.vdb" -r "$n" -m "$mode" >"$log" 2>/dev/null
      # The summary line: "... load X ms, voxelize Y ms, write Z ms, total ..."
      ms() { sed -n "s/.*$1 \([0-9.]*\) \(m\?s\).*/\1 \2/p" "$log" | awk '{print ($2=="s") ? $1*1000 : $1}'; }
      read -r secs kib <"$out/time"
      echo "| $mesh | $mb | $mode | $n | $(ms load) | $(ms voxelize) | $(ms write) | $(awk "BEGIN{print $secs*1000}") | $((kib / 1024)) |"
    done
  done
done
