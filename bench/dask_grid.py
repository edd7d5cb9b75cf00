#!/usr/bin/env python3
"""One grid across a Dask cluster (issue #38): voxfx.dask.voxelize_grid (Zarr) or voxelize_regions
(.vdb regions) of one mesh at one resolution on a LocalCluster of N worker processes (1 thread
each), against the single-process tiled voxelization of the same grid (voxfx.voxelize(...,
sparse=True)) in the same run. Prints one CSV row per worker count: seconds, the largest peak
resident set of a worker, the driver's peak, the store's bytes and files.

  PYTHONPATH=build/python /usr/bin/python3 bench/dask_grid.py data/meshes/bunny00.off 8192 1 2 4 \
      [--regions] [--brick 128] [--dir /tmp] [--task-ratio 8]

--task-ratio N: also the same N tasks (those of the most triangles) run one after another in this
process and in a 1-worker LocalCluster (each into a fresh store): the per-task seconds in the
worker against in-process, medians and their ratio (what a Dask worker's other threads cost a task).

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


def task_ratio(mesh, resolution, brick, count, folder):
    """Median seconds of the `count` tasks with the most triangles, in this process and in a
    1-worker LocalCluster, and the median of their per-task ratios."""
    import statistics

    import distributed

    import voxfx.dask as vd

    p = vd._plan(mesh, resolution, None, None, None, 0, False, "solid", "auto", brick, None)
    order = sorted((i for i, m in enumerate(p["parts"]) if m is not None),
                   key=lambda i: -p["parts"][i].triangle_count)[:count]
    kw = dict(frame=p["frame"], brick=brick, mode="solid", fill=p["fill"], threads=1)

    def fresh(name):
        store = os.path.join(folder, f"voxfx-bench-{os.getpid()}-{name}.zarr")
        shutil.rmtree(store, ignore_errors=True)
        vd._open_store(store, p["shape"], brick, p["attrs"], p["tasks_shape"], True)
        return store

    store = fresh("inproc")
    inproc = [vd._grid_task(p["tasks"][i], p["parts"][i], store=store, **kw)[3] for i in order]
    shutil.rmtree(store)
    store = fresh("worker")
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, memory_limit=0,
                                       dashboard_address=":0")
    client = distributed.Client(cluster)
    try:
        futures = [client.submit(vd._grid_task, p["tasks"][i], p["parts"][i], store=store, pure=False, **kw)
                   for i in order]
        worker = [r[3] for r in client.gather(futures)]
    finally:
        client.close()
        cluster.close()
        shutil.rmtree(store)
    m = statistics.median
    return m(inproc), m(worker), m(w / i for w, i in zip(worker, inproc))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("mesh")
    p.add_argument("resolution", type=int)
    p.add_argument("workers", type=int, nargs="+")
    p.add_argument("--regions", action="store_true", help="voxelize_regions (.vdb) instead of Zarr")
    p.add_argument("--brick", type=int, default=128)
    p.add_argument("--dir", default=tempfile.gettempdir())
    p.add_argument("--single", action="store_true", help="also time the single-process tiled grid")
    p.add_argument("--task-ratio", type=int, default=0, metavar="N",
                   help="also N tasks in-process against in one worker (per-task seconds)")
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
    if a.task_ratio:
        inproc, worker, ratio = task_ratio(mesh, a.resolution, a.brick, a.task_ratio, a.dir)
        print(f"task in-process (median of {a.task_ratio}),{a.resolution},0,{inproc:.3f},,,,,")
        print(f"task in 1 worker (median of {a.task_ratio}; per-task ratio {ratio:.2f}),{a.resolution},1,"
              f"{worker:.3f},,,,,", flush=True)
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
