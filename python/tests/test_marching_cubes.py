"""marching_cubes (voxfx/volume_to_mesh.hpp, OpenVDB's volumeToMesh) against independent oracles: a
sphere's analytic field (vertices within a stated distance of the sphere, the enclosed volume), a
topology check written here in NumPy (every edge shared by two triangles in opposite directions,
every vertex's triangles one fan, Euler characteristic), outward orientation (signed volume,
normals against the radial direction), and a real mesh's own volume for its level set's surface.
"""
import math
from collections import defaultdict

import numpy as np
import pytest

import voxfx


def sphere_field(n=64, r=0.7, centre=(0.0, 0.0, 0.0)):
    """The exact signed distance to a sphere (negative inside) sampled on n^3 points over [-1, 1]^3."""
    x = np.linspace(-1, 1, n)
    h = x[1] - x[0]
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    c = np.asarray(centre)
    f = np.sqrt((X - c[0]) ** 2 + (Y - c[1]) ** 2 + (Z - c[2]) ** 2) - r
    return f.astype(np.float32), h


def closed_manifold_report(v, f):
    """What is wrong with the mesh as a closed, consistently oriented 2-manifold (empty when nothing),
    and its Euler characteristic over the vertices the triangles use."""
    problems = []
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    if (f[:, 0] == f[:, 1]).any() or (f[:, 1] == f[:, 2]).any() or (f[:, 0] == f[:, 2]).any():
        problems.append("a triangle repeats a vertex")
    keys = directed[:, 0].astype(np.int64) * (len(v) + 1) + directed[:, 1]
    if len(np.unique(keys)) != len(keys):
        problems.append("an edge is used twice in the same direction (misoriented or non-manifold)")
    reverse = directed[:, 1].astype(np.int64) * (len(v) + 1) + directed[:, 0]
    if not np.isin(reverse, keys).all():
        problems.append("an edge has no opposite half (a boundary)")
    # Each vertex's link: the edges opposite it in its triangles must form one cycle.
    link = defaultdict(dict)
    for a, b, c in f.tolist():
        for p, q, r in ((a, b, c), (b, c, a), (c, a, b)):
            if q in link[p]:
                problems.append(f"vertex {p}: its link repeats a vertex")
            link[p][q] = r
    for p, nxt in link.items():
        start = next(iter(nxt))
        q, steps = start, 0
        while True:
            q = nxt.get(q)
            steps += 1
            if q is None or q == start or steps > len(nxt):
                break
        if q != start or steps != len(nxt):
            problems.append(f"vertex {p}: its triangles are not one fan")
            break
    used = np.unique(f)
    edges = len(np.unique(np.sort(directed, axis=1), axis=0))
    return problems, len(used) - edges + len(f)


