"""voxfx.dask.voxelize_grid on a real cluster: a `dask-scheduler` and two `dask-worker` processes
over TCP on this machine. The Zarr store's bits equal the single-process tiled voxelization
(voxfx.voxelize(..., sparse=True)) chunk by chunk at 1024^3 (the bunny, and the elephant with holes
through the gwn fill); a run whose driver and one worker are killed half-way gives the same store
after a rerun, which skips what was finished; what the tiles cannot do is refused before any task."""
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")
zarr = pytest.importorskip("zarr")

import voxfx  # noqa: E402
import voxfx.dask  # noqa: E402


def _env():
    """The environment of the cluster's processes: this voxfx importable, one thread each."""
    env = dict(os.environ)
    here = os.path.dirname(os.path.dirname(os.path.abspath(voxfx.__file__)))
    env["PYTHONPATH"] = here + os.pathsep + env.get("PYTHONPATH", "")
    env["OMP_NUM_THREADS"] = "1"
    return env


def _start_worker(scheduler_file, name):
    return subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file",
                             str(scheduler_file), "--nworkers", "1", "--nthreads", "1", "--no-dashboard",
                             "--memory-limit", "0", "--name", name], env=_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """(scheduler file, {name: worker process}): the scheduler and two workers, stopped at the end."""
    folder = tmp_path_factory.mktemp("cluster")
    scheduler_file = folder / "scheduler.json"
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                                 env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = {name: _start_worker(scheduler_file, name) for name in ("a", "b")}
    deadline = time.monotonic() + 60
    while not scheduler_file.exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    yield scheduler_file, workers
    for p in list(workers.values()) + [scheduler]:
        p.terminate()
    for p in list(workers.values()) + [scheduler]:
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()


@pytest.fixture
def client(cluster):
    scheduler_file, _ = cluster
    c = distributed.Client(scheduler_file=str(scheduler_file), timeout=60)
    c.wait_for_workers(2, timeout=60)
    yield c
    c.close()


def _expect_store_equals(store, reference):
    """Every brick of the store's voxels equals the reference grid's cells there; the counts agree."""
    voxels = zarr.open_group(store, mode="r")["voxels"]
    assert voxels.shape == reference.dims
    dense = reference.to_numpy()  # 1 GiB at 1024^3: once, not per brick
    b = voxels.chunks[0]
    total = 0
    for x0 in range(0, voxels.shape[0], b):
        for y0 in range(0, voxels.shape[1], b):
            for z0 in range(0, voxels.shape[2], b):
                ours = voxels[x0:x0 + b, y0:y0 + b, z0:z0 + b]
                theirs = dense[x0:x0 + b, y0:y0 + b, z0:z0 + b]
                assert np.array_equal(ours, theirs), (x0, y0, z0)
                total += int(ours.sum())
    assert total == reference.count() == int(dense.sum())


# 1024^3 (the size) in the slow suite, a grid of 16^3 bricks of 16 cells in the fast one.
@pytest.mark.parametrize("resolution,brick", [(256, 16), pytest.param(1024, 128, marks=pytest.mark.slow)])
@pytest.mark.parametrize("name,fill", [("bunny00.off", "parity"), ("elephant-with-holes.off", "gwn")])
def test_the_store_equals_the_single_process_tiles(tmp_path, data_path, client, name, fill, resolution, brick):
    mesh = voxfx.load_mesh(data_path("meshes/" + name))
    store = str(tmp_path / "grid.zarr")
    summary = voxfx.dask.voxelize_grid(mesh, resolution, client, store, fill=fill, brick=brick, progress=False)
    reference = voxfx.voxelize(mesh, resolution=resolution, fill=fill, sparse=True).to_grid()
    assert summary["dims"] == reference.dims
    stacks = math.ceil(reference.dims[0] / brick) * math.ceil(reference.dims[1] / brick)
    assert summary["skipped"] == 0 and summary["tasks"] <= stacks
    _expect_store_equals(store, reference)

    # The attributes place the grid: the affine is the reference's, and dask reads the array lazily.
    attrs = zarr.open_group(store, mode="r").attrs
    assert np.allclose(attrs["affine"], reference.affine)
    assert np.allclose(attrs["voxel_size"], reference.cell_size)
    lazy = voxfx.dask.open_grid(store)
    assert lazy.shape == reference.dims and lazy.dtype == bool
    half = resolution // 2
    assert int(lazy[:, :, half].sum().compute()) == int(reference.to_numpy()[:, :, half].sum())
    # Empty bricks are not written: fewer chunk files than bricks.
    chunks = [f for f in os.listdir(os.path.join(store, "voxels")) if not f.startswith(".")]
    assert 0 < len(chunks) < math.prod(math.ceil(n / brick) for n in reference.dims)
    assert not [f for f in chunks if f.endswith(".partial")]  # every chunk file renamed into place


