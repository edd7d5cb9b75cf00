"""sample_surface and sample_near_surface (voxfx/surface_sampling.hpp) against independent oracles:
chi-square tests of uniformity (over faces, and over a parallelogram's area), the sampled points on
their faces, signed distances against a brute-force point-triangle distance and a brute-force ray
parity in NumPy, and the Gaussian offsets' moments.

Significance: every chi-square test rejects at p < 1e-4 (a fixed seed makes each test
deterministic; 1e-4 is the chance that a correct sampler fails one with a random seed), and each is
shown to have power: the same statistic rejects a sampler that ignores the areas.
"""
import math
import pickle

import numpy as np
import pytest

import voxfx

ALPHA = 1e-4


def chi2_upper_quantile(dof, alpha=ALPHA):
    """The (1 - alpha) quantile of chi-square with `dof` degrees of freedom (Wilson-Hilferty: within
    a fraction of a percent for dof >= 30, which every test here has)."""
    # The standard normal quantile by bisection on erfc (no SciPy).
    lo, hi = 0.0, 10.0
    for _ in range(100):
        mid = (lo + hi) / 2
        if 0.5 * math.erfc(mid / math.sqrt(2)) > alpha:
            lo = mid
        else:
            hi = mid
    z = lo
    return dof * (1 - 2 / (9 * dof) + z * math.sqrt(2 / (9 * dof))) ** 3


def chi2_statistic(observed, expected):
    return float(((observed - expected) ** 2 / expected).sum())


def grouped(counts, expected, minimum=20.0):
    """Consecutive cells merged until each expects >= minimum (the chi-square approximation's rule)."""
    obs, exp = [], []
    o = e = 0.0
    for c, x in zip(counts, expected):
        o += c
        e += x
        if e >= minimum:
            obs.append(o)
            exp.append(e)
            o = e = 0.0
    if e > 0:
        obs[-1] += o
        exp[-1] += e
    return np.array(obs), np.array(exp)


