"""Dataset preparation: samples with signed distances, marching cubes on fields, batches as arrays,
attribute and colour grids, and torch tensors in and out.

The rule for torch tensors (every voxfx function): a CPU tensor is accepted wherever an array is
(mesh vertices and faces, a (vertices, faces) pair, points, fields); one that requires grad is
detached first, because voxfx computes no gradients (voxelization, sampling, distances and marching
cubes are not differentiable here): nothing flows back through a voxfx call, and what it returns
never requires grad. A tensor on another device is a TypeError (move it with .cpu()). as_tensor=True
returns CPU tensors sharing the NumPy arrays' memory (torch.from_numpy: no copy). torch is imported
only when a tensor is passed or as_tensor=True is asked for.
"""
import sys

from . import _voxfx


def _is_tensor(x):
    torch = sys.modules.get("torch")
    return torch is not None and isinstance(x, torch.Tensor)


def untensor(x):
    """A torch tensor as a NumPy array (detached, CPU only); anything else as it is."""
    if not _is_tensor(x):
        return x
    if x.device.type != "cpu":
        raise TypeError(f"voxfx takes CPU tensors, got one on {x.device}: move it with .cpu() first")
    return x.detach().numpy()


def untensor_args(args, kwargs):
    """untensor() on every argument, and on the items of (vertices, faces) pairs."""

    def one(a):
        if _is_tensor(a):
            return untensor(a)
        if isinstance(a, (tuple, list)) and len(a) == 2 and (_is_tensor(a[0]) or _is_tensor(a[1])):
            return type(a)(untensor(v) for v in a)
        return a

    return tuple(one(a) for a in args), {k: one(v) for k, v in kwargs.items()}


def _tensor(a):
    import torch

    return torch.from_numpy(a)


def _out(value, as_tensor):
    if not as_tensor:
        return value
    if isinstance(value, tuple) and hasattr(value, "_fields"):
        return type(value)(*(_tensor(v) for v in value))
    return _tensor(value)


def sample_surface(mesh, n, seed=0, *, threads=0, as_tensor=False):
    """n points uniformly distributed over the mesh's surface: SurfaceSamples(points (n, 3) float64,
    normals (n, 3) float32, faces (n,) int64).

    Area-weighted (a triangle is picked with probability area / total area, then a uniform point
    in it); the normal is the unit normal of the point's face (its counter-clockwise side: outward
    for a closed mesh oriented so). Deterministic: sample i depends only on (seed, i), so the
    result is the same for any thread count and the first k of n samples are those of a call for
    k. mesh: anything voxelize takes (a voxfx.Mesh, trimesh, Open3D, meshio, a (V, F) pair of
    arrays or CPU tensors). as_tensor=True returns torch tensors. The GIL is released; Ctrl-C
    stops it.
    """
    (mesh,), _ = untensor_args((mesh,), {})
    return _out(_voxfx.sample_surface(mesh, n, seed, threads=threads), as_tensor)


def sample_near_surface(mesh, n, sigma, seed=0, *, uniform=0.0, box_margin=0.1, sign="auto", winding_beta=3.0,
                        threads=0, as_tensor=False):
    """n points near the surface with exact signed distances and inside labels, as DeepSDF and
    Occupancy Networks prepare data: NearSurfaceSamples(points (n, 3) float64, sdf (n,) float64,
    inside (n,) bool).

    The first n - round(n * uniform) points are sample_surface(mesh, ..., seed)'s points moved by
    isotropic Gaussian offsets of standard deviation sigma (world units; a sequence of sigmas is
    cycled, sample i using sigma[i % len(sigma)], as DeepSDF mixes two); the last round(n * uniform)
    are uniform in the mesh's bounding box grown by box_margin times its longest side on every side.
    sdf is voxfx's signed distance: exact, negative inside (sign: auto = the exact parity test for
    closed meshes, the generalized winding number otherwise; trimesh's convention is the opposite:
    negate it for trimesh). inside is sdf < 0 (a point on the surface that the inside test puts
    inside has sdf -0.0 and is inside). Deterministic for a seed whatever the thread count.
    as_tensor=True returns torch tensors. The GIL is released; Ctrl-C stops it.
    """
    (mesh, sigma), _ = untensor_args((mesh, sigma), {})
    if hasattr(sigma, "tolist"):
        sigma = sigma.tolist()
    return _out(_voxfx.sample_near_surface(mesh, n, sigma, seed, uniform=uniform, box_margin=box_margin, sign=sign,
                                           winding_beta=winding_beta, threads=threads), as_tensor)


