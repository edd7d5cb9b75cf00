"""voxfx: voxelization of triangle meshes into bit grids, with NumPy arrays.

    import voxfx
    mesh = voxfx.load_mesh("bunny.off")            # or: vertices, faces = voxfx.load_mesh(...)
    grid = voxfx.voxelize(mesh, resolution=128)    # or: voxfx.voxelize(vertices, faces, ...)
    occ = grid.to_numpy()                          # bool array indexed [x, y, z]
    grid.save("bunny.binvox")                      # .binvox .vdb .nrrd .ply .obj
    inside = voxfx.contains(mesh, points)          # exact point occupancy, (K,) bool

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

from ._voxfx import (  # noqa: E402
    Density,
    Error,
    Grid,
    Mesh,
    PointClassifier,
    SurfaceMesh,
    __version__,
    closing,
    compute_density,
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
    voxelize,
)

#: File extension of each grid format that Grid.save writes.
GRID_FORMATS = (".binvox", ".vdb", ".nrrd", ".ply", ".obj")

__all__ = [
    "Density", "Error", "Grid", "Mesh", "PointClassifier", "SurfaceMesh", "GRID_FORMATS", "closing", "compute_density",
    "contains", "csg", "dilate", "erode", "extract_surface", "from_numpy", "load_mesh", "morphology",
    "opening", "read_grid", "resample_to_uniform", "reslice", "voxelize",
]
