#!/usr/bin/env bash
# Whole-command timings and peak memory of `voxfx voxelize` (load + voxelize + write), for each
# mode and resolution on the CGAL meshes. Needs GNU time (apt-get install time).
#   bench/cli_bench.sh [build-dir]   -> a markdown table on stdout
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
echo "| mesh | mode | N | voxelize (ms) | whole command (ms) | peak RSS (MiB) |"
echo "|---|---|---|---|---|---|"
for mesh in bunny00 armadillo ChineseDragon-10kv; do
  for mode in surface conservative solid; do
    for n in 128 256 512 1024; do
      log="$out/log"
      /usr/bin/time -f "%e %M" -o "$out/time" "$build/voxfx" voxelize "$root/data/meshes/$mesh.off" \
        -o "$out/grid.vdb" -r "$n" -m "$mode" >"$log" 2>/dev/null
      vox=$(sed -n 's/.*voxelize \([0-9.]*\) \(m\?s\).*/\1 \2/p' "$log" | awk '{print ($2=="s") ? $1*1000 : $1}')
      read -r secs kib <"$out/time"
      echo "| $mesh | $mode | $n | $vox | $(awk "BEGIN{print $secs*1000}") | $((kib / 1024)) |"
    done
  done
done
