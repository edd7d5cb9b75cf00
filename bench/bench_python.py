#!/usr/bin/env python3
"""voxfx's Python module against Open3D on the same CGAL meshes and points, in one run.

  surface voxels: voxfx.voxelize(mode="conservative") vs VoxelGrid.create_from_triangle_mesh,
                  in the same grid (Open3D's origin and voxel size passed as voxfx bounds);
                  agreement with voxfx's conservative cells, which the C++ tests check against
                  CGAL's exact triangle/box overlap.
  occupancy:      voxfx.contains vs RaycastingScene.compute_occupancy on uniform points in the
                  mesh's bounds (float32, as Open3D takes them); agreement with the exact answer
                  (voxfx.contains, checked against CGAL::Side_of_triangle_mesh in the C++ tests).

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [--points N] [--repeat R]
       [--resolution N] [--embree-fix auto|off] [meshes...]
       (default: a few closed CGAL meshes under data/meshes)
Timings are the best of R runs, wall clock, all threads of both libraries.

Debian's Open3D 0.16 casts rays that hit nothing: Open3D sets every ray's mask to 0, which only
works with an Embree built without ray masks (as Open3D's bundled one is), and Debian's libembree3
is built with them. With --embree-fix auto (the default) the script checks a ray into a box and,
when it misses, compiles bench/open3d_embree_mask_fix.c (a preloaded shim that sets the masks to
0xFFFFFFFF) and runs itself again under LD_PRELOAD. --embree-fix off measures Open3D as installed.
"""
import argparse
import atexit
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

import voxfx

try:
    import open3d as o3d
except ImportError:  # pragma: no cover
    sys.exit("bench_python.py needs Open3D (Debian: python3-open3d)")

DEFAULT_MESHES = ["bunny00.off", "armadillo.off", "elephant.off", "knot.off", "cow.off", "pinion.off"]


def open3d_rays_hit():
    """Whether a ray from the centre of a unit box hits the box in Open3D's RaycastingScene."""
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(o3d.geometry.TriangleMesh.create_box()))
    rays = o3d.core.Tensor([[0.5, 0.5, 0.5, 1, 0, 0]], dtype=o3d.core.Dtype.Float32)
    return bool(np.isfinite(scene.cast_rays(rays)["t_hit"].numpy()[0]))


def run_with_embree_fix():
    """Compiles the ray-mask shim and runs this script again with it preloaded (does not return)."""
    here = os.path.dirname(os.path.abspath(__file__))
    lib = os.path.join(tempfile.mkdtemp(prefix="voxfx-o3d-fix."), "open3d_embree_mask_fix.so")
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", lib, os.path.join(here, "open3d_embree_mask_fix.c"),
                    "-ldl"], check=True)
    env = dict(os.environ, VOXFX_BENCH_EMBREE_FIX=lib)
    env["LD_PRELOAD"] = lib + (":" + env["LD_PRELOAD"] if env.get("LD_PRELOAD") else "")
    sys.stdout.flush()
    os.execve(sys.executable, [sys.executable] + sys.argv, env)


def best(fn, repeat):
    times, result = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return min(times), result


