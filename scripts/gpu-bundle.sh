#!/usr/bin/env bash
# Packs what a machine with a GPU needs to run the CUDA tests and benchmarks without building
# there: the test program, the benchmark, the CLI, the CUDA module, the shared libraries they load
# beyond glibc, and the CGAL meshes they read, into the ignored folder .gpu/ (about 30 MB).
#   scripts/gpu-bundle.sh [BUILD_DIR]       (default build/, configured with VOXFX_CUDA on)
# Then, on the GPU machine, from a copy of the repository with .gpu/ in it: scripts/gpu-check.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
out="$root/.gpu"
for f in voxfx_device_tests bench_cuda voxfx voxfx_cuda.so; do
  [ -f "$build/$f" ] || { echo "gpu-bundle: $build/$f is missing (build with VOXFX_CUDA on)" >&2; exit 1; }
done
[ -s "$root/data/meshes/bunny00.off" ] || { echo "gpu-bundle: no CGAL data: run scripts/fetch-data.sh" >&2; exit 1; }
rm -rf "$out.tmp"
mkdir -p "$out.tmp/bin" "$out.tmp/lib" "$out.tmp/data/meshes"
for f in voxfx_device_tests bench_cuda voxfx voxfx_cuda.so; do
  strip --strip-unneeded -o "$out.tmp/bin/$f" "$build/$f"
done
# Every library the programs need except glibc's own (the GPU machine's glibc is at least as new).
ldd "$out.tmp"/bin/* | awk '/=> \// {print $3}' | sort -u | while read -r lib; do
  case "$(basename "$lib")" in
    libc.so* | libm.so* | libdl.so* | libpthread.so* | librt.so* | ld-linux*) ;;
    *) cp -L "$lib" "$out.tmp/lib/" ;;
  esac
done
for m in bunny00 armadillo ChineseDragon-10kv elephant knot1; do
  cp "$root/data/meshes/$m.off" "$out.tmp/data/meshes/"
done
# The test program runs the CLI from the build folder it was built in (VOXFX_CLI_PATH).
echo "$build/voxfx" >"$out.tmp/cli-path"
rm -rf "$out"
mv "$out.tmp" "$out"
du -sh "$out"
