#!/usr/bin/env bash
# Installs what voxfx needs to build, test and benchmark on Debian 12 (apt). Idempotent and quick
# when everything is there already. libsdl2-dev is the window of `voxfx view` (optional: without it the
# rest builds); xvfb, xdotool and x11-apps (xwd) run its test (tests/view_window_test.py).
set -euo pipefail
packages=(
  cmake ninja-build g++ pkg-config
  libtbb-dev libassimp-dev libopenvdb-dev libboost-iostreams-dev
  libcli11-dev nlohmann-json3-dev libpng-dev libopenexr-dev
  libgtest-dev libgmock-dev libbenchmark-dev libcgal-dev libgmp-dev libmpfr-dev libeigen3-dev
  libembree-dev clang-format time ccache zlib1g-dev libblosc-dev libzstd-dev
  clang libclang-rt-14-dev
  python3-dev pybind11-dev python3-numpy python3-pytest python3-distributed python3-zarr python3-openvdb
  python3-pip python3-setuptools python3-wheel python3-venv python3-mypy
  libsdl2-dev xvfb xdotool x11-apps
  python3-torch
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
