"""Issue #35, defects 1-6: padding stays empty, memory refusals, Ctrl-C and clamps, pickling,
conventions, install. Each test failed on 7f02cbf (the main before the fixes)."""
import _thread
import glob
import os
import pickle
import subprocess
import sys
import threading
import time
import warnings

import numpy as np
import pytest

import voxfx


def ring_cells(a, p):
    """Cells of a dense [x, y, z] array within p of a side."""
    inner = np.zeros_like(a, dtype=bool)
    inner[p:-p, p:-p, p:-p] = True
    return int((a & ~inner).sum())


def open_meshes(data_path):
    folder = os.path.dirname(data_path("meshes/cube-shuffled.off"))
    out = []
    for path in sorted(glob.glob(os.path.join(folder, "*.off"))):
        try:
            mesh = voxfx.load_mesh(path)
        except voxfx.Error:
            continue
        if mesh.triangle_count and not mesh.is_closed():
            out.append((os.path.basename(path), mesh))
    return out


# ---- 1. padding means empty -------------------------------------------------------------------

@pytest.mark.parametrize("name", ["cube-shuffled.off", "cube4-shuffled.off"])
@pytest.mark.parametrize("mode,fill", [("solid", "auto"), ("solid", "flood"), ("solid", "parity"),
                                       ("solid", "gwn"), ("surface", "auto"), ("conservative", "auto")])
def test_padding_ring_stays_empty(data_path, name, mode, fill):
    mesh = voxfx.load_mesh(data_path("meshes/" + name))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = voxfx.voxelize(mesh, resolution=32, cube=True, padding=1, mode=mode, fill=fill)
        s = voxfx.voxelize(mesh, resolution=32, cube=True, padding=1, mode=mode, fill=fill, sparse=True)
    a = g.to_numpy()
    assert a.shape == (32, 32, 32)
    assert ring_cells(a, 1) == 0
    inner = a.size - ring_cells(np.ones_like(a), 1)
    if mode == "solid" and fill != "gwn":  # the cube [-1, 1]^3 fills the fitted box (gwn needs
        # consistent orientation, which these shuffled cubes lack)
        assert a.sum() == inner
    else:  # a shell, not the whole box
        assert 0 < a.sum() < inner
    np.testing.assert_array_equal(s.to_grid().to_numpy(), a)


