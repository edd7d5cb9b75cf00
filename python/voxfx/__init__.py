"""voxfx: voxelization of triangle meshes into bit grids, with NumPy arrays.

    import voxfx
    mesh = voxfx.load_mesh("bunny.off")            # or: vertices, faces = voxfx.load_mesh(...)
    grid = voxfx.voxelize(mesh, resolution=128)    # or: voxfx.voxelize(vertices, faces, ...)
    occ = grid.to_numpy()                          # bool array indexed [x, y, z]
    grid.save("bunny.binvox")                      # .binvox .vdb .nrrd .ply .obj
    inside = voxfx.contains(mesh, points)          # exact point occupancy, (K,) bool
    d = voxfx.signed_distance(mesh, points)        # exact distance, negative inside, (K,) float64
    field = voxfx.sdf(mesh, resolution=128)        # narrow-band signed distance field
    report = voxfx.batch("meshes.txt", "out/", resolution=64)   # many meshes, as `voxfx batch`

Errors raise voxfx.Error (a RuntimeError) with the library's message. See also voxfx.dask for
voxelizing a manifest of meshes on a Dask cluster.
"""
import os as _os

from . import _paths


def _add_module_dir():
    # The I/O modules (voxfx_vdb.so, voxfx_assimp.so, voxfx_exr.so) are loaded on first use;
    # tell the loader where this copy of the package finds them (after any user setting).
    d = _os.path.normpath(_os.path.join(_os.path.dirname(__file__), _paths.MODULE_DIR))
    if _os.path.isdir(d):
        current = _os.environ.get("VOXFX_MODULE_PATH", "")
        if d not in current.split(":"):
            _os.environ["VOXFX_MODULE_PATH"] = current + ":" + d if current else d


_add_module_dir()

from ._voxfx import batch as _batch  # noqa: E402
from ._voxfx import (  # noqa: E402
    ClosestPoints,
    Density,
    Error,
    Grid,
    Mesh,
    PointClassifier,
    SignedDistanceField,
    SurfaceMesh,
    __version__,
    closing,
    compute_density,
    closest_points,
    cuda_status,
    contains,
    csg,
    dilate,
    erode,
    extract_surface,
    from_numpy,
    load_mesh,
    morphology,
    opening,
    read_grid,
    resample_to_uniform,
    reslice,
    sdf,
    signed_distance,
    voxelize,
)



class _ProgressLine:
    """progress=True of batch(): done/total, failures, rate and ETA on sys.stderr, at most twice a
    second (in place on a terminal), and each failed mesh on a line of its own."""

    def __init__(self):
        import sys
        import time

        self._stream, self._clock = sys.stderr, time.monotonic
        self._start = self._last = self._clock()
        self._tty = hasattr(self._stream, "isatty") and self._stream.isatty()
        self._ok = self._failed = self._skipped = 0

    def __call__(self, job, done, total):
        status = job["status"]
        self._ok += status == "ok"
        self._skipped += status == "skipped"
        if status == "error":
            self._failed += 1
            self._stream.write(("\r\033[K" if self._tty else "") + "voxfx: error: " + job["error"] + "\n")
        now = self._clock()
        if done < total and now - self._last < 0.5:
            return
        self._last = now
        elapsed = max(now - self._start, 1e-9)
        worked = done - self._skipped
        line = f"batch: {done:,}/{total:,} meshes, {self._failed:,} failed, {self._ok / elapsed:.3g} meshes/s"
        if done < total and worked > 0:
            line += f", ETA {(total - done) * elapsed / worked:.1f} s"
        self._stream.write(("\r" + line + "\033[K" + ("\n" if done == total else "")) if self._tty else line + "\n")
        self._stream.flush()


def batch(meshes, out_dir, *, progress=None, **options):
    if progress is True:
        progress = _ProgressLine()
    elif progress is False:
        progress = None
    return _batch(meshes, out_dir, progress=progress, **options)


batch.__doc__ = _batch.__doc__ + (
    "\n\nprogress=True prints done/total, failures, rate and ETA on sys.stderr; a callable is called as "
    "progress(job, done, total).")

#: File extension of each grid format that Grid.save writes.
GRID_FORMATS = (".binvox", ".vdb", ".nrrd", ".ply", ".obj")

__all__ = [
    "ClosestPoints", "Density", "Error", "Grid", "Mesh", "PointClassifier", "SignedDistanceField", "SurfaceMesh",
    "GRID_FORMATS", "batch", "closest_points", "closing", "compute_density",
    "contains", "cuda_status", "csg", "dilate", "erode", "extract_surface", "from_numpy", "load_mesh", "morphology",
    "opening", "read_grid", "resample_to_uniform", "reslice", "sdf", "signed_distance", "voxelize",
]
