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
chunk of the Zarr array "voxels" (bool, packed 8 to a byte (numcodecs.PackBits), then zstd; bricks that are all empty are
not written; a task hands Python its bricks once per stack, not once per brick, and in a plain folder
store voxfx writes the full bricks' chunk files itself, without the GIL). The array's attributes hold the index-to-world affine of the voxel centres
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

_GRID_FORMAT = 2  # the store's layout version, in its attributes


_FULL_CHUNKS = {}  # (chunk shape, compressor): a full chunk's encoded bytes, once per worker process


def _grid_task(rect, mesh, frame, store, brick, mode, fill, threads):
    """One task: the stacks of `rect` = (tx, ty, x0, y0, x1, y1), voxelized and written stack by
    stack into the store, then marked done. `mesh` holds the triangles over the rectangle's columns
    (or the whole mesh); None: none reach it, nothing to write. Returns (tx, ty, chunks written,
    seconds, peak resident bytes of the worker process)."""
    import numpy as np
    import zarr

    from voxfx._voxfx import _voxelize_stacks

    start = time.monotonic()
    root = zarr.open_group(store, mode="r+")
    voxels, done = root["voxels"], root["done"]
    tx, ty = rect[0], rect[1]
    written = 0
    full = None  # a full brick's chunk, encoded once: inside a solid most bricks are full
    chunks, compressor = voxels.chunk_store, voxels.compressor

    def full_chunk():
        key = (voxels.chunks, repr(compressor))
        return _FULL_CHUNKS.get(key) or _FULL_CHUNKS.setdefault(
            key, bytes(voxels._encode_chunk(np.ones(voxels.chunks, dtype=bool))))

    def write(x0, y0, full_z0, mixed_z0, packed):
        # One call per stack (the GIL taken once for it, not once per brick): its full bricks (unless
        # written by voxfx) and its mixed ones as the PackBits bytes of their chunks, compressed as
        # zarr's own encoding would (filters, then compressor); empty bricks, the fill value, never come.
        nonlocal written, full
        bx, by = x0 // brick, y0 // brick
        if full_z0 and full is None:
            full = full_chunk()
        for z0 in full_z0:
            chunks[voxels._chunk_key((bx, by, z0 // brick))] = full
        for z0, value in zip(mixed_z0, packed):
            chunks[voxels._chunk_key((bx, by, z0 // brick))] = compressor.encode(value)
        written += len(full_z0) + len(mixed_z0)

    if mesh is not None:
        files = {}
        folder = _chunk_folder(voxels)
        if folder is not None:  # a folder of chunk files: voxfx writes them, without the GIL
            files = dict(full_chunk=full_chunk(), chunk_folder=folder, separator=voxels._dimension_separator,
                         zstd_level=_zstd_level(voxels))
        written += _voxelize_stacks(mesh, frame, rect[2:], brick=brick, mode=mode, fill=fill, threads=threads,
                                    visit_stack=write, **files)
    done[tx, ty] = 1
    return tx, ty, written, time.monotonic() - start, _peak_rss()


def _zstd_level(array):
    """The level voxfx compresses mixed chunks at itself when `array` is encoded as voxelize_grid makes
    it (PackBits, then numcodecs.Zstd, whose chunks are one zstd frame of the packed bytes), else 0
    (zarr encodes them)."""
    import numcodecs

    filters, compressor = array.filters or [], array.compressor
    if [type(f) for f in filters] != [numcodecs.PackBits] or type(compressor) is not numcodecs.Zstd:
        return 0
    return compressor.level if compressor.level > 0 else 0


def _chunk_folder(array):
    """The folder of `array`'s chunk files when its store is a plain zarr.DirectoryStore whose chunk
    keys are file names in it (separator "."), else None (another store: zarr writes them all)."""
    import zarr

    store = array.chunk_store
    if type(store) is not zarr.storage.DirectoryStore or getattr(store, "normalize_keys", False):
        return None
    if array._dimension_separator != ".":
        return None
    return os.path.join(store.path, array.path)


def _region_task(rect, mesh, frame, folder, brick, mode, fill, threads):
    """One task of voxelize_regions: the stacks of `rect` written as FOLDER/region-TX-TY.vdb (none
    when no triangle reaches them), then marked done (FOLDER/done/TX-TY). Returns (tx, ty, filled
    cells, seconds, peak resident bytes)."""
    from voxfx._voxfx import _voxelize_region

    start = time.monotonic()
    tx, ty = rect[0], rect[1]
    filled = 0
    if mesh is not None:
        filled = _voxelize_region(mesh, frame, rect[2:], os.path.join(folder, f"region-{tx:04d}-{ty:04d}.vdb"),
                                  brick=brick, mode=mode, fill=fill, threads=threads)
    _mark(folder, tx, ty)
    return tx, ty, filled, time.monotonic() - start, _peak_rss()


def _mark(folder, tx, ty):
    with open(os.path.join(folder, "done", f"{tx}-{ty}"), "w"):
        pass


def _peak_rss():
    """The peak resident set of this (worker) process in bytes: VmHWM, whose memory map is the
    process's own (getrusage's ru_maxrss survives fork and exec: a spawned worker would report the
    driver's peak); 0 where /proc has none."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _tasks_of(dims, brick, stacks_per_task):
    """The rectangles of k x k stacks: (tx, ty, x0, y0, x1, y1) in stacks, row-major (ty, then tx)."""
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
    # Bools packed 8 to a byte (numcodecs.PackBits, which any zarr reader with numcodecs decodes), then
    # zstd level 1 (whole, not in blosc's blocks: 3x faster and 3x smaller on packed bits); the tasks
    # write the packed bytes straight from voxfx's bit columns.
    compressor = numcodecs.Zstd(level=1)
    root.create_dataset("voxels", shape=tuple(dims), chunks=(brick,) * 3, dtype=bool, fill_value=False,
                        compressor=compressor, filters=[numcodecs.PackBits()], write_empty_chunks=False)
    root.create_dataset("done", shape=tasks_shape, chunks=(1, 1), dtype="u1", fill_value=0,
                        write_empty_chunks=False)
    root.attrs.update(attrs)
    return root, False


_REGIONS_FILE = "voxfx-regions.json"


def _open_regions(folder, attrs, overwrite):
    """The regions folder: made, or reopened for the same grid and options (returns the (tx, ty) of
    the tasks done before). Another grid's folder is emptied only with overwrite; a non-empty folder
    that is not a regions folder is never touched."""
    import shutil

    folder = os.fspath(folder)
    info = os.path.join(folder, _REGIONS_FILE)
    if os.path.isfile(info):
        with open(info, encoding="utf-8") as f:
            old = json.load(f)
        if old.get("voxfx") == attrs["voxfx"] and not overwrite:
            names = os.listdir(os.path.join(folder, "done")) if os.path.isdir(os.path.join(folder, "done")) else []
            return {tuple(int(v) for v in n.split("-")) for n in names if n.count("-") == 1}
        if not overwrite:
            raise ValueError(f"{folder}: regions of another grid or other options ({old.get('voxfx')}); "
                             "overwrite=True replaces them")
        shutil.rmtree(folder)
    elif os.path.isdir(folder) and os.listdir(folder):
        raise ValueError(f"{folder}: a folder that is not a voxfx regions folder; give an empty or new path")
    os.makedirs(os.path.join(folder, "done"), exist_ok=True)
    _write_report(attrs, info)
    return set()


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


def _plan(mesh, resolution, voxel_size, dims, bounds, margin, cube, mode, fill, brick, stacks_per_task):
    """What both kinds of store need before any task: the mesh, frame, dims, k, tasks, the store's
    attributes, the fill the tasks run and, per task, its triangles (None: none reach it).

    Column-local fills (parity and winding, and the surface modes) see in a column only the
    triangles over it, so each task gets those alone; gwn's winding numbers need every triangle,
    so its tasks share the whole mesh. Fill auto is decided here, once, on the whole mesh (a part is
    open)."""
    import voxfx

    if isinstance(brick, bool) or not isinstance(brick, int) or brick <= 0 or brick % 8:
        raise ValueError(f"brick must be a positive multiple of 8, got {brick!r}")
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
    k = stacks_per_task or max(1, math.ceil(math.sqrt(stacks[0] * stacks[1] / 256)))
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise ValueError(f"stacks_per_task must be a positive integer, got {stacks_per_task!r}")
    run_fill = voxfx._voxfx._resolve_fill(mesh, frame, mode=mode, fill=fill)
    tasks = _tasks_of(shape, brick, k)
    if run_fill == "gwn":
        parts = [mesh] * len(tasks)
    else:
        parts = voxfx._voxfx._task_meshes(mesh, frame, brick=brick, stacks_per_task=k)
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
    return dict(mesh=mesh, frame=frame, shape=shape, k=k, tasks=tasks, parts=parts, attrs=attrs, fill=run_fill,
                tasks_shape=tasks_shape)


def _run(client, fn, todo, parts, progress, **kwargs):
    """Runs fn(rect, mesh, **kwargs) for the tasks `todo` (indices into parts) on the cluster;
    returns their results. Parts are sent once: the whole mesh broadcast to every worker, or each
    task's own triangles scattered."""
    client, cluster = _get_client(client)
    try:
        if not todo:
            return []
        if progress and getattr(client, "dashboard_link", None):
            print(f"voxfx.dask: {len(todo)} tasks; dashboard {client.dashboard_link}", file=sys.stderr)
        meshes = [parts[i] for i, _ in todo]
        if all(m is meshes[0] for m in meshes):  # gwn: one mesh for every task
            sent = [client.scatter(meshes[0], broadcast=True)] * len(todo)
        else:
            own = [i for i, m in enumerate(meshes) if m is not None]
            sent = [None] * len(todo)
            for i, f in zip(own, client.scatter([meshes[i] for i in own])):
                sent[i] = f
        futures = [client.submit(fn, rect, m, pure=False, **kwargs) for (_, rect), m in zip(todo, sent)]
        if progress:
            import distributed

            distributed.progress(futures)
        return client.gather(futures)
    finally:
        if cluster is not None:
            client.close()
            cluster.close()


def voxelize_grid(mesh, resolution=None, client=None, store=None, *, voxel_size=None, dims=None, bounds=None,
                  margin=0, cube=False, mode="solid", fill="auto", brick=128, stacks_per_task=None, threads=1,
                  overwrite=False, progress=True):
    """Voxelizes `mesh` into the Zarr store `store` on the Dask cluster of `client`, brick by brick.

    mesh: a voxfx.Mesh (or anything voxfx.Mesh takes) or a mesh file's path (read here). Each task
    gets the triangles over its columns only (gwn, whose winding numbers need them all: the whole
    mesh, sent once to every worker). The grid: resolution, voxel_size, dims, bounds, margin, cube as
    voxfx.voxelize takes them (axis z). mode: surface | conservative | solid | solid-conservative |
    interior; fill auto | parity | winding | gwn (auto: parity for a closed mesh; an open one needs
    fill="gwn": flood and vote need the whole grid). brick: the chunk edge B (a multiple of 8; 16
    for gwn). stacks_per_task: each task takes k x k stacks of bricks (default: about 256 tasks at
    most). threads: voxfx's threads per task (1: Dask's workers are the parallelism).
    client: a distributed.Client; None uses the current client or, when there is none, a
    LocalCluster on this machine for the call. store: a folder path (or any Zarr store). A rerun
    with the same arguments skips the bricks already done; other arguments on an existing store
    are refused unless overwrite=True. progress: Dask's progress bar (distributed.progress) while
    the tasks run. Returns a summary: store, dims, affine, tasks, skipped, chunks_written, seconds,
    worker_peak_bytes (the largest peak resident set of a worker that ran a task).
    """
    if store is None:
        raise TypeError("voxelize_grid needs a store (a folder for the Zarr array)")
    start = time.monotonic()
    p = _plan(mesh, resolution, voxel_size, dims, bounds, margin, cube, mode, fill, brick, stacks_per_task)
    root, reopened = _open_store(store, p["shape"], brick, p["attrs"], p["tasks_shape"], overwrite)
    done = root["done"][:] if reopened else None
    todo = [(i, t) for i, t in enumerate(p["tasks"]) if done is None or not done[t[0], t[1]]]
    results = _run(client, _grid_task, todo, p["parts"], progress, frame=p["frame"], store=store, brick=brick,
                   mode=mode, fill=p["fill"], threads=threads)
    return {
        "store": os.fspath(store) if isinstance(store, (str, os.PathLike)) else store,
        "dims": p["shape"],
        "affine": p["attrs"]["affine"],
        "tasks": len(p["tasks"]),
        "skipped": len(p["tasks"]) - len(todo),
        "chunks_written": sum(r[2] for r in results),
        "seconds": time.monotonic() - start,
        "worker_peak_bytes": max((r[4] for r in results), default=0),
    }


def voxelize_regions(mesh, resolution=None, client=None, folder=None, *, voxel_size=None, dims=None, bounds=None,
                     margin=0, cube=False, mode="solid", fill="auto", brick=128, stacks_per_task=None, threads=1,
                     overwrite=False, progress=True):
    """Voxelizes `mesh` on the Dask cluster of `client` into OpenVDB files, one per task's region:
    FOLDER/region-TX-TY.vdb, each a BoolGrid "voxels" of the cells of its k x k stacks of bricks in
    the whole grid's frame (transform and "voxfx_dims" the whole grid's), so that
    `voxfx merge FOLDER -o GRID.vdb` (or OpenVDB's own tools) unites them. A region no triangle
    reaches has no file. The arguments are voxelize_grid's; a rerun with the same arguments skips the
    regions marked done (FOLDER/done/TX-TY, written after the region's file is renamed into place).
    Returns a summary: folder, dims, affine, tasks, skipped, regions (files written), filled (their
    cells), seconds, worker_peak_bytes.
    """
    if folder is None:
        raise TypeError("voxelize_regions needs a folder for the region files")
    start = time.monotonic()
    p = _plan(mesh, resolution, voxel_size, dims, bounds, margin, cube, mode, fill, brick, stacks_per_task)
    folder = os.path.abspath(os.fspath(folder))
    done = _open_regions(folder, p["attrs"], overwrite)
    todo = [(i, t) for i, t in enumerate(p["tasks"]) if (t[0], t[1]) not in done]
    results = _run(client, _region_task, todo, p["parts"], progress, frame=p["frame"], folder=folder, brick=brick,
                   mode=mode, fill=p["fill"], threads=threads)
    return {
        "folder": folder,
        "dims": p["shape"],
        "affine": p["attrs"]["affine"],
        "tasks": len(p["tasks"]),
        "skipped": len(p["tasks"]) - len(todo),
        "regions": sum(p["parts"][i] is not None for i, _ in todo),
        "filled": sum(r[2] for r in results),
        "seconds": time.monotonic() - start,
        "worker_peak_bytes": max((r[4] for r in results), default=0),
    }


def merge_regions(folder, output):
    """Unites the region files of `folder` (voxelize_regions) into one grid file (.vdb, .binvox,
    .nrrd): `voxfx merge` in this process. Returns the merged voxfx.SparseGrid."""
    import voxfx

    files = sorted(os.path.join(folder, n) for n in os.listdir(folder)
                   if n.endswith(".vdb") and not n.startswith("."))
    if not files:
        raise ValueError(f"{folder}: no .vdb region in it")
    grid = voxfx.read_sparse_grid(files[0])
    for f in files[1:]:
        grid.unite(voxfx.read_sparse_grid(f))
    grid.save(output)
    return grid


def open_grid(store):
    """The "voxels" array of a voxelize_grid store as a lazy dask.array (bool, indexed [x, y, z]);
    its affine is in zarr.open_group(store).attrs["affine"]."""
    import dask.array as da

    return da.from_zarr(store, component="voxels")


def _main(argv):
    """`voxfx voxelize MESH -o GRID.zarr [--scheduler ADDRESS] ...` and `voxfx voxelize MESH -o
    GRID.vdb --scheduler ADDRESS`: the command hands these outputs to this (argv without the
    program's name). GRID.vdb: regions into GRID.regions/, then merged into GRID.vdb."""
    import argparse

    import voxfx

    p = argparse.ArgumentParser(prog="voxfx voxelize", description="One grid voxelized brick by brick on a "
                                "Dask cluster into a Zarr store (voxfx.dask.voxelize_grid)")
    p.add_argument("command", choices=["voxelize"])
    p.add_argument("mesh")
    p.add_argument("-o", "--output", required=True,
                   help="the Zarr store (a folder, GRID.zarr), or GRID.vdb (regions in GRID.regions/, merged)")
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
    grid = dict(voxel_size=a.voxel_size, dims=a.dims, bounds=bounds, margin=a.margin, cube=a.cube, mode=a.mode,
                fill=a.fill, brick=a.brick, overwrite=a.overwrite, progress=not a.quiet)
    vdb = a.output.lower().endswith(".vdb")
    try:
        if vdb:
            regions = a.output[:-4] + ".regions"
            s = voxelize_regions(a.mesh, a.resolution, client, regions, **grid)
            merge_regions(regions, a.output)
        else:
            s = voxelize_grid(a.mesh, a.resolution, client, a.output, **grid)
    except (voxfx.Error, ValueError, TypeError, OSError) as e:
        print(f"voxfx: error: {e}", file=sys.stderr)
        return 2
    finally:
        if client is not None:
            client.close()
    if not a.quiet:
        d = s["dims"]
        what = f"{s['regions']} regions written" if vdb else f"{s['chunks_written']} chunks written"
        print(f"{a.mesh} -> {d[0]} x {d[1]} x {d[2]} grid in {s['tasks']} tasks ({s['skipped']} done before), "
              f"{what}, {s['seconds']:.1f} s -> {a.output} ({'vdb, regions in ' + regions if vdb else 'zarr'})")
    return 0

