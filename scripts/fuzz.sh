#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang (AddressSanitizer + UndefinedBehaviorSanitizer)
# in build-fuzz/ and runs each for a bounded time, printing executions and corpus size per target.
#
#   scripts/fuzz.sh [--seconds N | --runs N] [target...]     (default: 60 seconds, every target)
#
# Each target starts from its committed seeds (fuzz/corpus/<target>/) and the inputs it found on
# earlier runs (build-fuzz/corpus/<target>/, not committed). A crash, leak, sanitizer report or
# timeout leaves its input in build-fuzz/artifacts/<target>/ and fails the script; keep it as a
# regression file in tests/regress/<target>/ (replayed by the FuzzCorpusReplay test) with a fix.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
limit=(-max_total_time=60)
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
  --seconds) limit=(-max_total_time="$2"); shift 2 ;;
  --runs) limit=(-runs="$2"); shift 2 ;;
  -h | --help) sed -n '2,10p' "$0"; exit 0 ;;
  -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
  *) targets+=("$1"); shift ;;
  esac
done
if [ ${#targets[@]} -eq 0 ]; then
  for f in fuzz/fuzz_*.cpp; do
    t="$(basename "$f" .cpp)"; t="${t#fuzz_}"
    targets+=("$t")
  done
fi

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# -O1 -g1: the sanitizers' usual level, and less than half the compile time of -O2 -g.
cmake -S . -B build-fuzz -G Ninja "${launcher[@]}" -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DVOXFX_BUILD_FUZZ=ON -DVOXFX_BUILD_TESTS=OFF -DVOXFX_BUILD_BENCH=OFF -DVOXFX_BUILD_EXAMPLES=OFF \
  -DVOXFX_BUILD_CLI=OFF -DVOXFX_INSTALL=OFF -DVOXFX_WERROR=OFF >/dev/null
cmake --build build-fuzz -j "$(nproc)" --target "${targets[@]/#/voxfx_fuzz_}"

failed=()
printf '%-18s %12s %8s %8s %10s %8s %10s %s\n' target execs seconds cpu-s exec/s corpus bytes result
for t in "${targets[@]}"; do
  mkdir -p "build-fuzz/corpus/$t" "build-fuzz/artifacts/$t"
  log="build-fuzz/artifacts/$t.log"
  rc=0
  start=$SECONDS
  # CPU seconds (user + system) besides wall seconds: on a loaded machine exec/s measures the
  # share of the CPU a target got, execs per CPU second the target itself.
  TIMEFORMAT='%U %S'
  { time ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    "build-fuzz/voxfx_fuzz_$t" "${limit[@]}" -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=20 \
    -print_final_stats=1 -artifact_prefix="build-fuzz/artifacts/$t/" \
    "build-fuzz/corpus/$t" "fuzz/corpus/$t" >"$log" 2>&1 || rc=$?; } 2>"$log.cpu"
  cpu="$(awk '{ printf "%.1f", $1 + $2 }' "$log.cpu")"
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)"
  corp="$(grep -o 'corp: [0-9]*/[0-9]*[a-zA-Z]*' "$log" | tail -1 | sed 's/corp: //')"
  result=ok
  if [ "$rc" -ne 0 ]; then
    result="FAILED (rc $rc, see $log)"
    failed+=("$t")
  fi
  printf '%-18s %12s %8s %8s %10s %8s %10s %s\n' "$t" "${execs:-?}" "$((SECONDS - start))" "${cpu:-?}" "${rate:-?}" \
    "${corp%%/*}" "${corp##*/}" "$result"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: findings in: ${failed[*]}" >&2
  exit 1
fi
