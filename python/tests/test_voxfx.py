"""The Python module against independent oracles: the voxfx command (byte-identical files), file
formats decoded here from their specifications, NumPy re-implementations of the toolkit, and the
voxelizer's own bits for contains() at voxel centres."""
import os
import re
import subprocess

import numpy as np
import pytest

import voxfx

MESHES = ["meshes/elephant.off", "meshes/knot.off", "meshes/elephant-with-holes.off", "meshes/cow.off"]


def read_off(path):
    """A plain OFF reader (triangles and fan-triangulated polygons), independent of voxfx."""
    with open(path) as f:
        tokens = [t for line in f for t in line.split("#")[0].split()]
    assert tokens[0] == "OFF"
    nv, nf = int(tokens[1]), int(tokens[2])
    at = 4
    v = np.array(tokens[at:at + 3 * nv], dtype=np.float64).reshape(nv, 3)
    at += 3 * nv
    faces = []
    for _ in range(nf):
        n = int(tokens[at])
        corners = [int(t) for t in tokens[at + 1:at + 1 + n]]
        at += 1 + n
        faces += [(corners[0], corners[k - 1], corners[k]) for k in range(2, n)]
    return v, np.array(faces, dtype=np.int64)


def run_cli(cli, *args):
    subprocess.run([cli, *map(str, args)], check=True, capture_output=True)


def read_nrrd(path):
    """uint8 NRRD (raw, x fastest) as an array indexed [x, y, z]."""
    data = open(path, "rb").read()
    header, raw = data.split(b"\n\n", 1)
    fields = dict(line.split(": ", 1) for line in header.decode().splitlines()[1:] if ": " in line)
    assert fields["encoding"] == "raw" and fields["type"] in ("uint8", "uchar", "unsigned char")
    nx, ny, nz = map(int, fields["sizes"].split())
    return np.frombuffer(raw, dtype=np.uint8).reshape(nz, ny, nx).transpose(2, 1, 0) != 0


def read_binvox(path):
    """binvox (run-length pairs, x slowest, then z, y fastest) as an array indexed [x, y, z]."""
    data = open(path, "rb").read()
    end = data.index(b"data\n") + 5
    header = data[:end].decode().split("\n")
    dims = [int(t) for t in next(line for line in header if line.startswith("dim")).split()[1:]]
    pairs = np.frombuffer(data[end:], dtype=np.uint8).reshape(-1, 2)
    flat = np.repeat(pairs[:, 0], pairs[:, 1]).astype(bool)
    nx, nz, ny = dims  # counts in data order, slowest first
    return flat.reshape(nx, nz, ny).transpose(0, 2, 1)


def test_load_mesh_unpacks_to_the_file_contents(data_path):
    path = data_path("meshes/elephant.off")
    mesh = voxfx.load_mesh(path)
    v, f = mesh
    ev, ef = read_off(path)
    assert v.dtype == np.float64 and v.shape == ev.shape
    np.testing.assert_array_equal(v, ev.astype(np.float32).astype(np.float64))
    np.testing.assert_array_equal(f, ef)
    assert mesh.triangle_count == len(ef) and mesh.is_closed()


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("options,cli_args", [
    ({"resolution": 40}, ["-r", "40"]),
    ({"voxel_size": 0.05, "mode": "conservative", "axis": "x"}, ["--voxel-size", "0.05", "-m", "conservative",
                                                                  "--axis", "x"]),
    ({"dims": (20, 31, 17), "mode": "interior", "fill": "vote", "margin": 2},
     ["--dims", "20", "31", "17", "-m", "interior", "--fill", "vote", "--margin", "2"]),
])
def test_save_is_byte_identical_to_the_cli(tmp_path, cli, data_path, name, options, cli_args):
    path = data_path(name)
    grid = voxfx.voxelize(voxfx.load_mesh(path), **options)
    for ext in (".binvox", ".nrrd", ".ply", ".obj"):
        ours, theirs = tmp_path / ("py" + ext), tmp_path / ("cli" + ext)
        grid.save(str(ours))
        run_cli(cli, "voxelize", path, "-o", theirs, "-q", *cli_args)
        assert ours.read_bytes() == theirs.read_bytes(), ext
    # OpenVDB files carry a random UUID: compare what they hold.
    grid.save(str(tmp_path / "py.vdb"))
    run_cli(cli, "voxelize", path, "-o", tmp_path / "cli.vdb", "-q", *cli_args)
    a, b = voxfx.read_grid(str(tmp_path / "py.vdb")), voxfx.read_grid(str(tmp_path / "cli.vdb"))
    np.testing.assert_array_equal(a.to_numpy(), b.to_numpy())
    np.testing.assert_array_equal(a.to_numpy(), grid.to_numpy())


