"""Grids the way learning code wants them, and Python habits (issue #24), against NumPy on small
grids: cubic fits, filled-cell indices and centres (np.argwhere), the affine and index maps, point
lookups, indexing, operators, bounds that round-trip, pickling, meshes from other libraries by
duck typing, errors, os.PathLike, signatures and the command line through python -m voxfx."""
import copy
import inspect
import os
import pathlib
import pickle
import subprocess
import sys
import warnings

import numpy as np
import pytest

import voxfx


def random_grid(shape, axis="z", seed=0, origin=(0.5, -1.0, 2.0), cell=(0.25, 0.5, 0.125)):
    a = np.random.default_rng(seed).random(shape) < 0.3
    g = voxfx.from_numpy(a, origin=origin, cell_size=cell)
    return voxfx.reslice(g, axis) if axis != "z" else g, a


# ---- cubic grids --------------------------------------------------------------------------------

def test_cube_with_padding_is_an_n_cubed_grid_of_cubic_cells(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    lo, hi = (np.array(b) for b in mesh.bounds)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        g = voxfx.voxelize(mesh, resolution=64, cube=True, padding=2)
    assert g.dims == (64, 64, 64)
    cell = np.array(g.cell_size)
    assert np.ptp(cell) == 0  # cubic
    np.testing.assert_allclose(cell[0], (hi - lo).max() / 60)  # 64 - 2 * 2 cells across the mesh
    np.testing.assert_allclose(np.array(g.origin) + 32 * cell, (lo + hi) / 2, atol=1e-12)  # centred
    assert np.all(lo >= np.array(g.origin) + 2 * cell - 1e-12)
    assert np.all(hi <= np.array(g.bounds[1]) - 2 * cell + 1e-12)
    occ = g.to_numpy()
    assert not occ[:2].any() and not occ[-2:].any()
    # dims that force unequal cells warn; the same dims over a cube's bounds do not.
    with pytest.warns(UserWarning, match="not cubic"):
        voxfx.voxelize(mesh, dims=(16, 16, 16))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        voxfx.voxelize(mesh, dims=g.dims, bounds=g.bounds)
    with pytest.raises(ValueError):
        voxfx.voxelize(mesh, voxel_size=0.1, cube=True)
    with pytest.raises(ValueError):
        voxfx.voxelize(mesh, resolution=4, padding=2)


# ---- indices, centres, affine, lookups ---------------------------------------------------------

@pytest.mark.parametrize("axis", ["x", "y", "z"])
@pytest.mark.parametrize("shape", [(7, 5, 63), (9, 3, 130), (1, 1, 1)])
def test_indices_and_centers_match_numpy(axis, shape):
    g, a = random_grid(shape, axis)
    idx = g.indices()
    assert idx.dtype == np.int32 and idx.shape == (a.sum(), 3)
    np.testing.assert_array_equal(idx, np.argwhere(a))
    expected = np.array(g.origin) + (np.argwhere(a) + 0.5) * np.array(g.cell_size)
    np.testing.assert_array_equal(g.centers(), expected)
    c32 = g.centers(dtype=np.float32)
    assert c32.dtype == np.float32
    np.testing.assert_array_equal(c32, expected.astype(np.float32))
    # The affine takes (i, j, k, 1) to the centres; world_to_index inverts it on them.
    hom = np.c_[np.argwhere(a), np.ones(len(idx))]
    np.testing.assert_allclose((g.affine @ hom.T).T[:, :3], expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(g.index_to_world(np.argwhere(a)), expected)
    np.testing.assert_array_equal(g.world_to_index(expected), np.argwhere(a))


@pytest.mark.parametrize("axis", ["x", "z"])
def test_contains_and_indexing_look_up_cells(axis):
    g, a = random_grid((6, 7, 70), axis)
    origin, cell = np.array(g.origin), np.array(g.cell_size)
    pts = origin - 1 + np.random.default_rng(1).random((5000, 3)) * (np.array(a.shape) * cell + 2)
    ijk = np.floor((pts - origin) / cell).astype(np.int64)
    inside = np.all((ijk >= 0) & (ijk < a.shape), axis=1)
    expected = np.zeros(len(pts), bool)
    expected[inside] = a[tuple(ijk[inside].T)]
    np.testing.assert_array_equal(g.contains(pts), expected)
    np.testing.assert_array_equal(g.world_to_index(pts), ijk)
    with pytest.raises(ValueError, match="not finite"):  # a NaN point has no inside: an error
        g.contains([[np.nan, 0, 0]])
    for i, j, k in [(0, 0, 0), (5, 6, 69), (-1, -2, -3), (3, 1, 64)]:
        assert g[i, j, k] == a[i, j, k]
    with pytest.raises(IndexError):
        g[6, 0, 0]
    np.testing.assert_array_equal(g[1:3, :, 5], a[1:3, :, 5])
    np.testing.assert_array_equal(np.asarray(g), a)
    assert np.asarray(g, dtype=np.uint8).dtype == np.uint8


def test_operators_combine_like_numpy():
    ga, a = random_grid((5, 6, 70), seed=1)
    gb, b = random_grid((5, 6, 70), seed=2)
    for got, want in [(ga | gb, a | b), (ga & gb, a & b), (ga - gb, a & ~b), (ga ^ gb, a ^ b)]:
        np.testing.assert_array_equal(got.to_numpy(), want)
    assert (ga == 1) is False and (ga != "grid") is True
    with pytest.raises(TypeError):
        ga | 1
    gc, _ = random_grid((5, 6, 70), seed=2, origin=(0, 0, 0))
    with pytest.raises(ValueError, match="same frame"):
        ga | gc


def test_bounds_and_like_round_trip_into_voxelize(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    g = voxfx.voxelize(mesh, resolution=40, cube=True, padding=1)
    again = voxfx.voxelize(mesh, bounds=g.bounds, dims=g.dims)
    assert again == g and again.bounds == g.bounds and again.cell_size == g.cell_size
    other = voxfx.load_mesh(data_path("meshes/elephant.off"))
    like = voxfx.voxelize(other, like=g)
    assert like.bounds == g.bounds and like.dims == g.dims
    np.testing.assert_array_equal((like | g).to_numpy(), like.to_numpy() | g.to_numpy())
    with pytest.raises(ValueError):
        voxfx.voxelize(other, like=g, resolution=10)


# ---- Python habits ------------------------------------------------------------------------------

def test_pickle_and_deepcopy(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    far = voxfx.Mesh(mesh.vertices + 1e6 + 0.1, mesh.faces)
    g = voxfx.voxelize(mesh, resolution=20, axis="x")
    for obj in (g, mesh, far):
        for twin in (pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj), copy.copy(obj)):
            assert type(twin) is type(obj)
            if isinstance(obj, voxfx.Grid):
                assert twin == obj and twin.axis == "x"
            else:
                np.testing.assert_array_equal(twin.vertices, obj.vertices)
                np.testing.assert_array_equal(twin.faces, obj.faces)
                assert twin.origin == obj.origin
    deep = copy.deepcopy(g)
    deep.set_words(np.zeros_like(deep.words))
    assert deep.count() == 0 and g.count() > 0
    pts = np.random.default_rng(0).random((2000, 3)) - 0.5
    for method in ("parity", "winding"):
        pc = voxfx.PointClassifier(mesh, method=method)
        for twin in (pickle.loads(pickle.dumps(pc)), copy.deepcopy(pc)):
            np.testing.assert_array_equal(twin(pts), pc(pts))
            assert twin.method == method and twin.resolution == pc.resolution


class TrimeshLike:
    def __init__(self, v, f):
        self.vertices, self.faces = v, f


class Vector3dVector:
    """Open3D's vector types: sequences that NumPy converts."""

    def __init__(self, a):
        self._a = a

    def __array__(self, dtype=None):
        return self._a if dtype is None else self._a.astype(dtype)


class Open3DLike:
    def __init__(self, v, f):
        self.vertices, self.triangles = Vector3dVector(v), Vector3dVector(f)


class MeshioLike:
    def __init__(self, v, cells):
        self.points, self.cells_dict = v, cells


def test_meshes_from_other_libraries(data_path):
    v, f = voxfx.load_mesh(data_path("meshes/cube-meshed.off"))
    reference = voxfx.voxelize(v, f, resolution=12)
    for mesh in (TrimeshLike(v, f), Open3DLike(v, f), MeshioLike(v, {"triangle": f, "vertex": [[0]]}), (v, f),
                 [v, f], voxfx.Mesh((v, f))):
        assert voxfx.voxelize(mesh, resolution=12) == reference, type(mesh)
        assert voxfx.voxelize(mesh=mesh, resolution=12) == reference
    # meshio's quads are split in two.
    quad_v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1.0]])
    quads = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [0, 4, 7, 3], [1, 2, 6, 5]])
    box = voxfx.voxelize(MeshioLike(quad_v, {"quad": quads}), resolution=8)
    assert box.count() == 512
    with pytest.raises(ValueError, match="no triangle or quad"):
        voxfx.voxelize(MeshioLike(quad_v, {"tetra": np.zeros((1, 4), int)}), resolution=8)
    with pytest.raises(TypeError):
        voxfx.voxelize(TrimeshLike(v, f), f, resolution=8)
    with pytest.raises(TypeError):
        voxfx.voxelize(object(), resolution=8)


