#!/usr/bin/env bash
# The test job on a fresh Debian 12 machine: install dependencies, fetch the test data, build
# and run the fast test suite in Release (the Python suite included), and check that an installed
# voxfx can be consumed with find_package. Set VOXFX_TEST_LABEL=slow (or "") to include the long
# cases. The same suite under AddressSanitizer and UndefinedBehaviorSanitizer is
# scripts/sanitize.sh, which CI runs after this.
#
# Every build option the job relies on is set explicitly: build/ may have been configured by
# scripts/run.sh (no tests, no benchmarks), and the CMake cache would keep that. ctest fails
# when it finds no test, and a test whose data file is missing fails instead of skipping
# (VOXFX_REQUIRE_DATA=1), since the data was fetched above.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
start=$SECONDS
source scripts/test-setup.sh

echo "== format check"
git ls-files '*.cpp' '*.hpp' '*.cu' | xargs clang-format --dry-run -Werror

echo "== Release build and tests"
# The benchmarks are programs, not tests: the test command leaves them out unless
# VOXFX_TEST_BENCH=ON (CI sets it, so they keep compiling; they cost about a minute here).
bench="${VOXFX_TEST_BENCH:-OFF}"
# The Python module is built for Debian's interpreter, the one with NumPy, pytest and Dask
# (python3-numpy, python3-pytest, python3-distributed); its pytest suite is the ctest test
# python.pytest.
cmake -S . -B build -G Ninja "${launcher[@]}" -DCMAKE_BUILD_TYPE=Release -DVOXFX_WERROR=ON -DVOXFX_SANITIZE=OFF \
  -DVOXFX_BUILD_CLI=ON -DVOXFX_BUILD_TESTS=ON -DVOXFX_BUILD_BENCH="$bench" -DVOXFX_BUILD_EXAMPLES=ON \
  -DVOXFX_BUILD_PYTHON=ON -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build build -j "$jobs"
ctest --test-dir build --no-tests=error --output-on-failure -j "$jobs" "${label_args[@]}"

if [ -x scripts/check-install.sh ]; then
  echo "== install and build examples/ against it with find_package(voxfx)"
  scripts/check-install.sh build
fi

echo "== all tests passed in $((SECONDS - start)) s"
