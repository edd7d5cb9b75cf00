"""Voxelize a manifest of meshes on a Dask cluster (distributed).

    from distributed import Client
    import voxfx.dask
    report = voxfx.dask.run_manifest("meshes.txt", "out/", client=Client("tcp://scheduler:8786"),
                                     resolution=64, format=".binvox")

The manifest is a text file with one mesh path per line, relative to the manifest's folder (or
absolute); blank lines and lines starting with '#' are skipped. Each mesh M is written to
OUTDIR/<stem of M><format> (the naming of `voxfx batch`), by `voxfx.Grid.save`, which writes a
temporary file beside the target and renames it: a crash never leaves a partial output. Each task
voxelizes a chunk of meshes in one worker; a mesh that fails is recorded with its error and the
rest go on. The report (a list of {"mesh", "output", "error", "skipped"} in manifest order) is
returned and written as JSON to `report` (default OUTDIR/report.json).

Workers need voxfx importable and the meshes and OUTDIR reachable at the same paths (a shared
file system).
"""
import json
import os

_VOXELIZE_OPTIONS = ("resolution", "voxel_size", "dims", "bounds", "margin", "mode", "fill", "axis",
                     "slicing", "threads")


def read_manifest(manifest):
    """The mesh paths of a manifest file, made absolute against the manifest's folder."""
    base = os.path.dirname(os.path.abspath(manifest))
    meshes = []
    with open(manifest, encoding="utf-8") as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            meshes.append(os.path.normpath(os.path.join(base, line)))
    return meshes


def output_path(mesh, outdir, fmt=".binvox"):
    """OUTDIR/<mesh file stem><fmt>, as `voxfx batch` names its outputs."""
    if not fmt.startswith("."):
        fmt = "." + fmt
    stem = os.path.splitext(os.path.basename(mesh))[0]
    return os.path.join(outdir, stem + fmt)


def run_chunk(meshes, outdir, fmt=".binvox", skip_existing=True, options=None):
    """Voxelizes and saves each mesh of `meshes` in this process; returns their report entries."""
    import voxfx

    options = dict(options or {})
    report = []
    for mesh in meshes:
        out = output_path(mesh, outdir, fmt)
        entry = {"mesh": mesh, "output": out, "error": None, "skipped": False}
        try:
            if skip_existing and os.path.exists(out):
                entry["skipped"] = True
            else:
                grid = voxfx.voxelize(voxfx.load_mesh(mesh), **options)
                grid.save(out)  # temporary file + rename
        except Exception as e:  # noqa: BLE001 - a bad mesh is recorded, the rest go on
            entry["error"] = str(e)
        report.append(entry)
    return report


def run_manifest(manifest, outdir, client=None, chunk=16, format=".binvox", skip_existing=True, report=None,
                 **voxelize_options):
    """Voxelizes every mesh of `manifest` into `outdir` on the Dask cluster of `client`.

    client: a distributed.Client; None uses the current client (distributed.get_client) or, when
    there is none, a LocalCluster of worker processes on this machine for the duration of the call.
    chunk: meshes per task. format: output extension (.binvox .vdb .nrrd .ply .obj).
    voxelize_options: what voxfx.voxelize takes (resolution, voxel_size, dims, bounds, margin, mode,
    fill, axis, slicing, threads). Returns the report (see the module docstring).
    """
    unknown = set(voxelize_options) - set(_VOXELIZE_OPTIONS)
    if unknown:
        raise TypeError("unknown voxelize options: " + ", ".join(sorted(unknown)))
    if chunk < 1:
        raise ValueError("chunk must be at least 1")
    import voxfx

    if not format.startswith("."):
        format = "." + format
    if format not in voxfx.GRID_FORMATS:
        raise ValueError("format must be one of " + " ".join(voxfx.GRID_FORMATS))
    meshes = read_manifest(manifest)
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
        futures = client.map(run_chunk, chunks, outdir=os.path.abspath(outdir), fmt=format,
                             skip_existing=skip_existing, options=voxelize_options, pure=False)
        results = [entry for part in client.gather(futures) for entry in part]
    finally:
        if own_cluster is not None:
            client.close()
            own_cluster.close()
    report_path = report if report is not None else os.path.join(outdir, "report.json")
    tmp = report_path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(results, f, indent=1)
    os.replace(tmp, report_path)
    return results
