"""voxfx.dask on a LocalCluster of two worker processes: outputs byte-identical to
`voxfx voxelize MESH -o OUT` with the same options, a bad mesh reported without stopping the
rest, finished outputs skipped on a second run."""
import json
import os
import subprocess

import pytest

distributed = pytest.importorskip("distributed")

import voxfx.dask  # noqa: E402

MESHES = ["knot.off", "cow.off", "elephant-with-holes.off", "cross.off", "pinion.off"]


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_run_manifest_matches_the_cli(tmp_path, cli, data_path, client):
    meshes = [data_path("meshes/" + m) for m in MESHES]
    manifest = tmp_path / "list" / "manifest.txt"
    manifest.parent.mkdir()
    lines = ["# CGAL meshes, relative to this file", ""]
    lines += [os.path.relpath(m, manifest.parent) for m in meshes]
    lines += ["missing.off"]
    manifest.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out"
    report = voxfx.dask.run_manifest(str(manifest), str(out), client=client, chunk=2, resolution=40,
                                     mode="solid", format=".binvox", threads=1)
    assert [r["mesh"] for r in report] == meshes + [str(manifest.parent / "missing.off")]
    assert all(r["error"] is None for r in report[:-1])
    assert "missing.off" in report[-1]["error"]
    assert json.loads((out / "report.json").read_text()) == report
    for m in meshes:
        stem = os.path.splitext(os.path.basename(m))[0]
        expected = tmp_path / (stem + ".cli.binvox")
        subprocess.run([cli, "voxelize", m, "-o", expected, "-r", "40", "-m", "solid", "-q", "-j", "1"],
                       check=True, capture_output=True)
        assert (out / (stem + ".binvox")).read_bytes() == expected.read_bytes(), m
    # No temporary files are left behind.
    assert sorted(os.listdir(out)) == sorted([os.path.splitext(m)[0] + ".binvox" for m in MESHES] + ["report.json"])

    # A second run skips what is there.
    again = voxfx.dask.run_manifest(str(manifest), str(out), client=client, chunk=3, resolution=40)
    assert all(r["skipped"] for r in again[:-1]) and again[-1]["error"]


def test_run_manifest_rejects_bad_options(tmp_path):
    manifest = tmp_path / "m.txt"
    manifest.write_text("a.off\n")
    with pytest.raises(TypeError):
        voxfx.dask.run_manifest(str(manifest), str(tmp_path), resolutoin=3)
    with pytest.raises(ValueError):
        voxfx.dask.run_manifest(str(manifest), str(tmp_path), format=".xyz")
