#!/usr/bin/env bash
# The Python module's API reference (scripts/api_docs.py: signatures from the type stubs, text from
# the docstrings; and pydoc's page) into build/api-docs (ignored by git), from the module of the
# CMake build in build/ (built first: cmake --build build --target voxfx_python).
# Usage: scripts/api-docs.sh [BUILD_DIR [OUT_DIR]]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
out="${2:-$build/api-docs}"
if [ ! -d "$build/python/voxfx" ]; then
  echo "api-docs: no Python module in $build/python (build the voxfx_python target first)" >&2
  exit 1
fi
PYTHONPATH="$build/python" /usr/bin/python3 "$root/scripts/api_docs.py" "$out"
