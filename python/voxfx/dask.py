"""Voxfx on a Dask cluster (distributed): one grid larger than a machine (voxelize_grid), and a
manifest of meshes as `voxfx batch` does (run_manifest).

One grid across many machines:

    from distributed import Client
    import voxfx.dask
    summary = voxfx.dask.voxelize_grid("bunny.off", 16384, Client("tcp://scheduler:8786"), "bunny.zarr")
    voxels = voxfx.dask.open_grid("bunny.zarr")          # a lazy dask.array of bool, [x, y, z]

The grid is cut as the tiled voxelizer cuts it (voxfx/tiled.hpp): bricks of B^3 cells, and the
*stacks* of bricks over the same B x B columns. A task voxelizes a rectangle of stacks on its own
(each column's parity or winding number is carried down its stack inside the task, so no task waits
for another and the result does not depend on which worker ran what) and writes each brick as one
chunk of the Zarr array "voxels" (bool, blosc zstd with bit shuffle; bricks that are all empty are
not written). The array's attributes hold the index-to-world affine of the voxel centres
("affine", 4 x 4), "voxel_size", "origin" (the world position of cell (0, 0, 0)'s centre) and the
options. A task marks its rectangle done in the array "done" after its last brick: a rerun with
the same arguments skips what is marked, so a run that crashed half-way loses nothing finished
(a task cut off before its mark is simply run again; its chunks are written whole, atomically).
Bricks are equal bit for bit to those of `voxfx.voxelize(..., sparse=True)` and of the command's
tiled path.

    from distributed import Client
    import voxfx.dask
    report = voxfx.dask.run_manifest("meshes.txt", "out/", client=Client("tcp://scheduler:8786"),
                                     resolution=64, format=".binvox")

A manifest of meshes: the manifest is read as `voxfx batch` reads it (one mesh path per line, relative to the manifest's
folder, or absolute; blank lines and '#' comments skipped; two meshes of the same file stem are
refused before any work). Each task runs a chunk of the manifest through voxfx.batch in one worker:
the same C++ runBatch as the command, so mesh M is written atomically to OUTDIR/<stem of M><format>
with the command's bytes, an existing output is skipped (a rerun resumes), and a mesh that fails
is recorded with its error while the rest go on. The chunks' per-mesh records are gathered, in
manifest order, into a report of the command's shape: ok, skipped, errors, seconds (the wall time
of run_manifest), ok_per_second and jobs ({mesh, output, status, error, triangles, ms} per mesh),
returned and written as JSON to `report` (default OUTDIR/report.json; False: none).

Workers need voxfx importable and the meshes and OUTDIR reachable at the same paths (a shared
file system); the manifest and OUTDIR are made absolute for them.
"""
import json
import math
import os
import sys
import tempfile
import time

_BATCH_OPTIONS = ("resolution", "voxel_size", "dims", "bounds", "margin", "cube", "padding", "mode", "fill", "axis",
                  "slicing", "vdb_float", "threads", "nested")


def run_chunk(meshes, outdir, fmt=".binvox", skip_existing=True, options=None):
    """Runs `meshes` through voxfx.batch in this process; returns their records (the report's jobs)."""
    import voxfx

    return voxfx.batch(list(meshes), outdir, format=fmt, skip_existing=skip_existing, report=False,
                       **dict(options or {}))["jobs"]


def summarize(jobs, seconds):
    """A report of the batch command's shape over per-mesh records, its counts recomputed."""
    ok = sum(j["status"] == "ok" for j in jobs)
    return {
        "ok": ok,
        "skipped": sum(j["status"] == "skipped" for j in jobs),
        "errors": sum(j["status"] == "error" for j in jobs),
        "seconds": seconds,
        "ok_per_second": ok / seconds if seconds > 0 else 0.0,
        "jobs": list(jobs),
    }