def signed_volume(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return float((a * np.cross(b, c)).sum() / 6)


def test_a_spheres_field_gives_a_closed_outward_sphere_within_the_stated_distance():
    r = 0.7
    field, h = sphere_field(64, r)
    s = voxfx.marching_cubes(field, spacing=h, origin=(-1, -1, -1))
    v, f = s.vertices, s.faces
    assert len(f) > 1000
    # OpenVDB puts one vertex in each voxel the surface crosses, at the mean of the points where it
    # crosses that voxel's edges (linear interpolation along each edge). Those points lie on the
    # sphere up to the interpolation error of |x| - r along an edge, at most h^2 / (8 r); their
    # mean lies within the sagitta of a chord as long as the voxel's diagonal, 3 h^2 / (8 r),
    # inside the sphere. Together h^2 / (2 r): 7.2e-4 here (h = 2 / 63).
    bound = h * h / (2 * r)
    assert np.abs(np.linalg.norm(v, axis=1) - r).max() < bound
    problems, euler = closed_manifold_report(v, f)
    assert problems == [] and euler == 2
    # Outward: counter-clockwise seen from outside gives a positive volume, close to the ball's
    # (the vertices lie within `bound` of the sphere: the volume within 4 pi r^2 bound of it).
    assert abs(signed_volume(v, f) - 4 / 3 * math.pi * r**3) < 4 * math.pi * r**2 * bound
    assert (np.einsum("ij,ij->i", s.normals, v) > 0).all()


def test_inside_above_meshes_occupancy_like_fields_the_same_way_round():
    field, h = sphere_field(40, 0.6)
    below = voxfx.marching_cubes(field, spacing=h, origin=(-1, -1, -1))
    above = voxfx.marching_cubes(-field, spacing=h, origin=(-1, -1, -1), inside="above")
    assert np.allclose(below.vertices, above.vertices, atol=1e-6)
    assert np.array_equal(below.faces, above.faces)
    assert signed_volume(above.vertices, above.faces) > 0
    # An iso value: the sphere of radius 0.6 + 0.1.
    grown = voxfx.marching_cubes(field, 0.1, spacing=h, origin=(-1, -1, -1))
    assert abs(np.linalg.norm(grown.vertices, axis=1).mean() - 0.7) < h * h


def test_a_solid_cut_by_the_array_border_is_closed_there():
    # A sphere centred on a corner: an eighth of it inside the array, capped by the array's box.
    field, h = sphere_field(32, 0.8, centre=(-1, -1, -1))
    s = voxfx.marching_cubes(field, spacing=h, origin=(-1, -1, -1))
    problems, euler = closed_manifold_report(s.vertices, s.faces)
    assert problems == [] and euler == 2
    assert signed_volume(s.vertices, s.faces) > 0


def test_a_level_set_of_a_real_mesh_gives_a_closed_surface_of_its_volume(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    v, f = mesh.vertices, mesh.faces
    ls = voxfx.level_set(mesh, resolution=96)
    s = voxfx.marching_cubes(ls)
    problems, _ = closed_manifold_report(s.vertices, s.faces)
    assert problems == []
    volume = signed_volume(v, f)
    voxel = ls.voxel_size[0]
    # The surface lies within a small part of a voxel of the mesh's (its vertices: below), so the
    # volumes differ by at most its area times that distance; half a voxel is generous.
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum()
    assert abs(signed_volume(s.vertices, s.faces) - volume) < 0.5 * voxel * area
    d = voxfx.closest_points(mesh, s.vertices[::7]).distance
    assert d.max() < 0.5 * voxel
    # The same surface from the field the level set was made of, narrow band or full.
    field = voxfx.sdf(mesh, resolution=96)
    from_field = voxfx.marching_cubes(field)
    assert len(from_field.faces) == len(s.faces)
    full = voxfx.sdf(mesh, resolution=48, band="full")
    dense = voxfx.marching_cubes(full)
    same = voxfx.marching_cubes(np.asarray(full), spacing=full.cell_size,
                                origin=np.array(full.origin) + np.array(full.cell_size) / 2)
    assert np.array_equal(dense.faces, same.faces) and np.allclose(dense.vertices, same.vertices)
    assert closed_manifold_report(dense.vertices, dense.faces)[0] == []


def test_results_do_not_depend_on_the_thread_count():
    field, h = sphere_field(48, 0.5)
    a = voxfx.marching_cubes(field, spacing=h, threads=1)
    b = voxfx.marching_cubes(field, spacing=h)
    assert np.array_equal(a.faces, b.faces) and np.array_equal(a.vertices, b.vertices)


def test_bad_fields_raise_clear_errors(data_path):
    field, _ = sphere_field(8, 0.5)
    field[1, 2, 3] = np.nan
    with pytest.raises(voxfx.ArgumentError, match=r"\(1, 2, 3\)"):
        voxfx.marching_cubes(field)
    with pytest.raises(TypeError):
        voxfx.marching_cubes(np.zeros((4, 4)))
    with pytest.raises(voxfx.ArgumentError, match="inside"):
        voxfx.marching_cubes(np.zeros((4, 4, 4)), inside="left")
    with pytest.raises(voxfx.ArgumentError, match="adaptivity"):
        voxfx.marching_cubes(np.zeros((4, 4, 4)), adaptivity=2)
    ls = voxfx.level_set(voxfx.load_mesh(data_path("meshes/sphere.off")), resolution=32)
    with pytest.raises(voxfx.ArgumentError, match="band"):
        voxfx.marching_cubes(ls, 10 * ls.background)
    with pytest.raises(voxfx.ArgumentError, match="negative inside"):
        voxfx.marching_cubes(ls, inside="above")
    assert len(voxfx.marching_cubes(np.ones((4, 4, 4))).faces) == 0


def test_torch_fields_are_meshed_like_arrays():
    torch = pytest.importorskip("torch")
    field, h = sphere_field(24, 0.5)
    t = torch.from_numpy(field).requires_grad_(True)
    a = voxfx.marching_cubes(t, spacing=h)
    b = voxfx.marching_cubes(field, spacing=h)
    assert np.array_equal(a.faces, b.faces)