def test_a_store_that_is_not_a_folder_of_chunk_files_gets_the_same_bits(tmp_path, data_path, client):
    """Full bricks go straight to the files of a plain DirectoryStore; any other store (here nested
    chunk folders, keys x/y/z) gets every chunk through zarr, with the same bits."""
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    store = zarr.storage.NestedDirectoryStore(str(tmp_path / "nested.zarr"))
    voxfx.dask.voxelize_grid(mesh, 128, client, store, brick=16, progress=False)
    assert os.path.isdir(tmp_path / "nested.zarr" / "voxels" / "3")  # nested: not the files voxfx writes
    _expect_store_equals(store, voxfx.voxelize(mesh, resolution=128, fill="parity", sparse=True).to_grid())


def test_a_run_killed_half_way_gives_the_same_store_after_a_rerun(tmp_path, data_path, cluster, client):
    scheduler_file, workers = cluster
    path = data_path("meshes/armadillo.off")
    store = str(tmp_path / "armadillo.zarr")
    args = dict(brick=32, stacks_per_task=1, progress=False)
    # The driver in its own process, so that it can be killed with a worker while tasks run.
    driver = subprocess.Popen([sys.executable, "-c", (
        "import sys, distributed, voxfx.dask\n"
        f"c = distributed.Client(scheduler_file={str(scheduler_file)!r})\n"
        f"voxfx.dask.voxelize_grid({path!r}, 384, c, {store!r}, **{args!r})\n")], env=_env())
    dims = voxfx.voxelize(voxfx.load_mesh(path), resolution=384, sparse=True).dims
    tasks = math.ceil(dims[0] / 32) * math.ceil(dims[1] / 32)
    done = 0
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and driver.poll() is None:
        try:
            done = int(zarr.open_group(store, mode="r")["done"][:].sum())
        except Exception:  # the store is not made yet
            done = 0
        if done >= tasks // 4:
            break
        time.sleep(0.02)
    assert done >= tasks // 4, f"the first run marked {done} of {tasks} tasks done"
    workers["a"].send_signal(signal.SIGKILL)
    driver.send_signal(signal.SIGKILL)
    driver.wait()
    workers["a"].wait()
    workers["a"] = _start_worker(scheduler_file, "a2")
    client.wait_for_workers(2, timeout=60)

    before = int(zarr.open_group(store, mode="r")["done"][:].sum())
    summary = voxfx.dask.voxelize_grid(path, 384, client, store, **args)
    assert summary["tasks"] == tasks
    # Tasks the killed driver had started may still finish and mark themselves after `before` was
    # read: the rerun skips at least what was marked then.
    assert summary["skipped"] >= before >= tasks // 4
    reference = voxfx.voxelize(voxfx.load_mesh(path), resolution=384, sparse=True).to_grid()
    _expect_store_equals(store, reference)
    # A third run has nothing left to do.
    assert voxfx.dask.voxelize_grid(path, 384, client, store, **args)["skipped"] == tasks


def test_what_the_tiles_cannot_do_is_refused_before_any_task(tmp_path, data_path):
    mesh = voxfx.load_mesh(data_path("meshes/elephant-with-holes.off"))
    with pytest.raises(voxfx.Error, match="flood"):  # auto is flood on an open mesh
        voxfx.dask.voxelize_grid(mesh, 64, None, str(tmp_path / "a.zarr"))
    with pytest.raises(ValueError, match="multiple of 8"):
        voxfx.dask.voxelize_grid(mesh, 64, None, str(tmp_path / "b.zarr"), brick=12, fill="gwn")
    # A store made for other options is not overwritten silently; a folder of other files never.
    bunny = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    store = str(tmp_path / "c.zarr")
    voxfx.dask.voxelize_grid(bunny, 32, _LocalClient(), store, progress=False)
    with pytest.raises(ValueError, match="another grid"):
        voxfx.dask.voxelize_grid(bunny, 40, _LocalClient(), store, progress=False)
    other = tmp_path / "photos"
    other.mkdir()
    (other / "a.jpg").write_bytes(b"x")
    with pytest.raises(ValueError, match="not a Zarr group"):
        voxfx.dask.voxelize_grid(bunny, 32, _LocalClient(), str(other), progress=False)
    assert (other / "a.jpg").read_bytes() == b"x"