def _write_report(report, path):
    """The report as JSON, written to a temporary file beside `path` and renamed."""
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".report-", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(report, f, indent=2, ensure_ascii=False)
            f.write("\n")
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def run_manifest(manifest, outdir, client=None, chunk=16, format=".binvox", skip_existing=True, report=None,
                 **batch_options):
    """Voxelizes every mesh of `manifest` into `outdir` on the Dask cluster of `client`.

    client: a distributed.Client; None uses the current client (distributed.get_client) or, when
    there is none, a LocalCluster of worker processes on this machine for the duration of the call.
    chunk: meshes per task. format: output extension (.binvox .vdb .nrrd .ply .obj .npy .npz).
    batch_options: what voxfx.batch takes for each chunk (resolution, voxel_size, dims, bounds,
    margin, cube, padding, mode, fill, axis, slicing, vdb_float; threads: workers per task, 0 = all cores, each
    mesh on one of them; nested). Returns the report (see the module docstring).
    """
    unknown = set(batch_options) - set(_BATCH_OPTIONS)
    if unknown:
        raise TypeError("unknown batch options: " + ", ".join(sorted(unknown)))
    if chunk < 1:
        raise ValueError("chunk must be at least 1")
    import voxfx
    from voxfx._voxfx import batch_jobs

    if not format.startswith("."):
        format = "." + format
    if format not in voxfx.GRID_FORMATS:
        raise ValueError("format must be one of " + " ".join(voxfx.GRID_FORMATS))
    start = time.monotonic()
    outdir = os.path.abspath(outdir)
    meshes = [mesh for mesh, _ in batch_jobs(os.path.abspath(manifest), outdir, format=format)]
    os.makedirs(outdir, exist_ok=True)
    own_cluster = None
    if client is None:
        import distributed

        try:
            client = distributed.get_client()
        except ValueError:
            own_cluster = distributed.LocalCluster(processes=True, dashboard_address=":0")
            client = distributed.Client(own_cluster)
    try:
        chunks = [meshes[i:i + chunk] for i in range(0, len(meshes), chunk)]
        futures = client.map(run_chunk, chunks, outdir=outdir, fmt=format, skip_existing=skip_existing,
                             options=batch_options, pure=False)
        jobs = [job for part in client.gather(futures) for job in part]
    finally:
        if own_cluster is not None:
            client.close()
            own_cluster.close()
    result = summarize(jobs, time.monotonic() - start)
    if report is None:
        report = os.path.join(outdir, "report.json")
    if report is not False:
        _write_report(result, os.fspath(report))
    return result


# ---- one grid across a cluster ------------------------------------------------------------------

_GRID_FORMAT = 1  # the store's layout version, in its attributes


def _grid_task(rect, mesh, frame, store, brick, mode, fill, threads):
    """One task: the stacks of `rect` = (tx, ty, x0, y0, x1, y1), voxelized and written brick by
    brick into the store, then marked done. Returns (tx, ty, chunks written, seconds)."""
    import zarr

    from voxfx._voxfx import _voxelize_stacks

    start = time.monotonic()
    root = zarr.open_group(store, mode="r+")
    voxels, done = root["voxels"], root["done"]
    tx, ty = rect[0], rect[1]
    written = 0
    for x0, y0, z0, value in _voxelize_stacks(mesh, frame, rect[2:], brick=brick, mode=mode, fill=fill,
                                             threads=threads):
        if value is False or (value is not True and not value.any()):
            continue  # the fill value: an empty brick is never written (zarr's own switch is not kept)
        if value is True:
            w, h, d = (min(brick, n - o) for n, o in zip(voxels.shape, (x0, y0, z0)))
            voxels[x0:x0 + w, y0:y0 + h, z0:z0 + d] = True
        else:
            w, h, d = value.shape
            voxels[x0:x0 + w, y0:y0 + h, z0:z0 + d] = value
        written += 1
    done[tx, ty] = 1
    return tx, ty, written, time.monotonic() - start


def _tasks_of(dims, brick, stacks_per_task):
    """The rectangles of k x k stacks: (tx, ty, x0, y0, x1, y1) in stacks."""
    sx, sy = (math.ceil(n / brick) for n in dims[:2])
    k = stacks_per_task
    return [(tx, ty, tx * k, ty * k, min(sx, tx * k + k), min(sy, ty * k + k))
            for ty in range(math.ceil(sy / k)) for tx in range(math.ceil(sx / k))]


