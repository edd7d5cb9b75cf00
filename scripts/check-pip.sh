#!/usr/bin/env bash
# Checks that the Python package installs the Python way, offline, with Debian's packages only:
# `pip install --no-build-isolation --no-index .` into a fresh venv (made with
# --system-site-packages, so Debian's NumPy, setuptools and wheel serve), then
# importlib.metadata.version("voxfx"), `python -m voxfx --version` and the `voxfx` script, a
# `pip wheel`, and mypy over a small typed program against the package's stubs (when Debian's
# python3-mypy is installed). Run by .ci/run, not by the test command (a separate CMake build of
# the library: minutes on two cores the first time, ccache makes later ones quick).
#
#   scripts/check-pip.sh
# Optional: VOXFX_PIP_WORK=<dir> (kept afterwards), VOXFX_PIP_BUILD_DIR (CMake's folder, default
# build-pip/py3X in the checkout), VOXFX_CMAKE_ARGS (default -DVOXFX_CUDA=OFF: no nvcc build here).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
python=${PYTHON:-/usr/bin/python3}
if [[ -n "${VOXFX_PIP_WORK:-}" ]]; then
  work=$VOXFX_PIP_WORK
  mkdir -p "$work"
else
  work=$(mktemp -d "${TMPDIR:-/tmp}/voxfx-pip.XXXXXX")
  trap 'rm -rf "$work"' EXIT
fi
export VOXFX_CMAKE_ARGS=${VOXFX_CMAKE_ARGS:--DVOXFX_CUDA=OFF}
export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-$(nproc)}

echo "== pip install --no-build-isolation --no-index . into a fresh venv"
"$python" -m venv --system-site-packages "$work/venv"
py=$work/venv/bin/python
"$py" -m pip install -q --no-build-isolation --no-index "$root"

echo "== the installed package, from outside the checkout"
cd "$work"
"$py" - <<'PY'
import importlib.metadata, os, sys
import numpy as np
import voxfx
assert importlib.metadata.version("voxfx") == voxfx.__version__, (importlib.metadata.version("voxfx"), voxfx.__version__)
assert voxfx.__file__.startswith(sys.prefix), voxfx.__file__
v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
g = voxfx.voxelize(v, f, resolution=8)
g.save(os.path.join(os.getcwd(), "t.vdb"))  # loads the OpenVDB module from inside the package
assert voxfx.read_grid("t.vdb") == g
print("voxfx", voxfx.__version__, "from", os.path.dirname(voxfx.__file__), ":", g)
PY
"$py" -m voxfx --version
"$work/venv/bin/voxfx" --version

echo "== pip wheel"
"$py" -m pip wheel -q --no-build-isolation --no-index --no-deps -w "$work/wheel" "$root"
ls "$work"/wheel/voxfx-*.whl
"$py" -m zipfile -l "$work"/wheel/voxfx-*.whl | grep -E "_voxfx|voxfx-cli|voxfx_vdb|py.typed|__init__.pyi" >/dev/null

if "$python" -c "import mypy" 2>/dev/null; then
  echo "== mypy over a typed program, against the installed stubs"
  "$py" -m mypy --strict --no-error-summary "$root/python/tests/typing_example.py"
  # ... and a wrong call is caught.
  printf 'import voxfx\nvoxfx.voxelize(None, resolution="64")\n' >"$work/wrong.py"
  if "$py" -m mypy --no-error-summary "$work/wrong.py" >/dev/null; then
    echo "mypy accepted a wrong call: the stubs are not in use" >&2
    exit 1
  fi
fi
echo "check-pip: OK"