def test_arrays_give_the_same_grid_as_a_loaded_mesh(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    v, f = mesh
    a = voxfx.voxelize(mesh, resolution=48)
    b = voxfx.voxelize(v, f.astype(np.int32), resolution=48)
    c = voxfx.voxelize(v.astype(np.float32), f.astype(np.uint32), resolution=48)
    assert a == b and a == c


def test_to_numpy_is_indexed_like_the_cli_files(tmp_path, cli, data_path):
    path = data_path("meshes/cow.off")
    for axis in ("x", "y", "z"):
        grid = voxfx.voxelize(voxfx.load_mesh(path), dims=(23, 17, 29), axis=axis)
        occ = grid.to_numpy()
        assert occ.shape == (23, 17, 29) == grid.dims and occ.dtype == np.bool_
        run_cli(cli, "voxelize", path, "-o", tmp_path / "c.nrrd", "--dims", 23, 17, 29, "--axis", axis, "-q")
        run_cli(cli, "voxelize", path, "-o", tmp_path / "c.binvox", "--dims", 23, 17, 29, "--axis", axis, "-q")
        np.testing.assert_array_equal(occ, read_nrrd(tmp_path / "c.nrrd"))
        np.testing.assert_array_equal(occ, read_binvox(tmp_path / "c.binvox"))
        assert occ.sum() == grid.count()


def test_frame_places_voxels_in_the_world(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    lo, hi = mesh.bounds
    grid = voxfx.voxelize(mesh, dims=(10, 20, 30))
    np.testing.assert_allclose(grid.origin, lo)
    np.testing.assert_allclose(np.array(grid.origin) + np.array(grid.cell_size) * grid.dims, hi, rtol=1e-12)
    # resolution N over given bounds: the longest side gets N cubic cells, the others
    # ceil(extent / cell), centred on the bounds.
    g2 = voxfx.voxelize(mesh, resolution=7, bounds=(-1, -2, -3, 4, 5, 6))
    extent = np.array([5.0, 7.0, 9.0])
    cell = 9.0 / 7
    assert g2.dims == tuple(int(n) for n in np.ceil(extent / cell))
    np.testing.assert_allclose(g2.cell_size, (cell, cell, cell))
    centre = np.array(g2.origin) + np.array(g2.dims) * cell / 2
    np.testing.assert_allclose(centre, (1.5, 1.5, 1.5), atol=1e-12)


def test_words_are_the_grid_without_a_copy(data_path):
    grid = voxfx.voxelize(voxfx.load_mesh(data_path("meshes/knot.off")), dims=(30, 20, 70))
    words = grid.words
    w, h, d = grid.shape
    assert words.shape == (h, w, (d + 63) // 64) and words.dtype == np.uint64
    # Decode the documented layout: slice s of column (x, y) is bit s % 64 of word s // 64.
    bits = np.unpackbits(words.view(np.uint8).reshape(h, w, -1), axis=2, bitorder="little")[:, :, :d]
    np.testing.assert_array_equal(bits.transpose(1, 0, 2).astype(bool), grid.to_numpy())
    # The array is the grid's memory, read-only: set_words writes (a copy); the array keeps the
    # grid alive after the last reference goes.
    assert not words.flags.writeable
    grid.set_words(np.zeros_like(words))
    assert grid.count() == 0 and int(words.sum()) == 0
    one = np.zeros_like(words)
    one[0, 0, 0] = 1
    grid.set_words(one)
    words2 = grid.words
    del grid, words
    import gc
    gc.collect()
    assert int(words2.sum()) == 1


def test_from_numpy_round_trips():
    rng = np.random.default_rng(3)
    a = rng.random((9, 70, 5)) < 0.3
    g = voxfx.from_numpy(a, origin=(1, 2, 3), cell_size=(0.5, 0.25, 2))
    np.testing.assert_array_equal(g.to_numpy(), a)
    assert g.dims == (9, 70, 5) and g.origin == (1, 2, 3) and g.cell_size == (0.5, 0.25, 2)


def test_errors_raise_with_the_library_message(data_path, tmp_path):
    assert issubclass(voxfx.Error, RuntimeError)
    with pytest.raises(voxfx.Error, match="nonexistent.off"):
        voxfx.load_mesh(str(tmp_path / "nonexistent.off"))
    v, f = voxfx.load_mesh(data_path("meshes/knot.off"))
    with pytest.raises(voxfx.Error, match="unknown voxelization mode 'solidd'"):
        voxfx.voxelize(v, f, mode="solidd")
    bad = f.copy()
    bad[5, 1] = len(v) + 3
    with pytest.raises(voxfx.Error, match="triangle 5"):
        voxfx.voxelize(v, bad)
    with pytest.raises(voxfx.Error):
        voxfx.voxelize(v, f, resolution=8).save(str(tmp_path / "x.unknown"))
    with pytest.raises(ValueError):
        voxfx.voxelize(v, f, resolution=8, voxel_size=0.1)
    with pytest.raises(ValueError):
        voxfx.voxelize(v[:, :2], f)
    with pytest.raises(TypeError):
        voxfx.voxelize(v, f.astype(np.float64))
    a = voxfx.voxelize(v, f, resolution=8)
    b = voxfx.voxelize(v, f, resolution=9)
    with pytest.raises(voxfx.Error):
        voxfx.csg(a, b, "union")


def test_toolkit_matches_numpy(data_path, tmp_path):
    grid = voxfx.voxelize(voxfx.load_mesh(data_path("meshes/cow.off")), dims=(24, 18, 30), axis="y")
    occ = grid.to_numpy()

    # Dilation by a 3x3x3 box, empty outside: OR of the 27 shifts.
    padded = np.pad(occ, 1)
    expected = np.zeros_like(occ)
    for dx in range(3):
        for dy in range(3):
            for dz in range(3):
                expected |= padded[dx:dx + 24, dy:dy + 18, dz:dz + 30]
    np.testing.assert_array_equal(voxfx.dilate(grid, 1, border="empty").to_numpy(), expected)
    # Erosion with a filled border: AND of the shifts of a one-padded grid.
    padded1 = np.pad(occ, 1, constant_values=True)
    eroded = np.ones_like(occ)
    for dx in range(3):
        for dy in range(3):
            for dz in range(3):
                eroded &= padded1[dx:dx + 24, dy:dy + 18, dz:dz + 30]
    np.testing.assert_array_equal(voxfx.erode(grid, 1, border="filled").to_numpy(), eroded)

    other = voxfx.dilate(grid, (2, 0, 1), border="empty")
    o = other.to_numpy()
    for op, f in (("union", np.logical_or), ("intersection", np.logical_and),
                  ("difference", lambda a, b: a & ~b), ("xor", np.logical_xor)):
        np.testing.assert_array_equal(voxfx.csg(grid, other, op).to_numpy(), f(occ, o), op)

    density = voxfx.compute_density(grid, level=1)
    occ_z = np.pad(occ, ((0, 0), (0, 0), (0, 0)))
    blocks = occ_z.reshape(12, 2, 9, 2, 15, 2).sum(axis=(1, 3, 5)) / 8.0
    np.testing.assert_array_equal(density.occupancy(), blocks.astype(np.float32))
    assert density.total() == occ.sum()
    density.save(str(tmp_path / "d.nrrd"))

    surface = voxfx.extract_surface(grid)
    assert surface.faces.shape[1] == 3 and len(surface.faces) > 100
    assert surface.vertices.shape == surface.normals.shape
    surface.save(str(tmp_path / "s.ply"))
    assert voxfx.load_mesh(str(tmp_path / "s.ply")).triangle_count == len(surface.faces)

    z = voxfx.reslice(grid, "z")
    np.testing.assert_array_equal(z.to_numpy(), occ)
    assert z.axis == "z"


def test_contains_at_voxel_centres_equals_the_solid_grid(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    grid = voxfx.voxelize(mesh, resolution=32, fill="parity")
    nx, ny, nz = grid.dims
    o, c = np.array(grid.origin), np.array(grid.cell_size)
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    centres = o + (np.stack([i, j, k], axis=-1).reshape(-1, 3) + 0.5) * c
    inside = voxfx.contains(mesh, centres)
    assert inside.dtype == np.bool_
    np.testing.assert_array_equal(inside.reshape(nx, ny, nz), grid.to_numpy())
    v, f = mesh
    np.testing.assert_array_equal(voxfx.contains(v, f, centres), inside)
    np.testing.assert_array_equal(voxfx.contains(v, f, centres, resolution=7, threads=1), inside)
    classifier = voxfx.PointClassifier(mesh, resolution=20)
    assert classifier.resolution == 20
    np.testing.assert_array_equal(classifier(centres), inside)
    np.testing.assert_array_equal(classifier(centres.astype(np.float32).astype(np.float64)),
                                  voxfx.contains(mesh, centres.astype(np.float32)))


def test_contains_methods_agree_on_a_closed_mesh(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    lo, hi = np.array(mesh.bounds)
    pts = np.random.default_rng(1).uniform(lo, hi, (3000, 3))
    parity = voxfx.contains(mesh, pts)
    winding = voxfx.contains(mesh, pts, method="winding")
    flood = voxfx.contains(mesh, pts, method="flood", resolution=64)
    assert parity.sum() > 100
    np.testing.assert_array_equal(parity, winding)
    np.testing.assert_array_equal(parity, voxfx.contains(mesh, pts, method="winding", winding_beta=0))
    assert np.all(flood[parity])  # flood includes the surface cells
    with pytest.raises(voxfx.Error, match="unknown contains method"):
        voxfx.contains(mesh, pts, method="vote")
    with pytest.raises(ValueError):
        voxfx.contains(mesh, pts[:, :2])


def test_gil_is_released_while_voxelizing(data_path, gil_stall):
    # A Python thread takes timestamps while one voxelize call runs: with the GIL held during
    # the call, none could fall inside it.
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    # one thread: a core stays free for the counter
    duration, gap = gil_stall(lambda: voxfx.voxelize(mesh, resolution=800, threads=1))
    # The call takes about 35 ms on the project's VM, longer under load; it must be long enough to
    # measure. With the GIL held the counter stalls for most of it.
    assert duration > 0.01
    assert gap < 0.5 * duration


def test_device_cuda_gives_the_cpu_grid_and_warns_without_a_gpu(data_path):
    """device="cuda" voxelizes on the GPU where one is usable and gives the CPU's grid bit for bit;
    without one (cuda_status() says why) it warns with that reason and still gives the CPU's grid."""
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    status = voxfx.cuda_status()
    assert set(status) == {"built", "available", "device", "reason"}
    assert status["available"] != bool(status["reason"])
    for mode in ("solid", "conservative", "interior"):
        cpu = voxfx.voxelize(mesh, resolution=72, mode=mode, fill="parity")
        if status["available"]:
            gpu = voxfx.voxelize(mesh, resolution=72, mode=mode, fill="parity", device="cuda")
        else:
            with pytest.warns(RuntimeWarning, match=re.escape(status["reason"][:40])):
                gpu = voxfx.voxelize(mesh, resolution=72, mode=mode, fill="parity", device="cuda")
        assert gpu == cpu
        assert np.array_equal(gpu.to_numpy(), cpu.to_numpy())
    with pytest.raises(voxfx.Error, match="cpu, cuda, auto"):
        voxfx.voxelize(mesh, resolution=8, device="gpu")


def _box(lo, hi):
    """A closed box mesh, outward-facing triangles, as (vertices, faces) arrays."""
    v = np.array([[x, y, z] for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])], np.float64)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return v, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], np.int64)


def test_intersection_volume_of_placed_boxes_holds_the_closed_form_within_its_bound():
    # [0, 3] x [0, 2] x [0, 1.5] against a 2.2 x 1.1 x 0.9 box turned a quarter about z and moved to
    # [1.9, 3] x [0.7, 2.9] x [0.4, 1.3]: 1.1 x 1.3 x 0.9 in common (a closed form).
    a, b = _box((0, 0, 0), (3, 2, 1.5)), _box((0, 0, 0), (2.2, 1.1, 0.9))
    turn = np.array([[0, -1, 0, 3.0], [1, 0, 0, 0.7], [0, 0, 1, 0.4]])
    exact = 1.1 * 1.3 * 0.9
    bounds = []
    for resolution in (32, 128):
        e = voxfx.intersection_volume(a, b, transform_b=turn, resolution=resolution)
        assert isinstance(e, voxfx.VolumeEstimate)
        assert abs(e.volume - exact) <= e.error_bound
        assert e.lower_volume <= exact <= e.upper_volume
        bounds.append(e.error_bound)
    assert bounds[1] < bounds[0] / 3
    # Grids of one frame: their common cells, exactly (a NumPy count is the oracle).
    ga = voxfx.voxelize(*a, bounds=(-1, -1, -1, 4, 4, 4), dims=(20, 20, 20))
    gb = voxfx.voxelize(*_box((1.9, 0.7, 0.4), (3.1, 2.9, 1.3)), like=ga)
    e = voxfx.intersection_volume(ga, gb)
    common = np.count_nonzero(ga.to_numpy() & gb.to_numpy())
    assert e.cells == common and e.error_bound == 0
    assert e.volume == pytest.approx(common * 0.25 ** 3)
    with pytest.raises(voxfx.ArgumentError):
        voxfx.intersection_volume(a, b, transform=np.eye(3))