def _open_store(store, dims, brick, attrs, tasks_shape, overwrite):
    """The group with "voxels" and "done": made, or reopened when it was made for the same grid and
    options (a restart). A store of another grid is replaced only with overwrite; a folder that is
    not a Zarr group at all is never touched."""
    import numcodecs
    import zarr

    path = os.fspath(store) if isinstance(store, (str, os.PathLike)) else None
    try:
        root = zarr.open_group(store, mode="r+")
    except (zarr.errors.GroupNotFoundError, zarr.errors.ContainsArrayError, FileNotFoundError):
        root = None
        if path is not None and os.path.isdir(path) and os.listdir(path):
            raise ValueError(f"{path}: a folder that is not a Zarr group; give an empty or new path")
    if root is not None and root.attrs.get("voxfx") == attrs["voxfx"] and not overwrite:
        return root, True
    if root is not None and not overwrite:
        raise ValueError(f"{path or store}: a store of another grid or other options "
                         f"({root.attrs.get('voxfx')}); overwrite=True replaces it")
    root = zarr.open_group(store, mode="w")
    compressor = numcodecs.Blosc(cname="zstd", clevel=3, shuffle=numcodecs.Blosc.BITSHUFFLE)
    root.create_dataset("voxels", shape=tuple(dims), chunks=(brick,) * 3, dtype=bool, fill_value=False,
                        compressor=compressor, write_empty_chunks=False)
    root.create_dataset("done", shape=tasks_shape, chunks=(1, 1), dtype="u1", fill_value=0,
                        write_empty_chunks=False)
    root.attrs.update(attrs)
    return root, False


def _get_client(client):
    """(client, cluster to close): the given client, the current one, or a LocalCluster."""
    if client is not None:
        return client, None
    import distributed

    try:
        return distributed.get_client(), None
    except ValueError:
        cluster = distributed.LocalCluster(processes=True, threads_per_worker=1, dashboard_address=":0")
        return distributed.Client(cluster), cluster


def voxelize_grid(mesh, resolution=None, client=None, store=None, *, voxel_size=None, dims=None, bounds=None,
                  margin=0, cube=False, mode="solid", fill="auto", brick=128, stacks_per_task=None, threads=1,
                  overwrite=False, progress=True):
    """Voxelizes `mesh` into the Zarr store `store` on the Dask cluster of `client`, brick by brick.

    mesh: a voxfx.Mesh (or anything voxfx.Mesh takes) or a mesh file's path (read here, sent once
    to every worker). The grid: resolution, voxel_size, dims, bounds, margin, cube as
    voxfx.voxelize takes them (axis z). mode: surface | conservative | solid | solid-conservative |
    interior; fill auto | parity | winding | gwn (auto: parity for a closed mesh; an open one needs
    fill="gwn": flood and vote need the whole grid). brick: the chunk edge B (a multiple of 8; 16
    for gwn). stacks_per_task: each task takes k x k stacks of bricks (default: about 1,000 tasks at
    most). threads: voxfx's threads per task (1: Dask's workers are the parallelism).
    client: a distributed.Client; None uses the current client or, when there is none, a
    LocalCluster on this machine for the call. store: a folder path (or any Zarr store). A rerun
    with the same arguments skips the bricks already done; other arguments on an existing store
    are refused unless overwrite=True. progress: Dask's progress bar (distributed.progress) while
    the tasks run. Returns a summary: store, dims, affine, tasks, skipped, chunks_written, seconds.
    """
    import voxfx

    if store is None:
        raise TypeError("voxelize_grid needs a store (a folder for the Zarr array)")
    if isinstance(brick, bool) or not isinstance(brick, int) or brick <= 0 or brick % 8:
        raise ValueError(f"brick must be a positive multiple of 8, got {brick!r}")
    start = time.monotonic()
    if isinstance(mesh, (str, os.PathLike)):
        mesh = voxfx.load_mesh(mesh)
    elif not isinstance(mesh, voxfx.Mesh):
        mesh = voxfx.Mesh(mesh)
    plan = voxfx._voxfx._grid_frame(mesh, resolution=resolution, voxel_size=voxel_size, dims=dims, bounds=bounds,
                                    margin=margin, cube=cube)
    frame, shape = plan["frame"], tuple(plan["dims"])
    # What the tiles refuse (a fill that needs the whole grid, a bad mesh, a brick size) is refused
    # here, before any task: an empty rectangle of stacks checks all of it.
    voxfx._voxfx._voxelize_stacks(mesh, frame, (0, 0, 0, 0), brick=brick, mode=mode, fill=fill, threads=1)
    stacks = [math.ceil(n / brick) for n in shape[:2]]
    k = stacks_per_task or max(1, math.ceil(math.sqrt(stacks[0] * stacks[1] / 1024)))
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise ValueError(f"stacks_per_task must be a positive integer, got {stacks_per_task!r}")
    tasks = _tasks_of(shape, brick, k)
    affine = plan["affine"]
    attrs = {
        "voxfx": {"format": _GRID_FORMAT, "frame": [list(frame[0]), list(frame[1]), frame[2], *frame[3:]],
                  "mode": mode, "fill": fill, "brick": brick, "stacks_per_task": k},
        "affine": affine,
        "voxel_size": [affine[i][i] for i in range(3)],
        "origin": [affine[i][3] for i in range(3)],
        "axes": ["x", "y", "z"],
    }
    tasks_shape = (math.ceil(stacks[0] / k), math.ceil(stacks[1] / k))
    root, reopened = _open_store(store, shape, brick, attrs, tasks_shape, overwrite)
    if reopened:
        done = root["done"][:]
        todo = [t for t in tasks if not done[t[0], t[1]]]
    else:
        todo = tasks
    client, cluster = _get_client(client)
    try:
        results = []
        if todo:
            if progress and getattr(client, "dashboard_link", None):
                print(f"voxfx.dask: {len(todo)} tasks ({len(tasks) - len(todo)} done before); dashboard "
                      f"{client.dashboard_link}", file=sys.stderr)
            mesh_future = client.scatter(mesh, broadcast=True)
            futures = client.map(_grid_task, todo, mesh=mesh_future, frame=frame, store=store, brick=brick,
                                 mode=mode, fill=fill, threads=threads, pure=False)
            if progress:
                import distributed

                distributed.progress(futures)
            results = client.gather(futures)
    finally:
        if cluster is not None:
            client.close()
            cluster.close()
    return {
        "store": os.fspath(store) if isinstance(store, (str, os.PathLike)) else store,
        "dims": shape,
        "affine": affine,
        "tasks": len(tasks),
        "skipped": len(tasks) - len(todo),
        "chunks_written": sum(r[2] for r in results),
        "seconds": time.monotonic() - start,
    }


