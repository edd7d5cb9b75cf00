"""Distances from the interpreter: closest_points, signed_distance and sdf, against references in
NumPy written from the definitions (brute force over every triangle, on small meshes), against
contains() and voxelize() for the signs, and OpenVDB's Python module for the .vdb level set."""
import math

import numpy as np
import pytest

import voxfx


def brute_force_distance(vertices, faces, points):
    """(K, F) distances from every point to every (closed) triangle, in NumPy: the minimum over
    the plane projection (when it falls in the triangle) and the three edge segments."""
    v = np.asarray(vertices, np.float64)
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    p = np.asarray(points, np.float64)[:, None, :]

    def segment(s0, s1):
        e = s1 - s0
        ee = np.einsum("ij,ij->i", e, e)
        t = np.where(ee > 0, np.einsum("kij,ij->ki", p - s0, e) / np.where(ee > 0, ee, 1), 0.0)
        t = np.clip(t, 0.0, 1.0)
        return np.linalg.norm(p - (s0 + t[..., None] * e), axis=-1)

    best = np.minimum(np.minimum(segment(a, b), segment(b, c)), segment(c, a))
    n = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", n, n)
    ok = nn > 0
    unit = np.where(ok[:, None], n / np.sqrt(np.where(ok, nn, 1))[:, None], 0)
    h = np.einsum("kij,ij->ki", p - a, unit)
    foot = p - h[..., None] * unit
    inside = np.ones(h.shape, bool)
    for s0, s1 in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("kij,ij->ki", np.cross(s1 - s0, foot - s0), n) >= 0
    return np.where(inside & ok, np.minimum(best, np.abs(h)), best)


def brute_force_min(vertices, faces, points, chunk=512):
    """The smallest distance of brute_force_distance, a chunk of points at a time."""
    return np.concatenate([brute_force_distance(vertices, faces, points[s:s + chunk]).min(1)
                           for s in range(0, len(points), chunk)])


def octahedron():
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float64) * 0.75
    v += [0.25, -0.5, 0.125]
    f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return v, f


def test_closest_points_match_brute_force_on_small_meshes(data_path):
    for v, f in (octahedron(), voxfx.load_mesh(data_path("meshes/cube-meshed.off"))):
        v = np.asarray(v, np.float64)
        rng = np.random.default_rng(3)
        lo, hi = v.min(0), v.max(0)
        pts = np.concatenate([rng.uniform(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo), (800, 3)), v])
        r = voxfx.closest_points(v, f, pts)
        assert isinstance(r, voxfx.ClosestPoints)
        d = brute_force_distance(v.astype(np.float32), f, pts)
        np.testing.assert_allclose(r.distance, d.min(1), rtol=0, atol=1e-12)
        # The face attains the minimum; the point lies at that distance and is the weighted corners.
        np.testing.assert_allclose(d[np.arange(len(pts)), r.face], d.min(1), rtol=0, atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(r.point - pts, axis=1), r.distance, rtol=0, atol=1e-12)
        corners = v.astype(np.float32).astype(np.float64)[f[r.face]]
        np.testing.assert_allclose(np.einsum("kc,kcj->kj", r.barycentric, corners), r.point, atol=1e-12)
        assert r.barycentric.min() >= -1e-15 and np.allclose(r.barycentric.sum(1), 1)
        assert r.face.dtype == np.int64 and r.point.dtype == np.float64
        # Vertices are on the mesh.
        np.testing.assert_array_less(r.distance[-len(v):], 1e-15)


def test_non_finite_points_get_nan_and_no_face():
    v, f = octahedron()
    r = voxfx.closest_points(v, f, np.array([[np.nan, 0, 0], [0, np.inf, 0], [0.25, -0.5, 2]]))
    assert list(r.face[:2]) == [-1, -1]
    assert np.isnan(r.distance[:2]).all() and np.isnan(r.point[:2]).all()
    assert r.face[2] >= 0 and math.isclose(r.distance[2], 2 - 0.125 - 0.75, abs_tol=1e-12)
    assert np.isnan(voxfx.signed_distance(v, f, np.array([[np.nan, 0, 0]]))[0])


