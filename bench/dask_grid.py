#!/usr/bin/env python3
"""One grid across a Dask cluster (issue #38): voxfx.dask.voxelize_grid (Zarr) or voxelize_regions
(.vdb regions) of one mesh at one resolution on a LocalCluster of N worker processes (1 thread
each), against the single-process tiled voxelization of the same grid (voxfx.voxelize(...,
sparse=True)) in the same run. Prints one CSV row per worker count: seconds, the largest peak
resident set of a worker, the driver's peak, the store's bytes and files.

  PYTHONPATH=build/python /usr/bin/python3 bench/dask_grid.py data/meshes/bunny00.off 8192 1 2 4 \
      [--regions] [--brick 128] [--dir /tmp]

Run it as a file (a LocalCluster's workers re-import the main module)."""
import argparse
import os
import shutil
import sys
import tempfile
import time


def peak_mib():
    with open("/proc/self/status", encoding="ascii") as f:
        return next(int(l.split()[1]) for l in f if l.startswith("VmHWM:")) / 1024


def folder_bytes(path):
    total = files = 0
    for root, _, names in os.walk(path):
        for n in names:
            total += os.path.getsize(os.path.join(root, n))
            files += 1
    return total, files


def main():
    p = argparse.ArgumentParser()
    p.add_argument("mesh")
    p.add_argument("resolution", type=int)
    p.add_argument("workers", type=int, nargs="+")
    p.add_argument("--regions", action="store_true", help="voxelize_regions (.vdb) instead of Zarr")
    p.add_argument("--brick", type=int, default=128)
    p.add_argument("--dir", default=tempfile.gettempdir())
    p.add_argument("--single", action="store_true", help="also time the single-process tiled grid")
    a = p.parse_args()
    import distributed

    import voxfx
    import voxfx.dask

    mesh = voxfx.load_mesh(a.mesh)
    print("what,resolution,workers,seconds,worker_peak_MiB,driver_peak_MiB,store_MiB,files,tasks")
    if a.single:
        t = time.monotonic()
        g = voxfx.voxelize(mesh, resolution=a.resolution, sparse=True, threads=1)
        s = time.monotonic() - t
        peak = peak_mib()
        print(f"single-process tiles (1 thread),{a.resolution},0,{s:.1f},,{peak:.0f},{g.memory_bytes / 2**20:.0f},,")
        del g
    for n in a.workers:
        out = os.path.join(a.dir, f"voxfx-bench-{os.getpid()}" + (".regions" if a.regions else ".zarr"))
        shutil.rmtree(out, ignore_errors=True)
        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, memory_limit=0,
                                           dashboard_address=":0")
        client = distributed.Client(cluster)
        try:
            fn = voxfx.dask.voxelize_regions if a.regions else voxfx.dask.voxelize_grid
            s = fn(mesh, a.resolution, client, out, brick=a.brick, progress=False)
        finally:
            client.close()
            cluster.close()
        size, files = folder_bytes(out)
        shutil.rmtree(out, ignore_errors=True)
        driver = peak_mib()
        print(f"{'regions' if a.regions else 'zarr'},{a.resolution},{n},{s['seconds']:.1f},"
              f"{s['worker_peak_bytes'] / 2**20:.0f},{driver:.0f},{size / 2**20:.0f},{files},{s['tasks']}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