class _LocalClient:
    """A client that runs each task in this process (client.submit/gather/scatter), for the checks
    that need no cluster."""
    dashboard_link = None

    def scatter(self, value, broadcast=False):
        return value

    def submit(self, fn, *args, pure=False, **kwargs):
        return fn(*args, **kwargs)

    def gather(self, futures):
        return futures


def test_the_command_hands_a_zarr_output_to_the_cluster(tmp_path, data_path, cli):
    path = data_path("meshes/bunny00.off")
    store = tmp_path / "bunny.zarr"
    r = subprocess.run([cli, "voxelize", path, "-r", "64", "--brick", "16", "-o", str(store), "-q"],
                       capture_output=True, text=True, env=_env(), timeout=600)
    assert r.returncode == 0, r.stderr
    ours = zarr.open_group(str(store), mode="r")["voxels"][:]
    assert np.array_equal(ours, voxfx.voxelize(voxfx.load_mesh(path), resolution=64).to_numpy())
    # What a Zarr grid cannot be is refused by the command itself, and nothing is written.
    bad = tmp_path / "x.zarr"
    r = subprocess.run([cli, "voxelize", path, "-r", "64", "--axis", "x", "-o", str(bad)], capture_output=True,
                       text=True, env=_env(), timeout=60)
    assert r.returncode != 0 and "sliced along z" in r.stderr and not bad.exists()


def _columns_crossed(vertices, faces, frame_lo, cell, x_range, y_range):
    """Brute force: the triangles whose x-y projection holds a column centre of the rectangle
    x_range x y_range (cells), by barycentric signs on every centre of each triangle's box."""
    out = set()
    for t, f in enumerate(faces):
        p = (vertices[f, :2] - frame_lo[:2]) / cell[:2] - 0.5  # column centres at integers
        lo, hi = np.floor(p.min(axis=0)).astype(int), np.ceil(p.max(axis=0)).astype(int)
        xs = np.arange(max(lo[0], x_range[0]), min(hi[0], x_range[1] - 1) + 1)
        ys = np.arange(max(lo[1], y_range[0]), min(hi[1], y_range[1] - 1) + 1)
        if not len(xs) or not len(ys):
            continue
        gx, gy = np.meshgrid(xs, ys)
        a, b, c = p
        def side(u, v):
            return (v[0] - u[0]) * (gy - u[1]) - (v[1] - u[1]) * (gx - u[0])
        s = np.stack([side(a, b), side(b, c), side(c, a)])
        if ((s >= 0).all(axis=0) | (s <= 0).all(axis=0)).any():
            out.add(t)
    return out


def test_each_task_gets_the_triangles_over_its_columns_and_not_the_whole_mesh(data_path):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    plan = voxfx._voxfx._grid_frame(mesh, resolution=128)
    frame, dims, brick, k = plan["frame"], plan["dims"], 16, 2
    parts = voxfx._voxfx._task_meshes(mesh, frame, brick=brick, stacks_per_task=k)
    tasks = voxfx.dask._tasks_of(dims, brick, k)
    assert len(parts) == len(tasks)
    v, f = mesh.vertices - np.asarray(mesh.origin), mesh.faces
    lo = np.asarray(frame[0])
    cell = (np.asarray(frame[1]) - lo) / np.asarray(dims)
    # Triangles are told apart by their corners (a part renumbers its vertices).
    def keys(vertices, faces):
        return {tuple(sorted(map(tuple, np.round(vertices[t], 6)))) for t in faces}
    sizes = []
    for (tx, ty, x0, y0, x1, y1), part in zip(tasks, parts):
        crossed = _columns_crossed(v, f, lo, cell, (x0 * brick, x1 * brick), (y0 * brick, y1 * brick))
        if part is None:
            assert not crossed, (tx, ty)
            continue
        pv = part.vertices - np.asarray(mesh.origin)
        assert keys(v, f[sorted(crossed)]) <= keys(pv, part.faces), (tx, ty)
        sizes.append(len(part.faces))
    # Each part is a small piece of the mesh; together about the mesh once (a border triangle twice).
    assert max(sizes) < 0.25 * len(f) and sum(sizes) < 1.3 * len(f)