def surface(mesh, v, f, resolution, repeat, budget):
    tm = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
    extent = v.max(axis=0) - v.min(axis=0)
    # Open3D 0.16 tests every triangle against every voxel of the bounds (about 5.6M pairs per
    # second here): the resolution is capped so that it finishes in seconds.
    volume = float(np.prod(np.maximum(extent / extent.max(), 1e-3)))
    resolution = max(4, min(resolution, int((budget / (len(f) * volume)) ** (1 / 3))))
    size = float(extent.max()) / resolution
    t_o3d, vg = best(lambda: o3d.geometry.VoxelGrid.create_from_triangle_mesh(tm, size), repeat)
    idx = np.array([vx.grid_index for vx in vg.get_voxels()], dtype=np.int64)
    # Open3D's voxel (i, j, k) is centred on origin + (i, j, k) * size.
    origin = np.asarray(vg.origin) - 0.5 * size
    dims = idx.max(axis=0) + 1
    bounds = tuple(origin) + tuple(origin + dims * size)
    t_vox, grid = best(lambda: voxfx.voxelize(mesh, dims=tuple(int(d) for d in dims), bounds=bounds,
                                              mode="conservative"), repeat)
    ours = grid.to_numpy()
    theirs = np.zeros_like(ours)
    theirs[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    both = np.count_nonzero(ours & theirs)
    return {
        "grid": "x".join(map(str, dims)), "resolution": resolution,
        "voxfx_ms": t_vox * 1e3, "open3d_ms": t_o3d * 1e3,
        "voxfx_cells": int(ours.sum()), "open3d_cells": int(theirs.sum()),
        "open3d_missing": int(ours.sum() - both), "open3d_extra": int(theirs.sum() - both),
    }


def occupancy(mesh, v, f, n, repeat, seed=1):
    lo, hi = v.min(axis=0), v.max(axis=0)
    pts32 = np.random.default_rng(seed).uniform(lo, hi, (n, 3)).astype(np.float32)
    pts = pts32.astype(np.float64)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
    query = o3d.core.Tensor(pts32)
    scene.compute_occupancy(query)  # builds the BVH once, outside the timing
    t_o3d, occ = best(lambda: scene.compute_occupancy(query).numpy().astype(bool), repeat)
    t_vox, exact = best(lambda: voxfx.contains(mesh, pts), repeat)
    return {
        "points": n, "voxfx_ms": t_vox * 1e3, "open3d_ms": t_o3d * 1e3,
        "voxfx_mpts_s": n / t_vox / 1e6, "open3d_mpts_s": n / t_o3d / 1e6,
        "inside": int(exact.sum()), "open3d_wrong": int(np.count_nonzero(occ != exact)),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="*")
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--pairs", type=float, default=2e7,
                    help="cap the surface resolution so that triangles x voxels stays under this")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--embree-fix", choices=("auto", "off"), default="auto",
                    help="preload the ray-mask shim when Open3D's rays miss everything (see above)")
    a = ap.parse_args()
    fix = os.environ.get("VOXFX_BENCH_EMBREE_FIX")
    if fix:  # the compiled shim's folder goes when this run ends (the library stays mapped)
        atexit.register(shutil.rmtree, os.path.dirname(fix), True)
    if open3d_rays_hit():
        rays = "works with bench/open3d_embree_mask_fix.c preloaded" if fix else "works as installed"
    elif a.embree_fix == "auto" and not fix:
        run_with_embree_fix()
    else:
        rays = "BROKEN: every ray misses (occupancy answers are all 0)"
    data = os.environ.get("VOXFX_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "data"))
    paths = a.meshes or [os.path.join(data, "meshes", m) for m in DEFAULT_MESHES]
    print(f"voxfx {voxfx.__version__}, Open3D {o3d.__version__}, {os.cpu_count()} CPUs; "
          f"surface at up to {a.resolution} cells along the longest side, {a.points:,} points, best of {a.repeat}")
    print(f"Open3D ray casting: {rays}")
    print("| mesh | triangles | grid | voxfx ms | Open3D ms | voxfx cells | Open3D missing | Open3D extra |"
          " voxfx contains ms (Mpts/s) | Open3D occupancy ms (Mpts/s) | Open3D wrong |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for p in paths:
        if not os.path.exists(p):
            print(f"skipping {p}: missing (scripts/fetch-data.sh)", file=sys.stderr)
            continue
        mesh = voxfx.load_mesh(p)
        v, f = mesh
        s = surface(mesh, v, f, a.resolution, a.repeat, a.pairs)
        o = occupancy(mesh, v, f, a.points, a.repeat)
        print(f"| {os.path.basename(p)} | {len(f):,} | {s['grid']} | {s['voxfx_ms']:.1f} | {s['open3d_ms']:.1f} | "
              f"{s['voxfx_cells']:,} | {s['open3d_missing']:,} | {s['open3d_extra']:,} | "
              f"{o['voxfx_ms']:.0f} ({o['voxfx_mpts_s']:.2f}) | {o['open3d_ms']:.0f} ({o['open3d_mpts_s']:.2f}) | "
              f"{o['open3d_wrong']:,} |", flush=True)


if __name__ == "__main__":
    main()
