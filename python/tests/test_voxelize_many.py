"""Batches as arrays: voxelize_many (dense and batch-indexed sparse coordinates), `voxfx batch` and
voxfx.batch with cube/padding writing .npy/.npz (read back by NumPy's own np.load), the Dask path,
and torch tensors in and out. The oracle for every grid is voxfx.voxelize of the same mesh one at a
time (the single-mesh path the rest of the suite checks against CGAL), and np.argwhere for the
coordinates.
"""
import os
import pickle
import subprocess

import numpy as np
import pytest

import voxfx

MESHES = ["meshes/elephant.off", "meshes/bunny00.off", "meshes/cactus.off", "meshes/sphere.off", "meshes/eight.off"]


def one_by_one(paths, resolution, padding, **options):
    return np.stack([voxfx.voxelize(voxfx.load_mesh(p), resolution=resolution, cube=True, padding=padding,
                                    **options).to_numpy() for p in paths])


def test_voxelize_many_stacks_what_voxelize_gives_one_by_one(data_path):
    paths = [data_path(m) for m in MESHES]
    batch = voxfx.voxelize_many(paths, 32, padding=2)
    assert batch.shape == (5, 32, 32, 32) and batch.dtype == np.bool_
    assert np.array_equal(batch, one_by_one(paths, 32, 2))
    # The padding stays empty (two cells on every side).
    assert not batch[:, :2].any() and not batch[:, -2:].any() and not batch[:, :, :2].any()
    # Mesh objects and paths mixed; other modes; one thread gives the same bits.
    mixed = [voxfx.load_mesh(paths[0]), paths[1], tuple(voxfx.load_mesh(paths[2]))]
    assert np.array_equal(voxfx.voxelize_many(mixed, 32, padding=2, threads=1), batch[:3])
    surface = voxfx.voxelize_many(paths[:2], 24, mode="surface")
    assert np.array_equal(surface, one_by_one(paths[:2], 24, 0, mode="surface"))


def test_sparse_coordinates_carry_the_batch_index_first(data_path):
    paths = [data_path(m) for m in MESHES]
    dense = voxfx.voxelize_many(paths, 32, padding=1)
    coords = voxfx.voxelize_many(paths, 32, padding=1, sparse=True)
    assert coords.dtype == np.int32 and coords.shape[1] == 4
    assert np.array_equal(coords, np.argwhere(dense).astype(np.int32))
    assert np.array_equal(np.unique(coords[:, 0]), np.arange(5))


def test_dims_stack_unequal_cells_and_bad_batches_name_the_item(data_path, tmp_path):
    paths = [data_path(m) for m in MESHES[:2]]
    stretched = voxfx.voxelize_many(paths, dims=(16, 8, 12), cube=False)
    assert stretched.shape == (2, 16, 8, 12)
    with pytest.warns(UserWarning):
        single = voxfx.voxelize(voxfx.load_mesh(paths[1]), dims=(16, 8, 12)).to_numpy()
    assert np.array_equal(stretched[1], single)
    with pytest.raises(voxfx.ArgumentError, match="cube=True"):
        voxfx.voxelize_many(paths, 16, cube=False)
    broken = tmp_path / "broken.off"
    broken.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")
    with pytest.raises(voxfx.Error, match=r"item 1 .*broken\.off"):
        voxfx.voxelize_many([paths[0], str(broken), paths[1]], 16)
    with pytest.raises(TypeError):
        voxfx.voxelize_many(paths[0], 16)


def test_torch_tensors_in_and_out(data_path):
    torch = pytest.importorskip("torch")
    mesh = voxfx.load_mesh(data_path("meshes/elephant.off"))
    v = torch.tensor(mesh.vertices, requires_grad=True)  # a leaf that wants gradients: detached
    f = torch.from_numpy(mesh.faces)
    out = voxfx.voxelize_many([(v, f)], 24, as_tensor=True)
    assert isinstance(out, torch.Tensor) and out.dtype == torch.bool and not out.requires_grad
    assert np.array_equal(out.numpy(), voxfx.voxelize_many([mesh], 24))
    coords = voxfx.voxelize_many([(v, f)], 24, sparse=True, as_tensor=True)
    assert coords.dtype == torch.int32 and coords.shape[1] == 4
    s = voxfx.sample_near_surface((v, f), 1000, 0.01, as_tensor=True)
    assert s.sdf.dtype == torch.float64 and s.inside.dtype == torch.bool
    # Every function takes tensors where it takes arrays (contains: mesh and points).
    pts = torch.rand(100, 3, dtype=torch.float64, requires_grad=True)
    assert np.array_equal(voxfx.contains((v, f), pts), voxfx.contains(mesh, pts.detach().numpy()))
    if torch.cuda.is_available():
        with pytest.raises(TypeError, match="CPU"):
            voxfx.voxelize_many([(v.cuda(), f)], 8)