def test_bad_arguments_raise_value_and_type_errors(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/cube.off"))
    assert issubclass(voxfx.ArgumentError, voxfx.Error) and issubclass(voxfx.ArgumentError, ValueError)
    for kwargs in ({"fill": "bogus"}, {"mode": "solidish"}, {"axis": "w"}, {"resolution": 0},
                   {"resolution": 8, "dims": (2, 2, 2)}, {"bounds": (1, 2, 3)}, {"threads": -1}):
        with pytest.raises(ValueError):
            voxfx.voxelize(mesh, **{"resolution": 8, **kwargs} if "dims" not in kwargs else kwargs)
    with pytest.raises(ValueError):
        voxfx.contains(mesh, np.zeros((3, 2)))
    with pytest.raises(ValueError):
        voxfx.contains(mesh, np.zeros((3, 3)), method="bogus")
    with pytest.raises(TypeError):
        voxfx.contains(mesh, "points")
    with pytest.raises(ValueError):
        voxfx.Mesh(np.zeros((3, 3)), [[0, 1, 5]])
    with pytest.raises(TypeError):
        voxfx.Mesh(np.zeros((3, 3)), [[0.0, 1.0, 2.0]])
    g = voxfx.voxelize(mesh, resolution=4)
    with pytest.raises(ValueError):
        voxfx.morphology(g, "grow")
    with pytest.raises(ValueError):
        voxfx.dilate(g, -1)
    with pytest.raises(TypeError):
        g.save(3)
    with pytest.raises(ValueError):
        g.set_words(np.zeros((1, 2, 3), np.uint64))


def test_repr_says_where_and_how_much(data_path):
    g = voxfx.voxelize(voxfx.load_mesh(data_path("meshes/cube.off")), resolution=4)
    r = repr(g)
    assert "4 x 4 x 4" in r and f"origin {g.origin}".replace(",)", ")") in r and f"{g.count()} filled" in r
    assert f"cell {g.cell_size[0]}" in r
    assert "triangles" in repr(voxfx.PointClassifier(voxfx.load_mesh(data_path("meshes/cube.off"))))


def test_paths_are_os_pathlike(tmp_path, data_path):
    mesh = voxfx.load_mesh(pathlib.Path(data_path("meshes/cube.off")))
    g = voxfx.voxelize(mesh, resolution=4)
    g.save(tmp_path / "g.binvox")
    assert voxfx.read_grid(tmp_path / "g.binvox").count() == g.count()
    voxfx.compute_density(g).save(tmp_path / "d.nrrd")
    voxfx.extract_surface(g).save(tmp_path / "s.ply")
    report = voxfx.batch([pathlib.Path(data_path("meshes/cube.off"))], tmp_path / "out", resolution=4,
                         report=tmp_path / "r.json")
    assert report["ok"] == 1 and (tmp_path / "r.json").exists() and (tmp_path / "d.nrrd").exists()


def test_import_leaves_the_environment_alone():
    code = "import os; before = dict(os.environ); import voxfx; voxfx.read_grid; print(dict(os.environ) == before)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"


def test_public_functions_have_signatures():
    for name in voxfx.__all__:
        f = getattr(voxfx, name)
        if isinstance(f, type) or not callable(f):
            continue
        sig = inspect.signature(f)
        assert len(sig.parameters) > 0 or name in ("cuda_status", "render_options", "shadow_kinds",
                                                   "glass_methods"), name
    params = inspect.signature(voxfx.voxelize).parameters
    assert list(params)[:2] == ["mesh", "faces"] and params["resolution"].kind is inspect.Parameter.KEYWORD_ONLY
    assert params["fill"].default == "auto" and params["cube"].default is False
    assert "progress" in inspect.signature(voxfx.batch).parameters


def test_stubs_name_every_public_function_with_its_parameters():
    import ast

    stub = pathlib.Path(voxfx.__file__).with_name("__init__.pyi")
    assert stub.exists() and stub.with_name("py.typed").exists()
    tree = ast.parse(stub.read_text())
    functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    for name in voxfx.__all__:
        obj = getattr(voxfx, name)
        if isinstance(obj, type):
            assert name in classes, name
            continue
        if not callable(obj):
            continue
        assert name in functions, name
        a = functions[name].args
        stub_names = [p.arg for p in a.args + a.kwonlyargs] + ([a.kwarg.arg] if a.kwarg else [])
        assert stub_names == list(inspect.signature(obj).parameters), name
    grid_methods = {n.name for n in classes["Grid"].body if isinstance(n, ast.FunctionDef)}
    public = {m for m in dir(voxfx.Grid) if not m.startswith("_")}
    assert public <= grid_methods, public - grid_methods


def test_python_m_voxfx_runs_the_command_line(cli):
    out = subprocess.run([sys.executable, "-m", "voxfx", "--version"], capture_output=True, text=True, check=True)
    assert out.stdout == subprocess.run([cli, "--version"], capture_output=True, text=True).stdout
    assert out.stdout.startswith("voxfx " + voxfx.__version__)
    bad = subprocess.run([sys.executable, "-m", "voxfx", "no-such-command"], capture_output=True, text=True)
    assert bad.returncode != 0
