"""The six defects of issue #24, each against an independent answer: NumPy's exact box test for
axis-aligned boxes, the parity method (itself checked against CGAL in tests/test_contains.cpp,
and orientation-blind by construction) for meshes oriented inward, NumPy re-implementations of
the morphology, elapsed time for Ctrl-C. Each of these failed on the module before the fixes."""
import contextlib
import os
import signal
import threading
import time

import numpy as np
import pytest

import voxfx

INWARD = ["meshes/beam.off", "meshes/tetrahedron.off", "meshes/ellipe0.003.off"]


def signed_volume(v, f):
    a = v[f]
    return float(np.einsum("ij,ij->i", a[:, 0], np.cross(a[:, 1], a[:, 2])).sum() / 6)


def box_mesh(lo, hi, dtype=np.float64):
    """A closed box, outward: 8 corners, 12 triangles."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    v = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]] for i in range(8)],
                 dtype=dtype)
    f = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3],
                  [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]])
    return v, f


# ---- 1. meshes oriented inward under winding and gwn ------------------------------------------

@pytest.mark.parametrize("name", INWARD + ["flipped bunny"])
def test_winding_and_gwn_fill_meshes_oriented_inward(data_path, name):
    if name == "flipped bunny":
        v, f = voxfx.load_mesh(data_path("meshes/bunny00.off"))
        f = f[:, ::-1].copy()
    else:
        v, f = voxfx.load_mesh(data_path(name))
    assert signed_volume(v, f) < 0  # inward throughout
    rng = np.random.default_rng(4)
    lo, hi = v.min(axis=0), v.max(axis=0)
    pts = lo - 0.1 * (hi - lo) + rng.random((3000, 3)) * 1.2 * (hi - lo)
    parity = voxfx.contains(v, f, pts)
    assert parity.sum() > 100
    # Winding is approximate near the surface: compare where parity's grid cell is away from it
    # by checking agreement on all but a thin shell (the beta-3 error is under 0.025).
    winding = voxfx.contains(v, f, pts, method="winding")
    assert (winding != parity).mean() < 0.002
    gwn = voxfx.voxelize(v, f, resolution=32, fill="gwn")
    solid = voxfx.voxelize(v, f, resolution=32, fill="parity")
    surface = voxfx.voxelize(v, f, resolution=32, mode="conservative").to_numpy()
    away = ~surface
    np.testing.assert_array_equal(gwn.to_numpy()[away], solid.to_numpy()[away])
    assert solid.to_numpy()[away].sum() > 50


def test_beam_is_filled_by_gwn_as_by_parity(data_path):
    # The numbers: parity gives 512 cells for beam at 32, gwn gave none.
    mesh = voxfx.load_mesh(data_path("meshes/beam.off"))
    assert voxfx.voxelize(mesh, resolution=32, fill="parity").count() == 512
    assert voxfx.voxelize(mesh, resolution=32, fill="gwn").count() == 512


# ---- 2. float64 vertices far from the origin ----------------------------------------------------

@pytest.mark.parametrize("x0", [5e6, -3.25e7, 1e9])
def test_float64_meshes_far_from_the_origin_keep_their_shape(x0):
    lo, hi = np.array([x0 - 0.15, 2.0, -1.0]), np.array([x0 + 0.15, 2.3, -0.7])
    v, f = box_mesh(lo, hi)
    rng = np.random.default_rng(1)
    pts = lo - 0.2 + rng.random((20000, 3)) * (hi - lo + 0.4)
    # Exact answers from the box (points within 1e-6 of a face are left out: float32 positions
    # of the recentred box are within 1e-8 of the true ones).
    margin = np.minimum(np.abs(pts - lo), np.abs(pts - hi)).min(axis=1)
    keep = margin > 1e-6
    expected = np.all((pts > lo) & (pts < hi), axis=1)
    for method in ("parity", "winding", "flood"):
        got = voxfx.contains(v, f, pts, method=method)
        if method == "flood":  # flood answers at its grid's resolution: inside cells only
            assert not (got & ~expected & (margin > 0.01)).any()
            continue
        np.testing.assert_array_equal(got[keep], expected[keep], err_msg=method)
    # The point: 0.1 outside the 0.3-wide cube is outside.
    assert not voxfx.contains(v, f, [[x0 + 0.25, 2.15, -0.85]])[0]
    assert voxfx.contains(v, f, [[x0 + 0.1, 2.15, -0.85]])[0]
    # The grid has the cube's shape and sits where the cube is.
    g = voxfx.voxelize(v, f, resolution=10)
    assert g.count() == 1000 and g.dims == (10, 10, 10)
    np.testing.assert_allclose(g.origin, lo, rtol=0, atol=1e-7 * max(1, abs(x0) / 1e6))
    np.testing.assert_allclose(g.cell_size, (0.03, 0.03, 0.03), rtol=1e-6)
    mesh = voxfx.Mesh(v, f)
    np.testing.assert_allclose(mesh.vertices, v, rtol=0, atol=1e-8)
    np.testing.assert_allclose(mesh.bounds, (lo, hi), rtol=0, atol=1e-8)


def test_float32_and_float32_exact_input_is_kept_as_is(data_path):
    v, f = voxfx.load_mesh(data_path("meshes/elephant.off"))
    assert voxfx.Mesh(v, f).origin == (0.0, 0.0, 0.0)
    np.testing.assert_array_equal(voxfx.Mesh(v.astype(np.float32), f).vertices, v)


# ---- 3. the no-copy words ----------------------------------------------------------------------

def test_words_cannot_set_padding_bits(data_path):
    g = voxfx.voxelize(voxfx.load_mesh(data_path("meshes/knot.off")), dims=(30, 20, 70))
    words = g.words
    with pytest.raises(ValueError):
        np.invert(words, out=words)
    assert g.count() == g.to_numpy().sum()
    g.set_words(np.invert(words))  # every bit, padding included: the padding is cleared
    assert g.count() == 30 * 20 * 70 - int(voxfx.voxelize(voxfx.load_mesh(data_path("meshes/knot.off")),
                                                            dims=(30, 20, 70)).count())
    assert g.count() == g.to_numpy().sum()


# ---- 4. morphology with a huge radius along the slicing axis ----------------------------------

def numpy_dilate(a, r):
    """Box dilation with radii r (x, y, z), cells outside ignored (the neutral border)."""
    out = a.copy()
    for axis in range(3):
        n = a.shape[axis]
        rr = min(r[axis], n)
        cum = np.concatenate([np.zeros_like(np.take(out, [0], axis=axis), dtype=np.int64),
                              np.cumsum(out, axis=axis, dtype=np.int64)], axis=axis)
        idx = np.arange(n)
        hi = np.minimum(idx + rr + 1, n)
        lo = np.maximum(idx - rr, 0)
        out = (np.take(cum, hi, axis=axis) - np.take(cum, lo, axis=axis)) > 0
    return out


@pytest.mark.parametrize("axis", ["x", "z"])
def test_morphology_with_a_huge_radius_is_quick(axis):
    rng = np.random.default_rng(2)
    a = rng.random((16, 16, 16)) < 0.02
    g = voxfx.reslice(voxfx.from_numpy(a), axis)
    start = time.perf_counter()
    for r in (10 ** 9, 10 ** 12):
        d = voxfx.dilate(g, (1, 0, r))
        np.testing.assert_array_equal(d.to_numpy(), numpy_dilate(a, (1, 0, r)))
        e = voxfx.erode(g, r)
        assert e.count() == (a.sum() == a.size) * a.size
    assert time.perf_counter() - start < 2


# ---- 5. Ctrl-C stops long calls -----------------------------------------------------------------

class Interrupted(Exception):
    """What SIGINT raises during these tests (not KeyboardInterrupt, which would stop pytest if a
    signal came late)."""


@contextlib.contextmanager
def interrupt_after(seconds):
    def handler(signum, frame):
        raise Interrupted()

    old = signal.signal(signal.SIGINT, handler)
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
        timer.join()
        signal.signal(signal.SIGINT, old)


def test_ctrl_c_stops_contains_between_chunks(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    lo, hi = (np.array(b) for b in mesh.bounds)
    classifier = voxfx.PointClassifier(mesh, method="winding")
    sample = lo + np.random.default_rng(0).random((100_000, 3)) * (hi - lo)
    start = time.perf_counter()
    classifier(sample)
    per_point = (time.perf_counter() - start) / len(sample)
    pts = np.tile(sample, (max(10, int(3.0 / (per_point * len(sample)))), 1))  # 3 s of work at least
    start = time.perf_counter()
    with interrupt_after(0.3), pytest.raises(Interrupted):
        classifier(pts)
    # It stops at the next chunk of 65,536 points.
    assert time.perf_counter() - start < 0.3 + per_point * 2 * 65536 + 0.5


def write_cube_copies(folder, n):
    v, f = box_mesh((0, 0, 0), (1, 1, 1))
    text = "OFF\n8 12 0\n" + "".join(f"{a} {b} {c}\n" for a, b, c in v) + "".join(
        f"3 {a} {b} {c}\n" for a, b, c in f)
    paths = []
    for i in range(n):
        p = folder / f"cube{i}.off"
        p.write_text(text)
        paths.append(p)
    return paths


def test_ctrl_c_stops_batch_between_meshes(tmp_path):
    # Enough meshes that the whole batch takes ten times the delay before Ctrl-C, whatever this
    # machine's speed (a cube at 300^3 takes 10 ms on a fast one): finishing early means it was
    # not stopped.
    out = tmp_path / "out"
    probe = write_cube_copies(tmp_path, 2)
    start = time.perf_counter()
    voxfx.batch(probe, out, resolution=300, threads=1, report=False)
    per_mesh = (time.perf_counter() - start) / 2
    for p in out.iterdir():
        p.unlink()
    delay = max(0.3, 2 * per_mesh)
    n = max(40, int(10 * delay / per_mesh))
    meshes = write_cube_copies(tmp_path, n)
    start = time.perf_counter()
    with interrupt_after(delay), pytest.raises(Interrupted):
        voxfx.batch(meshes, out, resolution=300, threads=1, report=False)
    elapsed = time.perf_counter() - start
    written = len(list(out.glob("*.binvox")))
    assert elapsed < n * per_mesh / 2 and 1 <= written < n
    assert not list(out.glob("*.tmp*"))  # the mesh under way was not left half-written


def test_ctrl_c_stops_voxelize_between_tiles(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    start = time.perf_counter()
    voxfx.voxelize(mesh, resolution=512, fill="gwn")
    full = time.perf_counter() - start
    start = time.perf_counter()
    with interrupt_after(0.1 * full), pytest.raises(Interrupted):
        voxfx.voxelize(mesh, resolution=512, fill="gwn")
    # Before: the whole voxelization (the same time again). Now: the next poll, a tile away.
    assert time.perf_counter() - start < 0.6 * full


def test_an_exception_from_progress_cancels_the_batch(tmp_path):
    meshes = write_cube_copies(tmp_path, 30)
    calls = []

    def progress(job, done, total):
        calls.append(done)
        raise ValueError("stop here")

    with pytest.raises(ValueError, match="stop here"):
        voxfx.batch(meshes, tmp_path / "out", resolution=64, threads=1, progress=progress, report=False)
    assert calls == [1]
    assert len(list((tmp_path / "out").glob("*.binvox"))) < 30


# ---- 6. paths ----------------------------------------------------------------------------------

def test_nul_bytes_in_paths_are_refused(tmp_path, data_path):
    g = voxfx.voxelize(voxfx.load_mesh(data_path("meshes/cube.off")), resolution=4)
    for bad in (str(tmp_path / "z\x00.binvox"), os.fsencode(tmp_path / "z\x00.binvox")):
        with pytest.raises(ValueError, match="NUL"):
            g.save(bad)
    assert not (tmp_path / "z").exists()
    with pytest.raises(ValueError, match="NUL"):
        voxfx.load_mesh(data_path("meshes/cube.off") + "\x00.txt")
    with pytest.raises(ValueError, match="NUL"):
        voxfx.batch([data_path("meshes/cube.off") + "\x00x.off"], tmp_path / "out")
    manifest = tmp_path / "list.txt"
    manifest.write_bytes(b"a.off\nb\x00.off\n")
    with pytest.raises(ValueError, match="line 2 holds a NUL byte"):
        voxfx.batch(manifest, tmp_path / "out")


def test_batch_says_what_is_wrong_with_its_meshes_argument(tmp_path, data_path):
    with pytest.raises(ValueError, match=r"is a mesh file \(\.off\), not a manifest"):
        voxfx.batch(data_path("meshes/cube.off"), tmp_path / "out")
    with pytest.raises(ValueError, match="is a folder"):
        voxfx.batch(tmp_path, tmp_path / "out")
    with pytest.raises(TypeError):
        voxfx.batch(42, tmp_path / "out")
    assert not (tmp_path / "out").exists()