def test_a_dataloader_collates_samples_into_batches(data_path):
    torch = pytest.importorskip("torch")
    from torch.utils.data import DataLoader, Dataset

    class Shapes(Dataset):
        def __init__(self, paths):
            self.meshes = [voxfx.load_mesh(p) for p in paths]

        def __len__(self):
            return len(self.meshes)

        def __getitem__(self, i):
            s = voxfx.sample_near_surface(self.meshes[i], 512, 0.01, seed=i, as_tensor=True)
            return s.points.float(), s.sdf.float()

    loader = DataLoader(Shapes([data_path(m) for m in MESHES[:4]]), batch_size=2)
    batches = list(loader)
    assert [tuple(b[0].shape) for b in batches] == [(2, 512, 3), (2, 512, 3)]
    # The dataset's meshes pickle (what DataLoader workers need).
    assert pickle.loads(pickle.dumps(voxfx.load_mesh(data_path(MESHES[0])))).triangle_count > 0


def write_manifest(tmp_path, paths):
    manifest = tmp_path / "meshes.txt"
    manifest.write_text("\n".join(paths) + "\n")
    return manifest


def test_batch_command_writes_npy_and_npz_with_cube_and_padding(data_path, cli, tmp_path):
    paths = [data_path(m) for m in MESHES[:3]]
    manifest = write_manifest(tmp_path, paths)
    expected = one_by_one(paths, 32, 3)
    for fmt in ("npy", "npz"):
        out = tmp_path / fmt
        subprocess.run([cli, "batch", str(manifest), "-o", str(out), "-r", "32", "--cube", "--padding", "3",
                        "--format", fmt, "-q"], check=True, capture_output=True)
        for p, grid in zip(paths, expected):
            stem = os.path.splitext(os.path.basename(p))[0]
            loaded = np.load(out / f"{stem}.{fmt}")
            if fmt == "npz":
                single = voxfx.voxelize(voxfx.load_mesh(p), resolution=32, cube=True, padding=3)
                assert sorted(loaded.files) == ["cell_size", "occupancy", "origin"]
                assert np.allclose(loaded["origin"], single.origin) and np.allclose(loaded["cell_size"], single.cell_size)
                loaded = loaded["occupancy"]
            assert loaded.dtype == np.bool_ and np.array_equal(loaded, grid)
    # voxfx.batch takes the same options and writes the same bytes.
    report = voxfx.batch(paths, tmp_path / "py", format=".npz", resolution=32, cube=True, padding=3)
    assert report["ok"] == 3
    for p in paths:
        name = os.path.splitext(os.path.basename(p))[0] + ".npz"
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "npz" / name).read_bytes()
    bad = subprocess.run([cli, "batch", str(manifest), "-o", str(tmp_path / "bad"), "-r", "8", "--padding", "4"],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "--padding" in bad.stderr


def test_grid_save_writes_npy_that_numpy_reads(data_path, tmp_path):
    grid = voxfx.voxelize(voxfx.load_mesh(data_path("meshes/elephant.off")), resolution=40, axis="x")
    grid.save(tmp_path / "g.npy")
    assert np.array_equal(np.load(tmp_path / "g.npy"), grid.to_numpy())
    with pytest.raises(voxfx.Error, match="not read back"):
        voxfx.read_grid(tmp_path / "g.npy")


def test_dask_run_manifest_takes_cube_and_padding(data_path, tmp_path):
    pytest.importorskip("distributed")
    import voxfx.dask
    from distributed import Client, LocalCluster

    paths = [data_path(m) for m in MESHES[:3]]
    manifest = write_manifest(tmp_path, paths)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        report = voxfx.dask.run_manifest(manifest, tmp_path / "out", client=client, format=".npy", resolution=32,
                                         cube=True, padding=2, chunk=2)
    assert report["ok"] == 3
    expected = one_by_one(paths, 32, 2)
    for p, grid in zip(paths, expected):
        stem = os.path.splitext(os.path.basename(p))[0]
        assert np.array_equal(np.load(tmp_path / "out" / f"{stem}.npy"), grid)
