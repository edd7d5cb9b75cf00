#!/usr/bin/env bash
# Batch throughput: `voxfx batch` against one `voxfx voxelize` process per mesh, on the CGAL meshes
# (data/meshes, fetched by scripts/fetch-data.sh) repeated to about JOBS jobs.
#
#   bench/batch_throughput.sh [BUILD_DIR] [JOBS] [RESOLUTIONS...]
#   e.g. bench/batch_throughput.sh build 1144 32 64 128
#
# Output names come from the mesh file's stem and must be unique, so the repeats are symbolic
# links in a scratch folder named r<k>_<stem>_<ext>.<ext> (sphere.off, sphere.ply and sphere.stl
# stay apart). Two manifests: every mesh, and the meshes under 10,000 triangles (the issue's
# target: >= 300 meshes/s at 64^3), triangle counts taken from a first batch's report.json.
# Wall time is what counts; the CPU time (user + sys) is printed too, since on a shared machine
# the wall time also measures everything else that runs. The per-process baseline runs each distinct mesh once, serially (a shell loop) and two at a time
# (xargs -P 2), and its outputs are compared byte for byte with the batch's.
set -euo pipefail

build=${1:-build}
jobs=${2:-1144}
shift $(($# > 2 ? 2 : $#)) || true
resolutions=("$@")
[ ${#resolutions[@]} -gt 0 ] || resolutions=(32 64 128)
root=$(cd "$(dirname "$0")/.." && pwd)
voxfx=$(cd "$build" && pwd)/src/cli/voxfx
[ -x "$voxfx" ] || voxfx=$(cd "$build" && pwd)/voxfx
[ -x "$voxfx" ] || { echo "no voxfx binary under $build" >&2; exit 1; }
meshes=("$root"/data/meshes/*.off "$root"/data/meshes/*.ply "$root"/data/meshes/*.stl)
[ -e "${meshes[0]}" ] || { echo "no meshes: run scripts/fetch-data.sh" >&2; exit 1; }

work=$(mktemp -d /tmp/voxfx-batch-bench.XXXXXX)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/links"

now() { date +%s.%N; }
rate() { python3 -c "import sys; n, t = int(sys.argv[1]), float(sys.argv[2]); print(f'{n} meshes in {t:.2f} s = {n / t:.0f} meshes/s')" "$@"; }

# Distinct meshes under unique link names, and the triangle counts from a first batch.
: >"$work/distinct.txt"
for m in "${meshes[@]}"; do
    f=$(basename "$m")
    stem=${f%.*} ext=${f##*.}
    ln -s "$m" "$work/links/r0_${stem}_${ext}.${ext}"
    echo "links/r0_${stem}_${ext}.${ext}" >>"$work/distinct.txt"
done
n=$(wc -l <"$work/distinct.txt")
"$voxfx" batch "$work/distinct.txt" -o "$work/probe" -r 8 -q >/dev/null || true
python3 - "$work" <<'EOF'
import json, os, sys
work = sys.argv[1]
report = json.load(open(os.path.join(work, "probe", "report.json")))
small = [os.path.relpath(j["mesh"], work) for j in report["jobs"]
         if j["status"] == "ok" and j["triangles"] < 10000]
open(os.path.join(work, "small.txt"), "w").write("".join(s + "\n" for s in small))
bad = [j["mesh"] for j in report["jobs"] if j["status"] != "ok"]
print(f"{len(report['jobs'])} distinct meshes, {len(small)} under 10K triangles, {len(bad)} that fail to load: "
      + ", ".join(os.path.basename(b) for b in bad))
EOF

# Repeats: links r1_..., r2_... until the manifest holds at least $jobs lines.
repeat() { # LIST OUT
    local list=$1 out=$2 k=0
    : >"$out"
    while [ "$(wc -l <"$out")" -lt "$jobs" ]; do
        while read -r l; do
            local name=${l#links/r0_}
            [ -e "$work/links/r${k}_$name" ] || ln -s "$(readlink "$work/$l")" "$work/links/r${k}_$name"
            echo "links/r${k}_$name" >>"$out"
        done <"$list"
        k=$((k + 1))
    done
}
repeat "$work/distinct.txt" "$work/all.txt"
repeat "$work/small.txt" "$work/small-rep.txt"
echo "manifests: $(wc -l <"$work/all.txt") jobs (all meshes), $(wc -l <"$work/small-rep.txt") jobs (under 10K triangles)"
echo "voxfx: $voxfx ($(nproc) cores)"

for r in "${resolutions[@]}"; do
    echo "== ${r}^3 (solid, auto fill, binvox)"
    for list in all small-rep; do
        for mode in "" "--nested"; do
            rm -rf "$work/out"
            t0=$(now)
            /usr/bin/time -f "%U %S" -o "$work/cpu" "$voxfx" batch "$work/$list.txt" -o "$work/out" -r "$r" -q -j 2 \
                $mode >/dev/null || true
            t1=$(now)
            cpu=$(tail -1 "$work/cpu" | awk '{print $1 + $2}')
            # The rate counts the meshes written (report.json's "ok"); failures are counted apart.
            read -r ok failed < <(python3 -c 'import json, sys; r = json.load(open(sys.argv[1])); print(r["ok"], r["errors"])' \
                "$work/out/report.json")
            echo "batch $list ${mode:-(1 thread per mesh)}: $(rate "$ok" "$(echo "$t1 - $t0" | bc)") written, $failed failed, CPU (user + sys) $cpu s"
        done
    done
    # One process per distinct mesh: a serial loop, and two at a time.
    rm -rf "$work/single" && mkdir -p "$work/single"
    t0=$(now)
    while read -r l; do
        f=$(basename "$l")
        "$voxfx" voxelize "$work/$l" -o "$work/single/${f%.*}.binvox" -r "$r" -q 2>/dev/null || true
    done <"$work/distinct.txt"
    t1=$(now)
    written=$(find "$work/single" -name '*.binvox' | wc -l)
    echo "process per mesh, loop: $(rate "$written" "$(echo "$t1 - $t0" | bc)") written, $((n - written)) failed"
    t0=$(now)
    (cd "$work" && xargs -P 2 -I{} sh -c 'f=$(basename {}); "$0" voxelize {} -o single/${f%.*}.binvox -r "$1" -q 2>/dev/null || true' \
        "$voxfx" "$r" <distinct.txt)
    t1=$(now)
    echo "process per mesh, xargs -P 2: $(rate "$written" "$(echo "$t1 - $t0" | bc)") written, $((n - written)) failed"
    # The batch's outputs of the first repeat against the single processes', byte for byte.
    rm -rf "$work/out" && "$voxfx" batch "$work/distinct.txt" -o "$work/out" -r "$r" -q >/dev/null || true
    same=0 differ=0
    for f in "$work"/single/*.binvox; do
        if cmp -s "$f" "$work/out/$(basename "$f")"; then same=$((same + 1)); else differ=$((differ + 1)); fi
    done
    echo "outputs identical to voxfx voxelize: $same, different: $differ"
done