def test_padding_ring_stays_empty_for_every_open_mesh(data_path):
    meshes = open_meshes(data_path)
    assert meshes
    for name, mesh in meshes:
        for mode in ("solid", "conservative"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                a = voxfx.voxelize(mesh, resolution=16, cube=True, padding=2, mode=mode).to_numpy()
            assert ring_cells(a, 2) == 0, (name, mode)


def test_flood_does_not_leak_through_the_padding(data_path):
    # A cube whose faces lie on the fitted bounds: flood (the walls kept out of the ring) and
    # parity (orientation-blind) fill the same cells.
    mesh = voxfx.load_mesh(data_path("meshes/cube-shuffled.off"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        flood = voxfx.voxelize(mesh, resolution=24, cube=True, padding=2, fill="flood").to_numpy()
        parity = voxfx.voxelize(mesh, resolution=24, cube=True, padding=2, fill="parity").to_numpy()
    assert ring_cells(flood, 2) == 0
    assert flood.sum() == 20**3
    np.testing.assert_array_equal(flood, parity)


def test_an_untrusted_fill_warns(data_path):
    meshes = open_meshes(data_path)
    name, mesh = meshes[0]
    with pytest.warns(RuntimeWarning, match="not closed"):
        voxfx.voxelize(mesh, resolution=16)


def test_cli_padding_ring_stays_empty(cli, data_path, tmp_path):
    out = tmp_path / "g.binvox"
    r = subprocess.run([cli, "voxelize", data_path("meshes/cube-shuffled.off"), "-o", str(out), "-r", "24", "--cube",
                        "--padding", "2"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert ring_cells(voxfx.read_grid(out).to_numpy(), 2) == 0


# ---- 2. memory ---------------------------------------------------------------------------------

def test_memory_limit_error_is_a_memory_error_and_a_voxfx_error():
    assert issubclass(voxfx.MemoryLimitError, MemoryError)
    assert issubclass(voxfx.MemoryLimitError, voxfx.Error)


def run_python(code, **env):
    e = dict(os.environ, **env)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=e, timeout=120)


def test_a_huge_sparse_resolution_is_refused_up_front(data_path):
    code = f"""
import resource, time, voxfx
m = voxfx.load_mesh({data_path("meshes/bunny00.off")!r})
t = time.perf_counter()
try:
    voxfx.voxelize(m, resolution=100000, sparse=True)
except MemoryError as e:
    assert isinstance(e, voxfx.MemoryLimitError), type(e)
    print("refused", time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""
    r = run_python(code, VOXFX_MEMORY_LIMIT="1G")
    assert r.returncode == 0, r.stderr
    word, seconds, rss_kib = r.stdout.split()
    assert word == "refused" and float(seconds) < 10 and int(rss_kib) < 1 << 20


def test_a_sparse_grid_stays_within_its_budget(data_path):
    # The process's growth during the voxelization stays within the budget, refused or not.
    code = f"""
import resource, voxfx
m = voxfx.load_mesh({data_path("meshes/bunny00.off")!r})
voxfx.voxelize(m, resolution=16, sparse=True)
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
try:
    voxfx.voxelize(m, resolution=4096, sparse=True, threads=1)
    print("done", before, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
except voxfx.MemoryLimitError:
    print("refused", before, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""
    r = run_python(code, VOXFX_MEMORY_LIMIT="64M")
    assert r.returncode == 0, r.stderr
    _, before, after = r.stdout.split()
    assert (int(after) - int(before)) * 1024 <= 64 << 20


def test_a_dense_refusal_is_a_memory_error(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    r = run_python(f"""
import voxfx
try:
    voxfx.voxelize(voxfx.load_mesh({data_path("meshes/bunny00.off")!r}), resolution=4000)
except MemoryError as e:
    print(type(e).__name__)
""", VOXFX_MEMORY_LIMIT="16M")
    assert r.stdout.strip() == "MemoryLimitError", r.stderr
    assert mesh.triangle_count


# ---- 3. hangs and Ctrl-C ----------------------------------------------------------------------

def test_sparse_morphology_with_a_huge_count_is_clamped(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    g = voxfx.voxelize(mesh, resolution=24, sparse=True)
    start = time.perf_counter()
    grown = g.copy().dilate(10 ** 6)
    assert time.perf_counter() - start < 20
    assert grown.count == int(np.prod(g.dims))  # every cell of the grid, none outside
    assert g.copy().erode(10 ** 6).count == 0


def test_level_set_offset_with_a_huge_distance_is_clamped_or_refused(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    ls = voxfx.level_set(mesh, resolution=32)
    start = time.perf_counter()
    assert voxfx.offset_level_set(ls, -1e6).active_count == 0
    with pytest.raises(MemoryError):
        voxfx.offset_level_set(ls, 1e6)
    assert time.perf_counter() - start < 20


class Interrupted(Exception):
    pass


def interrupt_soon(seconds):
    import signal

    def handler(signum, frame):
        raise Interrupted()

    old = signal.signal(signal.SIGINT, handler)
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    return old, timer


def test_ctrl_c_stops_a_full_sdf_promptly(data_path):
    import signal
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    old, timer = interrupt_soon(0.3)
    start = time.perf_counter()
    try:
        with pytest.raises(Interrupted):
            voxfx.sdf(mesh, resolution=400, band="full")
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, old)
    assert time.perf_counter() - start < 0.3 + 2.0


# ---- 4. pickling --------------------------------------------------------------------------------

def results(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    grid = voxfx.voxelize(mesh, resolution=24)
    return mesh, {
        "grid": grid,
        "sparse": voxfx.voxelize(mesh, resolution=24, sparse=True),
        "sdf": voxfx.sdf(mesh, resolution=24),
        "level_set": voxfx.level_set(mesh, resolution=24),
        "surface": voxfx.extract_surface(grid),
        "density": voxfx.compute_density(grid, 1),
        "mesh": mesh,
    }


def same(a, b):
    if isinstance(a, voxfx.SparseGrid):
        key = lambda g: sorted(map(tuple, g.coordinates().tolist()))
        return a.dims == b.dims and np.array_equal(a.transform, b.transform) and key(a) == key(b)
    if isinstance(a, voxfx.LevelSet):
        ia, va = a.active_voxels()
        ib, vb = b.active_voxels()
        return a.voxel_size == b.voxel_size and np.array_equal(ia, ib) and np.array_equal(va, vb)
    if isinstance(a, voxfx.Mesh):
        return np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    return bool(a == b)


def test_every_result_type_pickles(data_path):
    _, objs = results(data_path)
    for name, obj in objs.items():
        back = pickle.loads(pickle.dumps(obj))
        assert type(back) is type(obj), name
        assert same(obj, back), name
    sdf = objs["sdf"]
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(sdf)).to_numpy(), sdf.to_numpy())


class SdfDataset:
    def __init__(self, path):
        self.path = path

    def __len__(self):
        return 4

    def __getitem__(self, i):
        return voxfx.sdf(voxfx.load_mesh(self.path), resolution=16 + i)


def test_a_dataloader_with_two_workers_returns_results(data_path):
    torch = pytest.importorskip("torch")
    loader = torch.utils.data.DataLoader(SdfDataset(data_path("meshes/bunny00.off")), batch_size=None,
                                         num_workers=2, timeout=120)
    got = list(loader)
    assert [f.dims[0] for f in got] == [16 + 3 + 3 + i for i in range(4)] or len(got) == 4
    for i, f in enumerate(got):
        assert isinstance(f, voxfx.SignedDistanceField)
        assert f == SdfDataset(data_path("meshes/bunny00.off"))[i]


# ---- 5. conventions -----------------------------------------------------------------------------

def test_a_bad_mesh_raises_the_same_error_everywhere():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nan, 0, 0]], float)
    f = np.array([[0, 1, 2], [0, 1, 3]])
    pts = np.zeros((1, 3))
    for call in (lambda: voxfx.voxelize(v, f, resolution=8), lambda: voxfx.contains(v, f, pts),
                 lambda: voxfx.signed_distance(v, f, pts), lambda: voxfx.PointClassifier(v, f)):
        with pytest.raises(voxfx.ArgumentError):
            call()


def test_nan_points(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    pts = np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]])
    with pytest.raises(ValueError):
        voxfx.contains(mesh, pts)
    d = voxfx.signed_distance(mesh, pts)
    assert np.isfinite(d[0]) and np.isnan(d[1])


def test_bool_is_not_an_integer(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    for call in (lambda: voxfx.voxelize(mesh, resolution=True), lambda: voxfx.sdf(mesh, resolution=True),
                 lambda: voxfx.voxelize(mesh, resolution=8, padding=True),
                 lambda: voxfx.voxelize_many([mesh], resolution=True),
                 lambda: voxfx.voxelize_many([mesh], resolution=8, padding=True),
                 lambda: voxfx.batch([data_path("meshes/bunny00.off")], "unused-out", resolution=True)):
        with pytest.raises(TypeError):
            call()


def test_from_numpy_refuses_values_other_than_0_and_1():
    a = np.zeros((4, 4, 4))
    a[1, 1, 1] = 0.3
    with pytest.raises(ValueError):
        voxfx.from_numpy(a)
    a[1, 1, 1] = 1.0
    assert voxfx.from_numpy(a).count() == 1


def test_mesh_arrays_are_read_only(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    with pytest.raises(ValueError):
        mesh.vertices[0, 0] = 5.0
    with pytest.raises(ValueError):
        mesh.faces[0, 0] = 1


def test_a_small_part_far_away_in_float32_warns():
    v = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64) + 1e6).astype(np.float32)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    with pytest.warns(UserWarning, match="collapses"):
        voxfx.Mesh(v, f)


def test_sdf_cube_gives_resolution_cubed_and_takes_like_and_padding(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    f = voxfx.sdf(mesh, resolution=20, cube=True)
    assert f.dims == (20, 20, 20)
    g = voxfx.voxelize(mesh, resolution=20, cube=True, padding=2)
    like = voxfx.sdf(mesh, like=g)
    assert like.dims == g.dims and np.allclose(like.origin, g.origin)
    padded = voxfx.sdf(mesh, resolution=20, cube=True, padding=4)
    assert padded.dims == (20, 20, 20)
    assert padded.cell_size[0] > f.cell_size[0]


# ---- 6. install -----------------------------------------------------------------------------------

def test_install_notes():
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    readme = open(os.path.join(root, "README.md")).read()
    assert "/usr/bin/python3 -m venv" in readme and "VOXFX_CUDA=OFF" in readme
    assert "/.venv/" in open(os.path.join(root, ".gitignore")).read().split()
    setup = open(os.path.join(root, "setup.py")).read()
    assert "bdist_wheel" in setup and "VOXFX_CUDA" in setup
