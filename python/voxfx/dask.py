"""Voxelize a manifest of meshes on a Dask cluster (distributed), as `voxfx batch` does.

    from distributed import Client
    import voxfx.dask
    report = voxfx.dask.run_manifest("meshes.txt", "out/", client=Client("tcp://scheduler:8786"),
                                     resolution=64, format=".binvox")

The manifest is read as `voxfx batch` reads it (one mesh path per line, relative to the manifest's
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
import os
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
