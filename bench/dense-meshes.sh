#!/usr/bin/env bash
# Makes the benchmarks' meshes of about a million triangles from the CGAL data, by midpoint
# subdivision (bench/subdivide_off.awk), into the ignored data/dense/:
#   bunny1m.off   bunny00 subdivided twice (1,206,528 triangles, closed)
#   dragon1m.off  the Chinese dragon subdivided three times (1,279,616 triangles, open)
# Used by bench_voxelize and bench/cli_bench.sh; each file is made once (about 20 s each).
# $VOXFX_DENSE_DIR, when set, is the folder instead (as bench_meshes.hpp reads it).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
data="$root/data/meshes"
dense="${VOXFX_DENSE_DIR:-$root/data/dense}"
[ -s "$data/bunny00.off" ] || { echo "no CGAL data: run scripts/fetch-data.sh first" >&2; exit 1; }
mkdir -p "$dense"
make_mesh() { # name rounds source: written to a temporary file, renamed when complete
  [ -s "$dense/$1.off" ] && return
  echo "making $dense/$1.off" >&2
  awk -f "$root/bench/subdivide_off.awk" -v rounds="$2" "$data/$3" >"$dense/$1.off.tmp"
  mv "$dense/$1.off.tmp" "$dense/$1.off"
}
make_mesh bunny1m 2 bunny00.off
make_mesh dragon1m 3 ChineseDragon-10kv.off
