"""voxfx.voxelize(..., sparse=True) and voxfx.SparseGrid (python/bindings/sparse.cpp): the cells as
(N, 3) int32 coordinates without a dense array, against the dense grid's NumPy array (the same
voxels, #23), and the transform that places them."""
import numpy as np
import pytest

import voxfx


def _cells(coords):
    return {tuple(c) for c in coords.tolist()}


@pytest.mark.parametrize("mode,fill", [("solid", "auto"), ("conservative", "auto"), ("solid", "gwn")])
def test_sparse_coordinates_are_the_dense_grids_cells(data_path, mode, fill):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    for axis in ("x", "z"):
        dense = voxfx.voxelize(mesh, resolution=40, mode=mode, fill=fill, axis=axis)
        sparse = voxfx.voxelize(mesh, resolution=40, mode=mode, fill=fill, axis=axis, sparse=True)
        assert isinstance(sparse, voxfx.SparseGrid)
        coords = sparse.coordinates()
        assert coords.dtype == np.int32 and coords.shape == (dense.count(), 3) == (sparse.count, 3)
        assert _cells(coords) == _cells(np.argwhere(dense.to_numpy()))
        assert sparse.dims == dense.dims
        assert sparse.to_grid() == dense


def test_transform_maps_coordinates_to_voxel_centres(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/knot.off"))
    dense = voxfx.voxelize(mesh, dims=(10, 20, 30))
    sparse = voxfx.voxelize(mesh, dims=(10, 20, 30), sparse=True)
    coords = sparse.coordinates()
    world = (sparse.transform @ np.c_[coords, np.ones(len(coords))].T).T[:, :3]
    expected = np.array(dense.origin) + (coords + 0.5) * np.array(dense.cell_size)
    np.testing.assert_allclose(world, expected, rtol=0, atol=1e-12)
    assert sparse.origin == dense.origin and sparse.cell_size == dense.cell_size


def test_save_and_read_without_a_dense_grid(tmp_path, data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    sparse = voxfx.voxelize(mesh, resolution=64, sparse=True)
    sparse.save(str(tmp_path / "b.vdb"))
    back = voxfx.read_sparse_grid(str(tmp_path / "b.vdb"))
    assert back.count == sparse.count and back.dims == sparse.dims
    assert voxfx.read_grid(str(tmp_path / "b.vdb")) == voxfx.voxelize(mesh, resolution=64)
    assert _cells(back.coordinates()) == _cells(sparse.coordinates())


def test_operations_follow_numpy(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    solid = voxfx.voxelize(mesh, resolution=32, sparse=True)
    shell = voxfx.voxelize(mesh, resolution=32, mode="conservative", sparse=True)
    a, b = solid.to_grid().to_numpy(), shell.to_grid().to_numpy()
    assert solid.copy().unite(shell).count == int((a | b).sum())
    assert solid.copy().intersect(shell).count == int((a & b).sum())
    assert solid.copy().subtract(shell).count == int((a & ~b).sum())
    grown = solid.copy().dilate(1, neighbours=6)
    assert grown.count > solid.count
    with pytest.raises(ValueError):
        solid.dilate(1, neighbours=7)
    assert voxfx.SparseGrid.from_grid(solid.to_grid()).count == solid.count
