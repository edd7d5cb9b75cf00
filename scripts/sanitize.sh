#!/usr/bin/env bash
# The fast suite under AddressSanitizer and UndefinedBehaviorSanitizer (build-sanitize/, clang).
# Run by CI (.ci/run) after the test command; not part of the test command itself, whose ten
# minutes on two cores a second full build does not fit into. Set VOXFX_TEST_LABEL=slow (or "")
# to include the long cases.
#
# Clang builds this pass: its instrumented code generation costs about two thirds of GCC's
# (src/grid/morphology.cpp at -O1 -g1 with ASan and UBSan: 5.7 s of CPU against 8.6 s), and a
# second compiler checks what GCC lets through. No benchmarks or examples here: they add build
# time and no test. -O1 with line tables (-g1) still gives sanitizer reports file:line.
# Warnings are errors in the Release pass only. No Python module: a sanitized extension cannot
# load into an uninstrumented interpreter.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
start=$SECONDS
source scripts/test-setup.sh

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests (clang)"
CC=clang CXX=clang++ cmake -S . -B build-sanitize -G Ninja "${launcher[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DVOXFX_WERROR=OFF \
  -DVOXFX_SANITIZE=ON -DVOXFX_BUILD_CLI=ON -DVOXFX_BUILD_TESTS=ON -DVOXFX_BUILD_BENCH=OFF \
  -DVOXFX_BUILD_EXAMPLES=OFF -DVOXFX_BUILD_PYTHON=OFF >/dev/null
cmake --build build-sanitize -j "$jobs"
# intercept_tls_get_addr=0: LeakSanitizer 14 crashes ("Tracer caught signal 11") reading a bogus
# dynamic-TLS range of Embree's TBB worker threads under glibc 2.36; static TLS, stacks, globals
# and the heap are still scanned.
ASAN_OPTIONS=detect_leaks=1:intercept_tls_get_addr=0 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-sanitize --no-tests=error --output-on-failure -j "$jobs" "${label_args[@]}"
echo "== all tests passed under the sanitizers in $((SECONDS - start)) s"