def voxelize_many(meshes, resolution=None, *, dims=None, cube=True, padding=0, mode="solid", fill="auto", threads=0,
                  sparse=False, as_tensor=False):
    """Voxelizes many meshes in one call into one array.

    meshes: a list of mesh paths or of anything voxelize takes (voxfx.Mesh, trimesh, (V, F) pairs of
    arrays or CPU tensors). Each grid is voxelize(mesh, resolution=R, cube=True, padding=padding,
    mode=mode, fill=fill) (default R = 64), or dims=(nx, ny, nz) with cube=False. The meshes run in
    parallel (threads: 0 = all cores), the result is the same for any thread count.

    Returns a bool array (B, R, R, R) indexed [b, x, y, z]; sparse=True instead returns the filled
    cells as an (N, 4) int32 array of rows (b, i, j, k) with the batch index first, the convention of
    MinkowskiEngine (ME.utils.batched_coordinates) and spconv (SparseConvTensor's indices, with
    spatial_shape (R, R, R)), cells of a grid in np.argwhere's order, no dense array built.
    as_tensor=True returns a torch tensor (torch.bool or torch.int32). A mesh that fails raises
    voxfx.Error naming the first failing item. The GIL is released; Ctrl-C stops it.
    """
    if isinstance(meshes, (str, bytes)) or hasattr(meshes, "__fspath__"):
        raise TypeError("meshes must be a list of mesh paths or mesh objects (one path is not a batch)")
    meshes = [untensor_args((m,), {})[0][0] for m in meshes]
    return _out(_voxfx.voxelize_many(meshes, resolution, dims=dims, cube=cube, padding=padding, mode=mode, fill=fill,
                                     threads=threads, sparse=sparse), as_tensor)


def marching_cubes(field, iso=0.0, *, spacing=None, origin=None, adaptivity=0.0, inside="below", threads=0):
    """The iso-surface of a field as a voxfx.SurfaceMesh (vertices, faces, normals, save, to_mesh),
    by OpenVDB's volumeToMesh.

    field: a voxfx.LevelSet or voxfx.SignedDistanceField (world coordinates; iso within the band),
    or a 3-D array or CPU tensor indexed [i, j, k] whose value (i, j, k) lies at origin + (i, j, k) *
    spacing (spacing: a number or three, default 1; origin: default 0). inside='below' (default):
    values below iso are inside (signed distances in voxfx's convention, negative inside);
    inside='above': values above iso are inside (occupancy, density, trimesh's positive-inside
    distances). Triangles are counter-clockwise seen from outside and normals point outwards. Beyond
    an array the field counts as outside, so the mesh is closed at the array's box. adaptivity in
    [0, 1]: 0 keeps OpenVDB's uniform mesh, larger merges flat regions.
    """
    return _voxfx.marching_cubes(untensor(field), iso, spacing=untensor(spacing), origin=untensor(origin),
                                 adaptivity=adaptivity, inside=inside, threads=threads)