def face_areas(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def test_faces_are_picked_in_proportion_to_their_area_chi_square(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    v, f = mesh.vertices, mesh.faces
    n = 400_000
    s = voxfx.sample_surface(mesh, n, seed=1)
    area = face_areas(v, f)
    counts = np.bincount(s.faces, minlength=len(f))
    obs, exp = grouped(counts, n * area / area.sum())
    limit = chi2_upper_quantile(len(obs) - 1)
    assert chi2_statistic(obs, exp) < limit
    # Power: faces picked uniformly (areas ignored) fail the same test by far.
    rng = np.random.default_rng(1)
    wrong = np.bincount(rng.integers(0, len(f), n), minlength=len(f))
    assert chi2_statistic(*grouped(wrong, n * area / area.sum())) > 10 * limit


def test_points_are_uniform_over_a_skewed_parallelogram_chi_square():
    # Two triangles of different shapes tiling a parallelogram: mapped back to the unit square by
    # the inverse of the parallelogram's affine map, uniform points stay uniform, so a 20 x 20 grid
    # of equal cells tests both the choice of triangle and the position inside it.
    e1, e2, o = np.array([3.0, 0.2, 0.1]), np.array([1.1, 1.0, -0.4]), np.array([0.5, -2.0, 1.0])
    v = np.array([o, o + e1, o + e1 + e2, o + e2])
    f = np.array([[0, 1, 2], [0, 2, 3]])
    n = 200_000
    s = voxfx.sample_surface((v, f), n, seed=7)
    uv = np.linalg.lstsq(np.stack([e1, e2], axis=1), (s.points - o).T, rcond=None)[0].T
    assert uv.min() > -1e-12 and uv.max() < 1 + 1e-12
    cells = np.minimum((uv * 20).astype(int), 19)
    counts = np.bincount(cells[:, 0] * 20 + cells[:, 1], minlength=400)
    assert chi2_statistic(counts, np.full(400, n / 400)) < chi2_upper_quantile(399)
    # Power: barycentric weights (1 - a, a (1 - b), a b) without the square root of a crowd the
    # points at each triangle's first corner; half the points from each triangle, mapped to (u, v).
    rng = np.random.default_rng(7)
    a, b = rng.random(n // 2), rng.random(n // 2)
    naive = np.concatenate([np.stack([a, a * b], axis=1), np.stack([a * (1 - b), a], axis=1)])
    cells = np.minimum((naive * 20).astype(int), 19)
    wrong = np.bincount(cells[:, 0] * 20 + cells[:, 1], minlength=400)
    assert chi2_statistic(wrong, np.full(400, n / 400)) > 10 * chi2_upper_quantile(399)


def test_points_lie_on_their_faces_with_the_faces_normals(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    v, f = mesh.vertices, mesh.faces
    s = voxfx.sample_surface(mesh, 50_000, seed=3)
    assert s.points.shape == (50_000, 3) and s.points.dtype == np.float64
    assert s.normals.dtype == np.float32 and s.faces.dtype == np.int64
    a, b, c = v[f[s.faces, 0]], v[f[s.faces, 1]], v[f[s.faces, 2]]
    # Barycentric coordinates of each point in its face (least squares in the face's plane).
    m = np.stack([b - a, c - a], axis=2)
    w = np.linalg.solve(np.einsum("nki,nkj->nij", m, m), np.einsum("nki,nk->ni", m, s.points - a))
    residual = np.linalg.norm(a + np.einsum("nij,nj->ni", m, w) - s.points, axis=1)
    scale = np.ptp(v, axis=0).max()
    assert residual.max() < 1e-12 * scale
    assert w.min() > -1e-9 and (w.sum(axis=1)).max() < 1 + 1e-9
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    assert np.abs(s.normals - normal).max() < 1e-6


def test_samples_depend_on_the_seed_and_index_only():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    a = voxfx.sample_surface((v, f), 100_000, seed=5)
    b = voxfx.sample_surface((v, f), 100_000, seed=5, threads=1)
    c = voxfx.sample_surface((v, f), 40_000, seed=5)
    d = voxfx.sample_surface((v, f), 100_000, seed=6)
    for x, y in zip(a, b):
        assert np.array_equal(x, y)
    assert np.array_equal(a.points[:40_000], c.points)
    assert not np.array_equal(a.points, d.points)
    near1 = voxfx.sample_near_surface((v, f), 30_000, 0.05, seed=5, uniform=0.3)
    near2 = voxfx.sample_near_surface((v, f), 30_000, 0.05, seed=5, uniform=0.3, threads=1)
    for x, y in zip(near1, near2):
        assert np.array_equal(x, y)


def point_triangle_distance(p, a, b, c):
    """Brute force: the distance from each point p (K, 3) to each triangle (T, 3) -> (K, T), by
    Ericson's closest-point regions (Real-Time Collision Detection, 5.1.5), vectorized."""
    p = p[:, None, :]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = 1 / (va + vb + vc)
        v_in, w_in = vb * denom, vc * denom
        q = a + ab * v_in[..., None] + ac * w_in[..., None]  # inside the face
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    q = np.where(((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0))[..., None], b + (c - b) * t_bc[..., None], q)
    q = np.where(((vb <= 0) & (d2 >= 0) & (d6 <= 0))[..., None], a + ac * t_ac[..., None], q)
    q = np.where(((vc <= 0) & (d1 >= 0) & (d3 <= 0))[..., None], a + ab * t_ab[..., None], q)
    q = np.where(((d6 >= 0) & (d5 <= d6))[..., None], np.broadcast_to(c, q.shape), q)
    q = np.where(((d3 >= 0) & (d4 <= d3))[..., None], np.broadcast_to(b, q.shape), q)
    q = np.where(((d1 <= 0) & (d2 <= 0))[..., None], np.broadcast_to(a, q.shape), q)
    return np.linalg.norm(p - q, axis=-1)


def ray_parity_inside(points, a, b, c, direction):
    """Brute force: a ray from each point along `direction` crosses the closed mesh an odd number of
    times (Moller-Trumbore over every triangle)."""
    e1, e2 = b - a, c - a
    h = np.cross(direction, e2)
    det = (e1 * h).sum(-1)
    inv = 1 / det
    s = points[:, None, :] - a
    u = (s * h).sum(-1) * inv
    q = np.cross(s, e1)
    v = (q * direction).sum(-1) * inv
    t = (q * e2).sum(-1) * inv
    hit = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return hit.sum(axis=1) % 2 == 1


def test_near_surface_distances_and_signs_match_brute_force(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    v, f = mesh.vertices, mesh.faces
    scale = np.ptp(v, axis=0).max()
    s = voxfx.sample_near_surface(mesh, 1500, [0.01 * scale, 0.002 * scale], seed=11, uniform=0.2)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    brute = np.concatenate([point_triangle_distance(s.points[i:i + 100], a, b, c).min(axis=1)
                            for i in range(0, len(s.points), 100)])
    assert np.abs(np.abs(s.sdf) - brute).max() < 1e-9 * scale
    # Signs: a ray in a direction no edge or face of the mesh is parallel to, in practice.
    direction = np.array([0.5773, 0.5779, 0.5768])
    inside = np.concatenate([ray_parity_inside(s.points[i:i + 100], a, b, c, direction)
                             for i in range(0, len(s.points), 100)])
    assert np.array_equal(s.inside, inside)
    assert np.array_equal(s.inside, np.signbit(s.sdf))
    assert 0.2 < s.inside.mean() < 0.8


def test_near_surface_offsets_are_gaussian_around_the_surface_samples(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    n, sigma = 200_000, 0.004
    near = voxfx.sample_near_surface(mesh, n, sigma, seed=2)
    surface = voxfx.sample_surface(mesh, n, seed=2)  # the same seed: the same surface points
    offset = near.points - surface.points
    # Each coordinate N(0, sigma^2): the mean within 5 standard errors of 0, the variance within 5
    # of sigma^2 (the variance of a sample variance is 2 sigma^4 / n).
    assert np.abs(offset.mean(axis=0)).max() < 5 * sigma / math.sqrt(n)
    assert np.abs(offset.var(axis=0) - sigma**2).max() < 5 * sigma**2 * math.sqrt(2 / n)
    # The distance to the surface never exceeds the offset from a point of it.
    assert (np.abs(near.sdf) <= np.linalg.norm(offset, axis=1) + 1e-12).all()


def test_uniform_samples_fill_the_grown_box(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    lo, hi = (np.array(b) for b in mesh.bounds)
    grow = 0.25 * (hi - lo).max()
    s = voxfx.sample_near_surface(mesh, 100_000, 0.01, seed=4, uniform=0.5, box_margin=0.25)
    box = s.points[50_000:]
    assert (box >= lo - grow).all() and (box <= hi + grow).all()
    # Uniform per axis: 10 equal bins each, chi-square.
    for k in range(3):
        counts = np.bincount(((box[:, k] - lo[k] + grow) / (hi[k] - lo[k] + 2 * grow) * 10).astype(int), minlength=10)
        assert chi2_statistic(counts[:10], np.full(10, 5000.0)) < chi2_upper_quantile(9, ALPHA)


def test_bad_arguments_raise_clear_errors():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    f = np.array([[0, 1, 2]])
    with pytest.raises(voxfx.ArgumentError, match="sigma"):
        voxfx.sample_near_surface((v, f), 10, -1.0)
    with pytest.raises(voxfx.ArgumentError, match="sigma"):
        voxfx.sample_near_surface((v, f), 10, [])
    with pytest.raises(voxfx.ArgumentError, match="uniform"):
        voxfx.sample_near_surface((v, f), 10, 0.1, uniform=1.5)
    with pytest.raises(voxfx.ArgumentError, match="n must be"):
        voxfx.sample_surface((v, f), -1)
    with pytest.raises(voxfx.ArgumentError, match="seed"):
        voxfx.sample_surface((v, f), 1, seed=-3)
    with pytest.raises(voxfx.Error, match="zero area"):
        voxfx.sample_surface((np.zeros((3, 3)), f), 10)
    with pytest.raises(voxfx.ArgumentError, match="vertex index"):
        voxfx.sample_surface((v, np.array([[0, 1, 7]])), 10)
    empty = voxfx.sample_surface((v, f), 0)
    assert empty.points.shape == (0, 3) and empty.faces.shape == (0,)


def test_samples_pickle_and_recentred_meshes_keep_their_place():
    # float64 vertices far from the origin are recentred inside voxfx (Mesh.origin): the samples
    # come back in the caller's coordinates.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * 1e-3 + 5e6
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    s = voxfx.sample_surface((v, f), 1000, seed=1)
    assert (s.points >= v.min(axis=0) - 1e-6).all() and (s.points <= v.max(axis=0) + 1e-6).all()
    again = pickle.loads(pickle.dumps(s))
    assert np.array_equal(again.points, s.points) and type(again).__name__ == "SurfaceSamples"
