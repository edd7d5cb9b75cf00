"""Builds the voxfx Python package with CMake: `pip install --no-build-isolation .` (or `pip wheel`).

The extension (voxfx._voxfx), the I/O modules (voxfx_*.so) and the command line (voxfx-cli, what
`python -m voxfx` and the `voxfx` script run) are built by the project's CMake for the interpreter
running pip, and copied into the package, where the library finds them. The CMake build folder is
build-pip/py3X in the checkout (or VOXFX_PIP_BUILD_DIR), so a second install only rebuilds what
changed; ccache is used when it is installed. VOXFX_CMAKE_ARGS adds -D options (for example
-DVOXFX_CUDA=OFF to skip the CUDA module where nvcc is installed); VOXFX_CUDA=OFF (or ON) in the
environment says the same. The build takes minutes: its progress goes to stderr, which pip shows
with -v (`pip install -v --no-build-isolation .`); a line says so when the build starts.
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\(voxfx VERSION ([0-9.]+)", text).group(1)


def check_interpreter():
    """The interpreter running pip must have NumPy (the module returns arrays) and wheel (pip's
    bdist_wheel): say which interpreter lacks what, and that Debian's /usr/bin/python3 has both
    (python3-numpy, python3-wheel), instead of `invalid command 'bdist_wheel'` or a CMake error."""
    missing = []
    for module, package in (("numpy", "python3-numpy"), ("wheel", "python3-wheel")):
        try:
            __import__(module)
        except ImportError:
            missing.append(f"{module} ({package})")
    if missing:
        sys.exit(f"voxfx: {sys.executable} lacks " + ", ".join(missing) + ": build with Debian's "
                 "/usr/bin/python3 (`/usr/bin/python3 -m venv --system-site-packages .venv && "
                 ".venv/bin/pip install --no-build-isolation .`), or install them for this interpreter")


def say(text):
    """A line on stderr, which pip shows even without -v when the build fails."""
    print("voxfx: " + text, file=sys.stderr, flush=True)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        check_interpreter()
        package = Path(self.get_ext_fullpath(ext.name)).resolve().parent
        build = Path(os.environ.get("VOXFX_PIP_BUILD_DIR") or
                     ROOT / "build-pip" / f"py{sys.version_info.major}{sys.version_info.minor}")
        configure = ["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                     f"-DPython_EXECUTABLE={sys.executable}", "-DVOXFX_BUILD_PYTHON=ON", "-DVOXFX_BUILD_CLI=ON",
                     "-DVOXFX_BUILD_TESTS=OFF", "-DVOXFX_BUILD_BENCH=OFF", "-DVOXFX_BUILD_EXAMPLES=OFF",
                     "-DVOXFX_INSTALL=OFF"]
        if shutil.which("ninja") and not (build / "CMakeCache.txt").exists():
            configure += ["-G", "Ninja"]
        if shutil.which("ccache"):
            configure += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache", "-DCMAKE_CUDA_COMPILER_LAUNCHER=ccache"]
        cuda = os.environ.get("VOXFX_CUDA", "").upper()
        if cuda in ("OFF", "0", "NO", "FALSE"):
            configure += ["-DVOXFX_CUDA=OFF"]
        elif cuda in ("ON", "1", "YES", "TRUE"):
            configure += ["-DVOXFX_CUDA=ON"]
        elif shutil.which("nvcc"):
            say("nvcc found: the CUDA module is built too (VOXFX_CUDA=OFF skips it)")
        configure += shlex.split(os.environ.get("VOXFX_CMAKE_ARGS", ""))
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        say(f"building the extension with CMake in {build} ({jobs} jobs; several minutes the first time, "
            "progress shown with pip -v)")
        subprocess.run(configure, check=True, stdout=sys.stderr)
        subprocess.run(["cmake", "--build", str(build), "--target", "voxfx_python", "-j", jobs], check=True,
                       stdout=sys.stderr)
        # The build tree's package folder holds the extension and links to the modules and the
        # command line: copy what they point to.
        package.mkdir(parents=True, exist_ok=True)
        built = build / "python" / "voxfx"
        for f in sorted(built.iterdir()):
            if f.suffix == ".so" or f.name == "voxfx-cli":
                shutil.copy2(f.resolve(), package / f.name)


setup(
    version=project_version(),
    ext_modules=[Extension("voxfx._voxfx", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
)