def open_grid(store):
    """The "voxels" array of a voxelize_grid store as a lazy dask.array (bool, indexed [x, y, z]);
    its affine is in zarr.open_group(store).attrs["affine"]."""
    import dask.array as da

    return da.from_zarr(store, component="voxels")


def _main(argv):
    """`voxfx voxelize MESH -o GRID.zarr [--scheduler ADDRESS] ...`: the command hands .zarr outputs
    to this (argv without the program's name)."""
    import argparse

    import voxfx

    p = argparse.ArgumentParser(prog="voxfx voxelize", description="One grid voxelized brick by brick on a "
                                "Dask cluster into a Zarr store (voxfx.dask.voxelize_grid)")
    p.add_argument("command", choices=["voxelize"])
    p.add_argument("mesh")
    p.add_argument("-o", "--output", required=True, help="the Zarr store (a folder, GRID.zarr)")
    p.add_argument("-r", "--resolution", type=int)
    p.add_argument("--voxel-size", type=float)
    p.add_argument("--dims", type=int, nargs=3)
    p.add_argument("--bounds", type=float, nargs=6)
    p.add_argument("--margin", type=int, default=0)
    p.add_argument("--cube", action="store_true")
    p.add_argument("-m", "--mode", default="solid")
    p.add_argument("--fill", default="auto")
    p.add_argument("--brick", type=int, default=128)
    p.add_argument("--scheduler", help="the scheduler's address (tcp://host:8786); none: a local cluster")
    p.add_argument("--overwrite", action="store_true")
    p.add_argument("-q", "--quiet", action="store_true")
    a = p.parse_args(argv)
    client = None
    if a.scheduler:
        import distributed

        client = distributed.Client(a.scheduler)
    bounds = None if a.bounds is None else (a.bounds[:3], a.bounds[3:])
    try:
        s = voxelize_grid(a.mesh, a.resolution, client, a.output, voxel_size=a.voxel_size, dims=a.dims,
                          bounds=bounds, margin=a.margin, cube=a.cube, mode=a.mode, fill=a.fill, brick=a.brick,
                          overwrite=a.overwrite, progress=not a.quiet)
    except (voxfx.Error, ValueError, TypeError, OSError) as e:
        print(f"voxfx: error: {e}", file=sys.stderr)
        return 2
    finally:
        if client is not None:
            client.close()
    if not a.quiet:
        d = s["dims"]
        print(f"{a.mesh} -> {d[0]} x {d[1]} x {d[2]} grid in {s['tasks']} tasks ({s['skipped']} done before), "
              f"{s['chunks_written']} chunks written, {s['seconds']:.1f} s -> {a.output} (zarr)")
    return 0

