#!/usr/bin/env python3
# Start-up and small-job whole-process wall times of two voxfx binaries, interleaved in one run
# (run from the repository root, after scripts/fetch-data.sh):
#   bench/startup.py OLD NEW [runs]  -> median and min per case and binary, and the ratio of medians.
import subprocess, sys, time, statistics
old, new = sys.argv[1], sys.argv[2]; n = int(sys.argv[3]) if len(sys.argv) > 3 else 31
cases = [('--version', ['--version']),
         ('voxelize elephant.off (5,558 tri) 64^3 -> binvox', ['voxelize', 'data/meshes/elephant.off', '-o', '/tmp/sp.binvox', '-r', '64']),
         ('voxelize elephant.off 64^3 -> nrrd', ['voxelize', 'data/meshes/elephant.off', '-o', '/tmp/sp.nrrd', '-r', '64']),
         ('voxelize elephant.off 64^3 -> vdb', ['voxelize', 'data/meshes/elephant.off', '-o', '/tmp/sp.vdb', '-r', '64'])]
for name, args in cases:
    t = {old: [], new: []}
    for _ in range(n):
        for exe in (old, new):
            s = time.perf_counter(); subprocess.run([exe] + args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True); t[exe].append(time.perf_counter() - s)
    mo, mn = statistics.median(t[old]) * 1e3, statistics.median(t[new]) * 1e3
    print(f'| {name} | {mo:.1f} (min {min(t[old])*1e3:.1f}) | {mn:.1f} (min {min(t[new])*1e3:.1f}) | {mo/mn:.1f}x |')
