#!/bin/bash
# What compiling a program that renders costs, per version of include/ (BENCHMARKS.md, "#36 public
# headers"). Usage:
#   bench/header_cost.sh ROUNDS NAME=INCLUDE_DIR [NAME=INCLUDE_DIR ...]
# e.g. the committed headers against an older commit's:
#   mkdir -p /tmp/old && git archive 165e043 include | tar -x -C /tmp/old
#   bench/header_cost.sh 5 old=/tmp/old/include now=include
# Each round compiles, for every include directory in turn (alternating, so that a change of the
# machine's load falls on all of them alike):
#   program  examples/render_minimal.cpp to an object file (render.hpp, scene_io.hpp, image_io.hpp
#            and a typical use), with the Release flags of build/compile_commands.json;
#   header   a translation unit of the one line #include <voxfx/render.hpp>, -fsyntax-only;
# and once per round the floor: the standard headers render.hpp brings (docs/ARCHITECTURE.md,
# "Public headers"), without voxfx, -fsyntax-only. Prints the median user + sys CPU seconds of
# each (GNU time), the preprocessed lines and the headers -H lists (all, and voxfx's).
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=$1
shift
CXX=${CXX:-g++}
FLAGS="-O3 -DNDEBUG -ffp-contract=off -Wall -Wextra -Wpedantic -Wshadow=local -Werror -march=x86-64-v3 -std=c++20"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo '#include <voxfx/render.hpp>' >"$tmp/header.cpp"
sed -n '/^- standard headers:/,/^$/p' docs/ARCHITECTURE.md | grep -o '`<[a-z_]*>`' | tr -d '`' |
    sed 's/^/#include /' >"$tmp/floor.cpp"

cpu() { # CPU seconds of one compile: cpu ARGS...
    /usr/bin/time -f '%U %S' -o "$tmp/time" "$CXX" $FLAGS "$@" >/dev/null || {
        echo "compile failed: $*" >&2
        exit 1
    }
    awk '{printf "%.2f", $1 + $2}' "$tmp/time"
}
declare -A runs
for ((r = 0; r < rounds; ++r)); do
    for spec in "$@"; do
        name=${spec%%=*} inc=${spec#*=}
        runs[$name.program]+=" $(cpu -I"$inc" -c examples/render_minimal.cpp -o "$tmp/p.o")"
        runs[$name.header]+=" $(cpu -I"$inc" -fsyntax-only "$tmp/header.cpp")"
    done
    runs[floor]+=" $(cpu -fsyntax-only "$tmp/floor.cpp")"
done

median() { tr ' ' '\n' <<<"$1" | grep . | sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
shape() { # preprocessed lines, headers, voxfx headers: shape FLAGS... SOURCE
    local lines all vox
    lines=$("$CXX" $FLAGS "$@" -E | wc -l)
    all=$("$CXX" $FLAGS "$@" -fsyntax-only -H 2>&1 | grep -c '^\.' || true)
    vox=$("$CXX" $FLAGS "$@" -fsyntax-only -H 2>&1 | grep '^\.' | grep -c 'voxfx/' || true)
    echo "$lines lines, $all headers ($vox voxfx)"
}
printf '%-24s %8s  %s\n' "what" "CPU s" "runs; shape"
for spec in "$@"; do
    name=${spec%%=*} inc=${spec#*=}
    for what in program header; do
        src=examples/render_minimal.cpp
        [ $what = header ] && src=$tmp/header.cpp
        printf '%-24s %8s  %s; %s\n' "$name $what" "$(median "${runs[$name.$what]}")" "${runs[$name.$what]# }" \
            "$(shape -I"$inc" "$src")"
    done
done
printf '%-24s %8s  %s; %s\n' "floor (std headers)" "$(median "${runs[floor]}")" "${runs[floor]# }" "$(shape "$tmp/floor.cpp")"
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
