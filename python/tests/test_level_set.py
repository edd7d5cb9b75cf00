"""Level sets from the interpreter: voxfx.LevelSet, read_level_set, level_set, level_set_csg (with a
mesh operand on the level set's lattice) and offset_level_set.

Oracles: closed forms written here in NumPy. Boxes have an exact signed distance (the distance to a
box's surface is the distance to its triangles), so CSG with a box is compared at every voxel with
min / max / max(a, -b) of the analytic distances clamped to the band; spheres (fine UV spheres)
with the analytic sphere's distance, within the polyhedron's distance from the sphere, and their
signs with the analytic inside test away from that shell."""
import math
import warnings

import numpy as np
import pytest

import voxfx

H = 0.05  # voxel size of the lattices below


def uv_sphere(center, radius, rings=48, segments=96):
    """A closed UV sphere (vertices on the sphere, outward faces) as (vertices, faces)."""
    theta = np.pi * np.arange(1, rings) / rings
    phi = 2 * np.pi * np.arange(segments) / segments
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    v = np.concatenate([[[0, 0, 1]], ring, [[0, 0, -1]]]) * radius + center
    south = len(v) - 1
    faces = []
    for s in range(segments):
        n = (s + 1) % segments
        faces.append([0, 1 + s, 1 + n])
        for r in range(rings - 2):
            a, b = 1 + r * segments + s, 1 + r * segments + n
            c, d = a + segments, b + segments
            faces += [[a, c, d], [a, d, b]]
        last = 1 + (rings - 2) * segments
        faces.append([last + s, south, last + n])
    return v, np.array(faces)


def sphere_gap(radius, rings=48, segments=96):
    """An upper bound of the distance between uv_sphere's faces and the sphere: a face lies within
    its circumscribed cap, whose angular radius is at most the quad's diagonal angle."""
    step = max(np.pi / rings, 2 * np.pi / segments)
    return radius * (1 - math.cos(step * math.sqrt(2)))


def box_mesh(lo, hi):
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    v = np.array([[x, y, z] for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])])
    f = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3],
                  [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]])
    return v, f


def box_distance(lo, hi, p):
    c, h = (np.asarray(lo) + np.asarray(hi)) / 2, (np.asarray(hi) - np.asarray(lo)) / 2
    q = np.abs(p - c) - h
    return np.linalg.norm(np.maximum(q, 0), axis=-1) + np.minimum(q.max(-1), 0)


def combine(op, a, b):
    return {"union": np.minimum(a, b), "intersection": np.maximum(a, b), "difference": np.maximum(a, -b)}[op]


def clamp(d, w):
    return np.where(np.abs(d) < w, d, np.copysign(w, d))


def index_box(ls, lo, hi):
    """Every index whose world position lies in [lo, hi], as (N, 3) int64, and those positions."""
    origin, h = np.array(ls.index_origin), np.array(ls.voxel_size)
    first = np.floor((np.asarray(lo) - origin) / h).astype(np.int64)
    last = np.ceil((np.asarray(hi) - origin) / h).astype(np.int64)
    axes = [np.arange(first[a], last[a] + 1) for a in range(3)]
    ijk = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return ijk, ijk @ ls.affine[:3, :3].T + ls.affine[:3, 3]


# Two overlapping spheres; the second is given to the CSG as a mesh (on the first's lattice).
CA, RA = np.array([0.0, 0.0, 0.0]), 0.6
CB, RB = np.array([0.45, 0.1, -0.05]), 0.5


def test_csg_of_a_level_set_and_a_sphere_mesh_matches_the_analytic_spheres():
    a = voxfx.level_set(uv_sphere(CA, RA), voxel_size=H)
    assert isinstance(a, voxfx.LevelSet) and a.axis_aligned
    np.testing.assert_allclose(a.voxel_size, (H, H, H), rtol=1e-12)
    assert a.band == pytest.approx(3) and a.background == pytest.approx(3 * H, rel=1e-6)
    mesh_b = voxfx.Mesh(*uv_sphere(CB, RB))
    ijk, p = index_box(a, CA - 1.0, CB + 0.8)
    da, db = np.linalg.norm(p - CA, axis=1) - RA, np.linalg.norm(p - CB, axis=1) - RB
    w = a.background
    # The meshes lie within `gap` of the spheres; min and max move by no more than their inputs.
    gap = max(sphere_gap(RA), sphere_gap(RB))
    assert gap < 0.06 * H
    shell = (np.abs(da) < gap + 1e-6) | (np.abs(db) < gap + 1e-6)
    for op, result in (("union", a | mesh_b), ("intersection", a & mesh_b), ("difference", a - mesh_b),
                       ("union", voxfx.level_set_csg(a, mesh_b, "union", threads=1))):
        assert result.voxel_size == a.voxel_size and result.index_origin == a.index_origin
        got = result.value(ijk)
        assert got.dtype == np.float32 and got.shape == (len(ijk),)
        inside = {"union": (da < 0) | (db < 0), "intersection": (da < 0) & (db < 0),
                  "difference": (da < 0) & ~(db < 0)}[op]
        assert inside[~shell].sum() > 1000, op
        np.testing.assert_array_equal(np.signbit(got[~shell]), inside[~shell], err_msg=op)
        expected = combine(op, clamp(da, w), clamp(db, w))
        np.testing.assert_allclose(got, expected, rtol=0, atol=gap + 1e-6, err_msg=op)