@pytest.mark.parametrize("batch_bytes,threads", [(64 << 20, 1), (3 * (1 + 16 ** 3 // 8), 2)])
def test_a_stack_comes_in_one_call_with_its_bricks_packed_as_zarr_packs_them(data_path, batch_bytes, threads):
    """_voxelize_stacks(visit_stack=...): each written brick once, full ones by position and mixed
    ones as the numcodecs.PackBits bytes of their chunk, against the dense voxelize() grid; one call
    per stack unless the packed bytes pass batch_bytes (then a stack comes in several)."""
    import numcodecs

    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    plan = voxfx._voxfx._grid_frame(mesh, resolution=96)
    frame, dims, b = plan["frame"], plan["dims"], 16
    dense = np.pad(voxfx.voxelize(mesh, resolution=96, fill="parity").to_numpy(),
                   [(0, -n % b) for n in dims])  # the grid's cells, False past its end as in a chunk
    calls, seen = [], {}

    def visit(x0, y0, full, mixed, packed):
        calls.append((x0, y0))
        assert packed.dtype == np.uint8 and packed.shape == (len(mixed), 1 + b ** 3 // 8)
        for z0 in full:  # a full brick's cells in the grid; past its end a chunk holds none
            seen[(x0, y0, z0)] = np.zeros((b, b, b), dtype=bool)
            seen[(x0, y0, z0)][:dims[0] - x0, :dims[1] - y0, :dims[2] - z0] = True
        for z0, chunk in zip(mixed, packed):
            seen[(x0, y0, z0)] = numcodecs.PackBits().decode(chunk).reshape(b, b, b)
            assert seen[(x0, y0, z0)].any()

    stacks = [math.ceil(n / b) for n in dims[:2]]
    voxfx._voxfx._voxelize_stacks(mesh, frame, [0, 0, *stacks], brick=b, fill="parity", threads=threads,
                                  visit_stack=visit, batch_bytes=batch_bytes)
    expected = {(x, y, z) for x in range(0, dims[0], b) for y in range(0, dims[1], b) for z in range(0, dims[2], b)
                if dense[x:x + b, y:y + b, z:z + b].any()}
    assert set(seen) == expected
    for (x, y, z), bits in seen.items():
        assert np.array_equal(bits, dense[x:x + b, y:y + b, z:z + b]), (x, y, z)
    written = {(x, y) for x, y, _ in expected}
    if batch_bytes > 1 << 20:
        assert sorted(calls) == sorted(written)  # one call per stack with a written brick
    else:
        assert set(calls) == written and len(calls) > len(written)


def test_the_chunk_files_voxfx_writes_are_the_bytes_zarr_writes_and_hold_the_dense_grid(tmp_path, data_path):
    """A task on a folder store (PackBits then numcodecs.Zstd, as voxelize_grid makes it) writes its
    full and mixed chunk files itself, without the GIL: each file holds the bytes zarr's own encoder
    makes of the brick (numcodecs.Zstd: one zstd frame, compressed afresh here), and the bricks
    equal the dense voxelize() grid."""
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    b, res = 16, 96
    p = voxfx.dask._plan(mesh, res, None, None, None, 0, False, "solid", "parity", b, None)
    store = str(tmp_path / "grid.zarr")
    root, _ = voxfx.dask._open_store(store, p["shape"], b, p["attrs"], p["tasks_shape"], True)
    voxels = root["voxels"]
    assert voxfx.dask._zstd_level(voxels) == 1
    for i, part in enumerate(p["parts"]):
        if part is not None:
            voxfx.dask._grid_task(p["tasks"][i], part, frame=p["frame"], store=store, brick=b, mode="solid",
                                  fill=p["fill"], threads=2)
    folder = os.path.join(store, "voxels")
    names = [n for n in os.listdir(folder) if not n.startswith(".")]
    assert not [n for n in names if n.endswith(".partial")]
    dims = p["shape"]
    dense = np.pad(voxfx.voxelize(mesh, resolution=res, fill="parity").to_numpy(), [(0, -n % b) for n in dims])
    mixed = 0
    for name in names:
        x, y, z = (int(v) * b for v in name.split("."))
        brick = dense[x:x + b, y:y + b, z:z + b]
        assert brick.any(), name  # no chunk of the fill value
        with open(os.path.join(folder, name), "rb") as f:
            assert f.read() == bytes(voxels._encode_chunk(brick)), name
        mixed += not brick[:dims[0] - x, :dims[1] - y, :dims[2] - z].all()
    expected = {(x, y, z) for x in range(0, dims[0], b) for y in range(0, dims[1], b)
                for z in range(0, dims[2], b) if dense[x:x + b, y:y + b, z:z + b].any()}
    assert len(names) == len(expected) and mixed > 100
    assert np.array_equal(voxels[...], dense[:dims[0], :dims[1], :dims[2]])


def _expect_vdb_equals(path, reference):
    ours = voxfx.read_sparse_grid(str(path)).to_grid()
    assert ours.dims == reference.dims and np.allclose(ours.affine, reference.affine)
    assert np.array_equal(ours.to_numpy(), reference.to_numpy())


def test_regions_merged_equal_the_single_process_grid_and_a_rerun_skips_them(tmp_path, data_path, client, cli):
    mesh = voxfx.load_mesh(data_path("meshes/bunny00.off"))
    reference = voxfx.voxelize(mesh, resolution=256, sparse=True).to_grid()
    folder = tmp_path / "bunny.regions"
    s = voxfx.dask.voxelize_regions(mesh, 256, client, str(folder), brick=32, stacks_per_task=2, progress=False)
    assert s["dims"] == reference.dims and s["skipped"] == 0 and 1 < s["regions"] < s["tasks"]
    files = sorted(p for p in os.listdir(folder) if p.endswith(".vdb"))
    assert len(files) == s["regions"] and s["filled"] == reference.count()
    # The merge command and the Python merge give the single-process grid.
    r = subprocess.run([cli, "merge", str(folder), "-o", str(tmp_path / "cli.vdb")], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert f"{len(files)} regions" in r.stdout
    _expect_vdb_equals(tmp_path / "cli.vdb", reference)
    voxfx.dask.merge_regions(str(folder), str(tmp_path / "py.vdb"))
    _expect_vdb_equals(tmp_path / "py.vdb", reference)
    # A rerun skips every region done; one mark removed: that region alone runs again.
    os.remove(folder / "done" / "1-1")
    again = voxfx.dask.voxelize_regions(mesh, 256, client, str(folder), brick=32, stacks_per_task=2, progress=False)
    assert again["skipped"] == s["tasks"] - 1
    voxfx.dask.merge_regions(str(folder), str(tmp_path / "again.vdb"))
    _expect_vdb_equals(tmp_path / "again.vdb", reference)
    # Another grid's regions are refused by the merge, and nothing is written.
    other = tmp_path / "other.regions"
    voxfx.dask.voxelize_regions(mesh, 128, client, str(other), brick=32, progress=False)
    mixed = sorted(str(other / p) for p in os.listdir(other) if p.endswith(".vdb"))[:1] + [str(folder / files[0])]
    r = subprocess.run([cli, "merge", *mixed, "-o", str(tmp_path / "mixed.vdb")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode != 0 and "another grid" in r.stderr and not (tmp_path / "mixed.vdb").exists()


def test_the_command_writes_vdb_regions_on_the_cluster_and_merges_them(tmp_path, data_path, cli, cluster):
    scheduler_file, _ = cluster
    import json

    address = json.load(open(scheduler_file))["address"]
    path = data_path("meshes/bunny00.off")
    out = tmp_path / "bunny.vdb"
    r = subprocess.run([cli, "voxelize", path, "-r", "96", "--brick", "16", "-o", str(out), "--scheduler", address,
                        "-q"], capture_output=True, text=True, env=_env(), timeout=600)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "bunny.regions" / "voxfx-regions.json").exists()
    _expect_vdb_equals(out, voxfx.voxelize(voxfx.load_mesh(path), resolution=96, sparse=True).to_grid())
