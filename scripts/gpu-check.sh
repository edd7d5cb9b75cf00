#!/usr/bin/env bash
# Runs the CUDA back end's tests and benchmarks on a machine with a GPU, from the bundle that
# scripts/gpu-bundle.sh made (.gpu/), without building there. Logs and the benchmark's JSON go to
# $OUT (or .gpu/out). Steps:
#   scripts/gpu-check.sh [tests|bench|all] [BENCH_FILTER]        (default: all)
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
b="$root/.gpu"
out="${OUT:-$b/out}"
what="${1:-all}"
filter="${2:-.}"
mkdir -p "$out"
export LD_LIBRARY_PATH="$b/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export VOXFX_DATA_DIR="$b/data" VOXFX_REQUIRE_DATA=1
# The test program runs the CLI at the path it was built with: put the bundle's CLI there.
cli="$(cat "$b/cli-path")"
if [ ! -e "$cli" ]; then mkdir -p "$(dirname "$cli")" && ln -s "$b/bin/voxfx" "$cli"; fi
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv | tee "$out/gpu.txt"
"$b/bin/voxfx" devices | tee -a "$out/gpu.txt"
rc=0
if [ "$what" = tests ] || [ "$what" = all ]; then
  timeout 200 "$b/bin/voxfx_device_tests" --gtest_brief=1 2>&1 | tee "$out/tests.log" | tail -40
  rc=${PIPESTATUS[0]}
  echo "tests: exit $rc"
fi
if [ "$what" = bench ] || [ "$what" = all ]; then
  timeout 220 "$b/bin/bench_cuda" --benchmark_filter="$filter" --benchmark_min_time=0.05 \
    --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$out/bench.json" --benchmark_out_format=json 2>&1 | grep -v "_mean\|_stddev\|_cv" | tee "$out/bench.log"
fi
exit "$rc"