def test_signed_distance_is_the_distance_with_the_sign_of_contains(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    lo, hi = np.array(mesh.bounds)
    pts = np.random.default_rng(1).uniform(lo, hi, (20000, 3))
    sd = voxfx.signed_distance(mesh, pts)
    d = voxfx.closest_points(mesh, pts).distance
    np.testing.assert_array_equal(np.abs(sd), d)
    np.testing.assert_array_equal(np.signbit(sd), voxfx.contains(mesh, pts))
    np.testing.assert_array_equal(voxfx.signed_distance(mesh, pts, sign="parity", threads=1), sd)
    winding = voxfx.signed_distance(mesh, pts, sign="winding")
    assert np.mean(np.signbit(winding) == np.signbit(sd)) > 0.999
    with pytest.raises(voxfx.Error, match="unknown sign method"):
        voxfx.signed_distance(mesh, pts, sign="inside")
    with pytest.raises(ValueError):
        voxfx.signed_distance(mesh, pts[:, :2])
    with pytest.raises(TypeError):
        voxfx.closest_points(mesh)


def test_sdf_matches_brute_force_and_the_solid_grid(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/eight.off"))
    v, f = mesh
    field = voxfx.sdf(mesh, resolution=24)
    assert isinstance(field, voxfx.SignedDistanceField)
    dense = field.to_numpy()
    nx, ny, nz = field.dims
    assert dense.shape == (nx, ny, nz) and dense.dtype == np.float32
    # The affine maps indices to voxel centres.
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    ijk = np.stack([i, j, k], axis=-1).reshape(-1, 3)
    centres = ijk @ field.affine[:3, :3].T + field.affine[:3, 3]
    np.testing.assert_allclose(centres[1], np.array(field.origin) + (ijk[1] + 0.5) * np.array(field.cell_size))
    exact = brute_force_min(v, f, centres).reshape(nx, ny, nz)
    band = exact < field.background * (1 - 1e-6)
    assert band.sum() > 1000
    np.testing.assert_allclose(np.abs(dense[band]), exact[band], rtol=2 ** -23, atol=1e-12)
    far = exact > field.background * (1 + 1e-6)
    np.testing.assert_array_equal(np.abs(dense[far]), np.float32(field.background))
    # The sign is the solid voxelization's bit, with the same grid (resolution 24 and a margin of 3).
    solid = voxfx.voxelize(mesh, resolution=24, margin=3, fill="parity").to_numpy()
    assert solid.sum() > 500
    np.testing.assert_array_equal(np.signbit(dense), solid)
    # The band as indices and values, without a dense array.
    idx, values = field.active()
    assert idx.dtype == np.int32 and idx.shape == (field.active_count, 3)
    np.testing.assert_array_equal(values, dense[idx[:, 0], idx[:, 1], idx[:, 2]])
    np.testing.assert_array_equal(np.sort(np.flatnonzero(band)),
                                  np.sort(np.ravel_multi_index(idx.T, dense.shape)))
    assert field.value(*idx[0]) == values[0]
    np.testing.assert_array_equal(np.asarray(field), dense)


def test_sdf_full_band_and_options(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/joint.off"))
    v, f = mesh
    field = voxfx.sdf(mesh, resolution=12, band="full", margin=2)
    assert field.full and field.active_count == np.prod(field.dims)
    dense = field.to_numpy()
    idx, _ = field.active()
    centres = idx @ field.affine[:3, :3].T + field.affine[:3, 3]
    exact = brute_force_min(v, f, centres)
    np.testing.assert_allclose(np.abs(dense[idx[:, 0], idx[:, 1], idx[:, 2]]), exact, rtol=2 ** -23, atol=1e-12)
    assert voxfx.sdf(mesh, voxel_size=0.25, band=1.5).band == 1.5
    for bad in (0.5, float("nan"), "wide"):
        with pytest.raises(ValueError):
            voxfx.sdf(mesh, resolution=8, band=bad)
    with pytest.raises(ValueError):
        voxfx.sdf(mesh, resolution=8, voxel_size=0.1)


def test_sdf_of_an_open_mesh_takes_the_gwn_sign(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant-with-holes.off"))
    field = voxfx.sdf(mesh, resolution=32)
    assert field.fill == "gwn"
    solid = voxfx.voxelize(mesh, resolution=32, margin=3, fill="gwn").to_numpy()
    np.testing.assert_array_equal(np.signbit(field.to_numpy()), solid)


def test_sdf_vdb_opens_in_openvdb_as_a_level_set(data_path, tmp_path):
    vdb = pytest.importorskip("pyopenvdb")
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    field = voxfx.sdf(mesh, resolution=48)
    path = tmp_path / "knot.vdb"
    field.save(path)
    grid = vdb.read(str(path), "sdf")
    assert grid.gridClass == "level set"
    assert math.isclose(grid.background, field.background, rel_tol=1e-7)
    assert grid.activeVoxelCount() == field.active_count
    np.testing.assert_allclose(grid.transform.voxelSize(), field.cell_size, rtol=1e-12)
    for ijk in ((0, 0, 0), (5, 17, 23)):
        np.testing.assert_allclose(grid.transform.indexToWorld(ijk),
                                   field.affine[:3, :3] @ np.array(ijk) + field.affine[:3, 3], atol=1e-12)
    dense = np.zeros(field.dims, np.float32)
    grid.copyToArray(dense)
    np.testing.assert_array_equal(dense, field.to_numpy())


def test_gil_is_released_while_computing_distances(data_path, gil_stall):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    pts = np.random.default_rng(2).uniform(-0.6, 0.6, (20000, 3))
    duration, gap = gil_stall(lambda: voxfx.closest_points(mesh, pts, threads=1))
    assert duration > 0.01
    assert gap < 0.5 * duration
