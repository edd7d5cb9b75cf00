#!/usr/bin/env bash
# The test job on a fresh Debian 12 machine: install dependencies, fetch the test data, build
# and run the fast test suite in Release, then again under AddressSanitizer and
# UndefinedBehaviorSanitizer. Set VOXFX_TEST_LABEL=slow (or "") to include the long cases.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
scripts/install-deps.sh
scripts/fetch-data.sh
label="${VOXFX_TEST_LABEL-fast}"
label_args=()
[ -n "$label" ] && label_args=(-L "$label")
jobs="$(nproc)"

echo "== format check"
git ls-files '*.cpp' '*.hpp' | xargs clang-format --dry-run -Werror

echo "== Release build and tests"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DVOXFX_WERROR=ON >/dev/null
cmake --build build -j "$jobs"
ctest --test-dir build --output-on-failure -j "$jobs" "${label_args[@]}"

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVOXFX_SANITIZE=ON -DVOXFX_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j "$jobs" "${label_args[@]}"
