#!/usr/bin/env bash
# Fetches the real test meshes and volumes from Debian's libcgal-demo package into data/
# (ignored by git): data/meshes/*.off|stl|ply and data/images/*.inr[.gz].
# Idempotent: does nothing when data/meshes/bunny00.off is already there.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dest="${VOXFX_DATA_DIR:-$root/data}"
if [ -f "$dest/meshes/bunny00.off" ] && [ -f "$dest/images/skull_2.9.inr" ]; then
  exit 0
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
# apt-get download runs as the _apt user where it can; a world-writable folder lets it write.
chmod 777 "$work"
apt-get download libcgal-demo >/dev/null
dpkg-deb -x libcgal-demo_*.deb pkg
mkdir -p extract
tar xzf pkg/usr/share/doc/libcgal-dev/data.tar.gz -C extract
mkdir -p "$dest/meshes" "$dest/images"
cp extract/data/meshes/* "$dest/meshes/"
cp extract/data/images/* "$dest/images/"
echo "fetched $(ls "$dest/meshes" | wc -l) meshes and $(ls "$dest/images" | wc -l) images into $dest"
