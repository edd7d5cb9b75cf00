#!/usr/bin/env bash
# The main job on a fresh Debian 12 machine: install dependencies, build voxfx (Release), fetch
# the CGAL test meshes, and voxelize the Stanford bunny at 512^3 into every output format.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
scripts/install-deps.sh
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
# The same compile flags as scripts/test.sh's Release pass, so running the tests afterwards
# reuses these objects; the tests themselves are not built here.
cmake -S . -B build -G Ninja "${launcher[@]}" -DCMAKE_BUILD_TYPE=Release -DVOXFX_WERROR=ON -DVOXFX_SANITIZE=OFF \
  -DVOXFX_BUILD_CLI=ON -DVOXFX_BUILD_TESTS=OFF -DVOXFX_BUILD_BENCH=OFF -DVOXFX_BUILD_EXAMPLES=OFF >/dev/null
cmake --build build --target voxfx_cli
scripts/fetch-data.sh
mkdir -p out
build/voxfx info data/meshes/bunny00.off
for ext in vdb binvox nrrd ply; do
  build/voxfx voxelize data/meshes/bunny00.off -o "out/bunny.$ext" --resolution 512 --mode solid
done
build/voxfx voxelize data/meshes/ChineseDragon-10kv.off -o out/dragon.vdb --resolution 512
echo "outputs in $root/out (open .vdb in Blender or ParaView, .ply in any mesh viewer)"
