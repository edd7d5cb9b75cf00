"""voxfx: voxelization of triangle meshes into bit grids, with NumPy arrays.

    import voxfx
    mesh = voxfx.load_mesh("bunny.off")            # or any mesh object: trimesh, Open3D, meshio, (V, F)
    grid = voxfx.voxelize(mesh, resolution=64, cube=True, padding=2)   # a 64^3 grid, never stretched
    occ = grid.to_numpy()                          # bool array indexed [x, y, z]
    ijk = grid.indices()                           # (N, 3) int32 filled cells, no dense array
    ijk = voxfx.voxelize(mesh, resolution=4096, sparse=True).coordinates()  # the same, no dense grid
    grid.save("bunny.binvox")                      # .binvox .vdb .nrrd .ply .obj
    inside = voxfx.contains(mesh, points)          # exact point occupancy, (K,) bool
    d = voxfx.signed_distance(mesh, points)        # exact distance, negative inside, (K,) float64
    field = voxfx.sdf(mesh, resolution=128)        # narrow-band signed distance field
    ls = voxfx.read_level_set("a.vdb") - mesh      # OpenVDB level-set CSG, a mesh on its lattice: exact
    report = voxfx.batch("meshes.txt", "out/", resolution=64)   # many meshes, as `voxfx batch`
    image = voxfx.render("scene.json", shadows="deep", epsilon=0.02)  # (H, W, 3) float32, linear RGB
    s = voxfx.sample_near_surface(mesh, 100_000, sigma=0.01)  # points, exact sdf (negative inside), inside
    batch = voxfx.voxelize_many(paths, 64, padding=2)          # (B, 64, 64, 64) bool, or sparse=True: (N, 4)
    surface = voxfx.marching_cubes(field)          # OpenVDB's volumeToMesh of a level set, SDF or array
    r = voxfx.Renderer("scene.glb", width=640, height=360)       # frame after frame, as `voxfx view`
    frame = r.render(r.camera().orbit(0.3), preview=True)          # (90, 160, 3) uint8 sRGB

Torch: every function takes CPU tensors where it takes arrays; a tensor that requires grad is
detached (voxfx computes no gradients), and as_tensor=True returns tensors (see voxfx._datasets).

Errors raise voxfx.Error (a RuntimeError) with the library's message, bad arguments (a bad
mesh, a NaN query point, resolution=True) voxfx.ArgumentError (also a ValueError), refusals for
want of memory voxfx.MemoryLimitError (also a MemoryError). Every result pickles. Long calls release the GIL and stop at Ctrl-C. See also
voxfx.dask for voxelizing a manifest of meshes on a Dask cluster, and `python -m voxfx` for the
command line.
"""
import __future__

from . import _voxfx
from ._voxfx import (ArgumentError, Density, Error, Grid, MemoryLimitError, Mesh, PointClassifier, Scene, SparseGrid, SurfaceMesh,
                     VolumeEstimate, __version__)
from ._voxfx import Camera, Renderer
from ._voxfx import ClosestPoints, LevelSet, SignedDistanceField
from ._voxfx import NearSurfaceSamples, SurfaceSamples
from ._datasets import (AttributeGrid, attributes, marching_cubes, sample_near_surface, sample_surface, untensor_args,
                        voxelize_many)

# The I/O modules (voxfx_vdb.so, ...) lie next to _voxfx (the library looks there): nothing is
# set in os.environ.


def _with_signature(f):
    """A Python function calling the extension's function f, with f's parameters for
    inspect.signature (through __wrapped__, a function compiled from the signature line pybind11
    writes at the top of f's docstring; annotations stay text)."""
    line = (f.__doc__ or "").split("\n", 1)[0]
    name = f.__name__

    def call(*args, **kwargs):
        args, kwargs = untensor_args(args, kwargs)  # CPU torch tensors: detached, as arrays
        return f(*args, **kwargs)

    call.__name__ = call.__qualname__ = name
    call.__module__ = __name__
    call.__doc__ = f.__doc__
    if line.startswith(name + "("):
        params, arrow, result = line[len(name):].rpartition(" -> ")
        if not arrow:
            params, result = line[len(name):], "None"
        space = {}
        try:
            code = compile(f"def {name}{params} -> {result}: pass", "<voxfx>", "exec",
                           flags=__future__.annotations.compiler_flag, dont_inherit=True)
            exec(code, {"dtype": __import__("numpy").dtype}, space)
            call.__wrapped__ = space[name]
        except (SyntaxError, NameError, TypeError):
            pass
    return call


_FUNCTIONS = [
    "closing", "compute_density", "contains", "csg", "cuda_status", "dilate", "erode", "extract_surface",
    "from_numpy", "intersection_volume", "load_mesh", "morphology", "opening", "read_grid", "resample_to_uniform",
    "reslice", "voxelize", "batch_jobs", "glass_methods", "load_scene", "read_sparse_grid", "render", "render_options",
    "shadow_kinds", "closest_points", "signed_distance", "sdf", "read_level_set", "level_set", "level_set_csg",
    "offset_level_set",
]
for _name in _FUNCTIONS:
    globals()[_name] = _with_signature(getattr(_voxfx, _name))
_batch = _with_signature(_voxfx.batch)
load_colored_mesh = _with_signature(_voxfx.load_colored_mesh)


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


batch.__doc__ = _voxfx.batch.__doc__ + (
    "\n\nprogress=True prints done/total, failures, rate and ETA on sys.stderr; a callable is called as "
    "progress(job, done, total).")
if hasattr(_batch, "__wrapped__"):
    batch.__wrapped__ = _batch.__wrapped__

#: File extension of each grid format that Grid.save writes.
GRID_FORMATS = (".binvox", ".vdb", ".nrrd", ".ply", ".obj", ".npy", ".npz")

__all__ = ["ArgumentError", "Camera", "ClosestPoints", "Density", "Error", "Grid", "LevelSet", "MemoryLimitError", "Mesh",
           "PointClassifier", "Renderer", "Scene", "SignedDistanceField", "SparseGrid", "SurfaceMesh", "VolumeEstimate",
           "GRID_FORMATS", "batch", *sorted(_FUNCTIONS),
           # Dataset preparation (#35): samples, marching cubes on fields, batches, attributes.
           "AttributeGrid", "NearSurfaceSamples", "SurfaceSamples", "attributes", "load_colored_mesh",
           "marching_cubes", "sample_near_surface", "sample_surface", "voxelize_many"]