class AttributeGrid:
    """Per-voxel attributes of a mesh (voxfx.attributes): NumPy arrays indexed [x, y, z] (vectors
    [x, y, z, c]) for the channels asked for, and the grid's placement.

    Channels: count (uint16: writes per voxel), normal (float32 (.., 3): the unit average of the
    writes' triangle normals, outward for closed meshes), material (int32: the material index of
    the voxel's first write, -1 where nothing was written), ior (float32: that material's refraction
    index, 0 where unwritten), attenuation (float32 (.., 3): its Beer-Lambert coefficient), color
    (float32 (.., 3): the mean per-vertex colour of the writes, 0 where unwritten) with color_count
    (uint32: its writes). A channel is an attribute (grid.normal) and an item (grid["normal"]).
    Voxel (i, j, k) covers origin + (i, j, k) * cell_size to origin + (i + 1, j + 1, k + 1) *
    cell_size; affine maps (i, j, k, 1) to its centre. Pickles as its arrays.
    """

    def __init__(self, arrays, origin, cell_size, dims):
        self.arrays = dict(arrays)
        self.origin = tuple(origin)
        self.cell_size = tuple(cell_size)
        self.dims = tuple(dims)

    @property
    def channels(self):
        """The names of the channels held."""
        return tuple(self.arrays)

    def __getitem__(self, name):
        return self.arrays[name]

    def __getattr__(self, name):
        arrays = self.__dict__.get("arrays", {})
        if name in arrays:
            return arrays[name]
        raise AttributeError(f"voxfx.AttributeGrid has no channel or attribute {name!r} (channels: "
                             f"{', '.join(arrays) or 'none'})")

    @property
    def affine(self):
        """4 x 4 matrix from (i, j, k, 1) to the centre of voxel (i, j, k)."""
        import numpy as np

        a = np.eye(4)
        for k in range(3):
            a[k, k] = self.cell_size[k]
            a[k, 3] = self.origin[k] + 0.5 * self.cell_size[k]
        return a

    def occupancy(self):
        """bool [x, y, z]: the voxels written at least once (from count, material, ior or color)."""
        for name, empty in (("count", 0), ("material", -1), ("color_count", 0), ("ior", 0)):
            if name in self.arrays:
                return self.arrays[name] != empty
        raise ValueError("occupancy needs the count, material, color or ior channel")

    def save(self, path, channel=None):
        """Writes the library's channels as `voxfx attributes` does (atomically): .vdb (every channel,
        or the one named), .nrrd or .npy (one channel: the grid's only one, or `channel`). The color
        channel is voxfx's own and not in these formats: np.save(path, grid.color) writes it."""
        arrays = {k: v for k, v in self.arrays.items() if k not in ("color", "color_count")}
        _voxfx._write_attributes(path, arrays, self.origin, self.cell_size, self.dims, channel)

    def __repr__(self):
        return (f"<voxfx.AttributeGrid {self.dims[0]} x {self.dims[1]} x {self.dims[2]}, cell "
                f"{self.cell_size[0]:g}, channels {', '.join(self.arrays)}>")


AttributeGrid.__module__ = "voxfx"


def attributes(mesh, *, channels=None, colors=None, resolution=None, voxel_size=None, dims=None, bounds=None, margin=1,
               cube=False, padding=0, coverage="center", slab_overlap=0.0, threads=0):
    """`voxfx attributes` in the interpreter: per-voxel counts, normals, materials, refraction indices
    and attenuation (CHANG's attribute voxelization), and per-vertex colours averaged per voxel.

    mesh: a path (a scene file's materials are kept, as the command keeps them; a PLY or COFF
    file's vertex colours too) or anything voxelize takes (one material: ior 1.5). channels: a comma
    list or a sequence of count, normal, material, ior, attenuation, color (default: count, normal,
    material, ior, and color when there are colours). colors: (V, 3) or (V, 4) per-vertex colours
    (uint8 over 255, floats as given), overriding the file's. The grid: as voxelize fits it
    (resolution, default 128 as the command, voxel_size, dims, bounds, margin default 1, cube,
    padding); coverage center (CHANG: each covered column centre's voxel) or conservative (every
    voxel the surface touches); slab_overlap widens the slabs (attribute channels only: colours use
    the writes of slab_overlap 0). Returns a voxfx.AttributeGrid. The GIL is released; Ctrl-C stops
    it.
    """
    (mesh,), _ = untensor_args((mesh,), {})
    out = _voxfx._attributes(mesh, channels=channels, colors=untensor(colors), resolution=resolution,
                             voxel_size=voxel_size, dims=dims, bounds=bounds, margin=margin, cube=cube,
                             padding=padding, coverage=coverage, slab_overlap=slab_overlap, threads=threads)
    origin, cell, size = out.pop("origin"), out.pop("cell_size"), out.pop("dims")
    return AttributeGrid(out, origin, cell, size)


__all__ = ["AttributeGrid", "attributes", "marching_cubes", "sample_near_surface",
           "sample_surface", "voxelize_many"]