def test_csg_with_a_box_mesh_is_exact_at_every_voxel_in_either_order():
    lo_a, hi_a = np.array([-0.53125, -0.40625, -0.46875]), np.array([0.40625, 0.53125, 0.34375])
    lo_b, hi_b = np.array([-0.15625, -0.65625, -0.21875]), np.array([0.78125, 0.21875, 0.65625])
    # A lattice whose centres sit at odd multiples of 0.025 plus 0.0123: never on a box face.
    a = voxfx.level_set(box_mesh(lo_a, hi_a), voxel_size=H, bounds=[-1.0123, -1, -1, 1, 1, 1])
    b = box_mesh(lo_b, hi_b)
    ijk, p = index_box(a, [-1, -1, -1], [1.2, 1.2, 1.2])
    da, db = box_distance(lo_a, hi_a, p), box_distance(lo_b, hi_b, p)
    w = a.background
    edge = (np.abs(np.abs(da) - w) < 1e-5) | (np.abs(np.abs(db) - w) < 1e-5)
    for op in ("union", "intersection", "difference"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no resampling warning: the mesh joins on a's lattice
            ab = voxfx.level_set_csg(a, b, op)
            ba = voxfx.level_set_csg(b, a, op)
        np.testing.assert_allclose(ab.value(ijk)[~edge], combine(op, clamp(da, w), clamp(db, w))[~edge],
                                   rtol=0, atol=2e-6, err_msg=op)
        np.testing.assert_allclose(ba.value(ijk)[~edge], combine(op, clamp(db, w), clamp(da, w))[~edge],
                                   rtol=0, atol=2e-6, err_msg=op)
    # The operators with the mesh on the left (the level set's reflected operators).
    for op, result in (("union", b | a), ("intersection", b & a), ("difference", b - a),
                       ("difference", voxfx.Mesh(*b) - a)):
        np.testing.assert_allclose(result.value(ijk)[~edge], combine(op, clamp(db, w), clamp(da, w))[~edge],
                                   rtol=0, atol=2e-6, err_msg=op)
    # The box's own level set on a's lattice: active exactly within the band.
    lb = voxfx.level_set(b, like=a)
    idx, values = lb.active_voxels()
    pb = idx @ a.affine[:3, :3].T + a.affine[:3, 3]
    d = box_distance(lo_b, hi_b, pb)
    assert idx.dtype == np.int32 and values.dtype == np.float32 and len(values) == lb.active_count > 1000
    assert np.all(np.abs(d) < w + 1e-6)
    np.testing.assert_allclose(values, d, rtol=0, atol=2e-6)


def test_a_mesh_far_from_the_origin_joins_on_the_lattice_exactly():
    # float64 vertices far away are recentred by the module; the lattice is in world coordinates.
    shift = np.array([1000.3, -2000.1, 500.7])
    lo_a, hi_a = shift + [-0.53125, -0.40625, -0.46875], shift + [0.40625, 0.53125, 0.34375]
    lo_b, hi_b = shift + [-0.15625, -0.65625, -0.21875], shift + [0.78125, 0.21875, 0.65625]
    a = voxfx.level_set(box_mesh(lo_a, hi_a), voxel_size=H)
    r = a.difference(box_mesh(lo_b, hi_b))
    ijk, p = index_box(a, shift - 1, shift + 1)
    da, db = box_distance(lo_a, hi_a, p), box_distance(lo_b, hi_b, p)
    w = a.background
    edge = (np.abs(np.abs(da) - w) < 1e-4) | (np.abs(np.abs(db) - w) < 1e-4)
    # Vertices rounded to float32 around the mesh's own origin: within 1e-6 of the float64 boxes.
    np.testing.assert_allclose(r.value(ijk)[~edge], np.maximum(clamp(da, w), -clamp(db, w))[~edge], rtol=0,
                               atol=1e-5)


def test_write_and_read_round_trip(tmp_path):
    a = voxfx.level_set(uv_sphere(CA, RA), voxel_size=H, name="ball")
    r = a - uv_sphere(CB, RB)
    path = tmp_path / "r.vdb"
    r.save(path)
    back = voxfx.read_level_set(path)
    assert back.name == "ball" and back.active_count == r.active_count > 1000
    assert back.voxel_size == r.voxel_size and back.index_origin == r.index_origin
    assert back.background == r.background and back.active_bounds == r.active_bounds
    i0, v0 = r.active_voxels()
    i1, v1 = back.active_voxels()
    np.testing.assert_array_equal(i0, i1)
    np.testing.assert_array_equal(v0, v1)
    r.write(tmp_path / "w.vdb")
    assert voxfx.read_level_set(str(tmp_path / "w.vdb")).active_count == r.active_count
    # value(): one index gives a float, many an array; far away it is the background.
    assert back.value(i0[7]) == v0[7]
    np.testing.assert_array_equal(back.value(i0[::5].astype(np.int64)), v0[::5])
    far = back.value(np.array([[10 ** 6, 0, 0], [-(10 ** 6), 5, 5]]))
    np.testing.assert_array_equal(far, [back.background, back.background])
    vdb = pytest.importorskip("pyopenvdb")
    grid = vdb.read(str(path), "ball")
    assert grid.gridClass == "level set" and grid.activeVoxelCount() == r.active_count


def test_a_signed_distance_field_becomes_the_same_level_set():
    field = voxfx.sdf(uv_sphere(CA, RA), voxel_size=H)
    ls = voxfx.level_set(field)
    idx, values = field.active()
    np.testing.assert_array_equal(ls.value(idx), values)
    assert ls.active_count == field.active_count
    np.testing.assert_array_equal(ls.affine, field.affine)
    with pytest.raises(ValueError):
        voxfx.level_set(field, voxel_size=0.1)


def test_offset_moves_a_sphere_within_a_twentieth_of_a_voxel():
    a = voxfx.level_set(uv_sphere(CA, RA), voxel_size=H)
    for d in (0.1, -0.1):
        moved = voxfx.offset_level_set(a, d)
        idx, values = moved.active_voxels()
        p = idx @ moved.affine[:3, :3].T + moved.affine[:3, 3]
        expected = np.linalg.norm(p - CA, axis=1) - (RA + d)
        near = np.abs(expected) < 1.5 * H
        assert near.sum() > 1000
        # OpenVDB's tracker is approximate (the C++ test measured 0.018 voxel with the faceting).
        assert np.abs(values[near] - expected[near]).max() < 0.05 * H


def test_lattices_on_different_grids_warn_that_they_were_resampled():
    a = voxfx.level_set(uv_sphere(CA, RA), voxel_size=H)
    b = voxfx.level_set(uv_sphere(CB, RB), voxel_size=H * 1.1)
    with pytest.warns(RuntimeWarning, match="resampled"):
        voxfx.level_set_csg(a, b, "union")


def test_bad_input_is_a_clear_error(tmp_path):
    grid_path = tmp_path / "occ.vdb"
    voxfx.voxelize(uv_sphere(CA, RA), resolution=16).save(grid_path)
    with pytest.raises(voxfx.Error, match="not a level set"):
        voxfx.read_level_set(grid_path)
    with pytest.raises(voxfx.Error, match="missing.vdb"):
        voxfx.read_level_set(tmp_path / "missing.vdb")
    a = voxfx.level_set(uv_sphere(CA, RA), voxel_size=H)
    with pytest.raises(ValueError, match="needs a voxfx.LevelSet"):
        voxfx.level_set_csg(uv_sphere(CA, RA), uv_sphere(CB, RB))
    with pytest.raises(ValueError):
        voxfx.level_set_csg(a, uv_sphere(CB, RB), "nand")
    with pytest.raises(ValueError, match="like="):
        voxfx.level_set(uv_sphere(CB, RB), like=a, voxel_size=0.1)
    with pytest.raises(TypeError):
        a.value(np.zeros((4, 3)) + 0.5)
    with pytest.raises(TypeError):
        a.value(np.zeros((4, 2), np.int32))
    with pytest.raises(ValueError, match="32-bit"):
        a.value(np.array([[2 ** 40, 0, 0]]))
    v, f = uv_sphere(CB, RB)
    f[3, 1] = len(v) + 5
    with pytest.raises(ValueError):
        a | (v, f)
    with pytest.raises(ValueError):
        voxfx.offset_level_set(a, float("nan"))


def test_gil_is_released_while_a_mesh_joins_a_level_set(gil_stall):
    a = voxfx.level_set(uv_sphere(CA, RA), voxel_size=0.02)
    b = uv_sphere(CB, RB, rings=96, segments=192)
    duration, gap = gil_stall(lambda: voxfx.level_set_csg(a, b, "difference", threads=1))
    assert duration > 0.01
    assert gap < 0.5 * duration
