#!/usr/bin/env bash
# Checks that voxfx installs as a package: configures and builds it into a temporary prefix,
# `cmake --install`s it, builds examples/ as a separate project against that prefix with
# find_package(voxfx), and runs the example on a glTF cube (through the installed Assimp module)
# and on an OFF cube written as .vdb (through the installed OpenVDB module). Exits non-zero on
# any failure.
#
#   scripts/check-install.sh            # static library (the default)
#   VOXFX_SHARED=ON scripts/check-install.sh   # BUILD_SHARED_LIBS=ON
#   scripts/check-install.sh build      # install what an existing build folder built (no rebuild;
#                                       # the folder is kept): what scripts/test.sh does
# Optional: VOXFX_INSTALL_WORK=<dir> (kept afterwards), VOXFX_INSTALL_BUILD_DIR=<dir> (voxfx's build
# folder, removed after installing; with ccache, a folder beside build/ reuses its compilations),
# VOXFX_CMAKE_ARGS (more -D options for voxfx), JOBS, CMAKE_CXX_COMPILER_LAUNCHER=ccache.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
shared=${VOXFX_SHARED:-OFF}
jobs=${JOBS:-$(nproc)}
if [[ -n "${VOXFX_INSTALL_WORK:-}" ]]; then
  work=$VOXFX_INSTALL_WORK
  mkdir -p "$work"
else
  work=$(mktemp -d "${TMPDIR:-/tmp}/voxfx-install.XXXXXX")
  trap 'rm -rf "$work"' EXIT
fi
prefix=$work/prefix
build=${VOXFX_INSTALL_BUILD_DIR:-$work/build}
launcher=()
[[ -n "${CMAKE_CXX_COMPILER_LAUNCHER:-}" ]] && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER="$CMAKE_CXX_COMPILER_LAUNCHER")

if [[ $# -ge 1 ]]; then
  # An existing, built build folder, installed as it is into the temporary prefix. Its baked-in
  # module folder is the configured prefix's, not this one, so a program linked statically
  # elsewhere is told where the modules are, as the README tells users of a moved install.
  shared=$(sed -n 's/^BUILD_SHARED_LIBS:BOOL=//p' "$1/CMakeCache.txt")
  shared=${shared:-OFF}
  echo "== voxfx: install $1 (BUILD_SHARED_LIBS=$shared) into $prefix"
  cmake --install "$1" --prefix "$prefix" >/dev/null
  libdir=$(sed -n 's/^CMAKE_INSTALL_LIBDIR:PATH=//p' "$1/CMakeCache.txt")
  export VOXFX_MODULE_PATH="$prefix/${libdir:-lib}/voxfx"
else
  echo "== voxfx: build (BUILD_SHARED_LIBS=$shared) and install into $prefix"
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_SHARED_LIBS="$shared" \
    -DVOXFX_BUILD_TESTS=OFF -DVOXFX_BUILD_BENCH=OFF -DVOXFX_BUILD_EXAMPLES=OFF \
    -DCMAKE_INSTALL_PREFIX="$prefix" "${launcher[@]}" ${VOXFX_CMAKE_ARGS:-} >/dev/null
  cmake --build "$build" -j "$jobs"
  cmake --install "$build" >/dev/null
  # The build tree is removed: the example must work from the installed files alone.
  rm -rf "$build"
fi

echo "== examples/ as a consumer project: find_package(voxfx)"
cmake -S "$root/examples" -B "$work/examples" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" "${launcher[@]}" >/dev/null
cmake --build "$work/examples" -j "$jobs"

echo "== run it"
# A cube [-1, 1]^3 as OFF, and as glTF (8 float vertices, 36 uint16 indices in a base64 data URI).
printf 'OFF\n8 6 0\n-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n' >"$work/cube.off"
bin() {
  local one='\x00\x00\x80\x3f' minus='\x00\x00\x80\xbf' v a
  for v in 0 1 2 3 4 5 6 7; do
    for a in 0 1 2; do
      if (((v >> a) & 1)); then printf "$one"; else printf "$minus"; fi
    done
  done
  for i in 0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5; do
    printf "\\x$(printf %02x "$i")\\x00"
  done
}
cat >"$work/cube.gltf" <<JSON
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
 "buffers": [{"uri": "data:application/octet-stream;base64,$(bin | base64 -w0)", "byteLength": 168}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96}, {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1]},
               {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]}
JSON
example=$work/examples/voxelize_minimal
"$example" "$work/cube.off" "$work/cube.vdb"
"$example" "$work/cube.gltf" "$work/cube.binvox"
test -s "$work/cube.vdb"
test -s "$work/cube.binvox"
# The installed command finds the modules from its own place too.
"$prefix/bin/voxfx" --version
"$prefix/bin/voxfx" voxelize "$work/cube.gltf" -o "$work/cli.vdb" --resolution 16 >/dev/null
test -s "$work/cli.vdb"
echo "check-install: OK (BUILD_SHARED_LIBS=$shared)"
