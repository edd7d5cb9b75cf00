"""voxfx.dask on a LocalCluster of two worker processes: outputs and per-mesh report records
identical to `voxfx batch` with the same options, a bad mesh reported without stopping the rest,
finished outputs skipped on a second run."""
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


def records_without_times(report):
    """The per-mesh records without the timings and with outputs by file name (folders differ)."""
    return [dict({k: v for k, v in j.items() if k != "ms"}, output=os.path.basename(j["output"]))
            for j in report["jobs"]]


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
    theirs = tmp_path / "cli"
    r = subprocess.run([cli, "batch", str(manifest), "-o", str(theirs), "-r", "40", "-m", "solid", "-q", "-j", "1"],
                       capture_output=True, text=True)
    assert r.returncode == 2, r.stderr  # one mesh failed
    cli_report = json.loads((theirs / "report.json").read_text())

    # The same per-mesh records as the command's (times aside), in manifest order, the counts
    # recomputed over all chunks, and the file is the returned report.
    assert records_without_times(report) == records_without_times(cli_report)
    assert [os.path.realpath(j["mesh"]) for j in report["jobs"]] == \
        [os.path.realpath(m) for m in meshes + [str(manifest.parent / "missing.off")]]
    assert [j["status"] for j in report["jobs"]] == ["ok"] * len(MESHES) + ["error"]
    assert "missing.off" in report["jobs"][-1]["error"]
    assert list(report) == list(cli_report)  # the command's keys, in its order
    assert (report["ok"], report["skipped"], report["errors"]) == (len(MESHES), 0, 1)
    assert report["ok_per_second"] == pytest.approx(report["ok"] / report["seconds"])
    assert json.loads((out / "report.json").read_text()) == report

    # Outputs byte-identical to the command's; no temporary files left behind.
    for m in MESHES:
        name = os.path.splitext(m)[0] + ".binvox"
        assert (out / name).read_bytes() == (theirs / name).read_bytes(), m
    assert sorted(os.listdir(out)) == sorted(os.listdir(theirs))

    # A second run skips what is there, in other chunks, and counts it.
    again = voxfx.dask.run_manifest(str(manifest), str(out), client=client, chunk=3, resolution=40)
    assert [j["status"] for j in again["jobs"]] == ["skipped"] * len(MESHES) + ["error"]
    assert (again["ok"], again["skipped"], again["errors"]) == (0, len(MESHES), 1)


def test_run_manifest_rejects_bad_options(tmp_path):
    manifest = tmp_path / "m.txt"
    manifest.write_text("a.off\n")
    with pytest.raises(TypeError):
        voxfx.dask.run_manifest(str(manifest), str(tmp_path), resolutoin=3)
    with pytest.raises(ValueError):
        voxfx.dask.run_manifest(str(manifest), str(tmp_path), format=".xyz")
    # Two meshes whose outputs would collide: refused as the command refuses them, before any work.
    manifest.write_text("a/x.off\nb/x.off\n")
    with pytest.raises(voxfx.Error, match="stem"):
        voxfx.dask.run_manifest(str(manifest), str(tmp_path / "never"))
    assert not (tmp_path / "never").exists()
