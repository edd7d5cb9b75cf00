#!/usr/bin/env python3
"""Distances at a million points: voxfx against Open3D's RaycastingScene, in one run.

  distance:        voxfx.closest_points(...).distance vs compute_distance
  closest points:  voxfx.closest_points vs compute_closest_points (point, face, barycentric)
  signed distance: voxfx.signed_distance vs compute_signed_distance (Open3D's sign comes from
                   ray-cast occupancy; voxfx's from the exact inside test)

Points: "uniform" in the mesh's bounds grown by 10% on every side, "near" a random vertex moved by
a normal offset of 1% of the longest side per coordinate (float32 values, so both libraries see
the same points). Accuracy: the largest difference of Open3D's distance from voxfx's (which the C++
tests check against CGAL's exact squared distance), in units of the mesh's longest side, and the
points whose sign differs from voxfx's (exact for these closed meshes).

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_distance.py [--points N] [--repeat R]
       [meshes...]   (default: bunny00, armadillo, and data/dense/bunny1m.off when present; the
       environment's VOXFX_DENSE_DIR overrides that folder, as for bench_meshes.hpp)
Timings are the best of R runs, wall clock, all threads of both libraries; Open3D's scene is built
once outside the timing, voxfx builds its hierarchy inside every call. Open3D is Debian's
python3-open3d; its ray-mask quirk (see bench_python.py) is worked around the same way.
"""
import argparse
import os
import sys

import numpy as np

import voxfx

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_python import best, o3d, open3d_rays_hit, run_with_embree_fix  # noqa: E402


def points_for(v, kind, n, seed=7):
    rng = np.random.default_rng(seed)
    lo, hi = v.min(axis=0), v.max(axis=0)
    if kind == "uniform":
        e = hi - lo
        return rng.uniform(lo - 0.1 * e, hi + 0.1 * e, (n, 3)).astype(np.float32)
    s = 0.01 * float((hi - lo).max())
    return (v[rng.integers(0, len(v), n)] + rng.normal(0, s, (n, 3))).astype(np.float32)


def compare(mesh, v, f, kind, n, repeat):
    pts32 = points_for(v, kind, n)
    pts = pts32.astype(np.float64)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
    q = o3d.core.Tensor(pts32)
    scene.compute_distance(q[:10])  # builds the BVH outside the timing
    t_od, od = best(lambda: scene.compute_distance(q).numpy(), repeat)
    t_oc, oc = best(lambda: scene.compute_closest_points(q), repeat)
    t_os, osd = best(lambda: scene.compute_signed_distance(q).numpy(), repeat)
    t_vc, vc = best(lambda: voxfx.closest_points(mesh, pts), repeat)
    t_vs, vs = best(lambda: voxfx.signed_distance(mesh, pts), repeat)
    longest = float((v.max(axis=0) - v.min(axis=0)).max())
    return {
        "t_o3d_distance": t_od, "t_o3d_closest": t_oc, "t_o3d_signed": t_os,
        "t_voxfx_closest": t_vc, "t_voxfx_signed": t_vs,
        "o3d_max_err": float(np.max(np.abs(od - vc.distance))) / longest,
        "o3d_point_err": float(np.max(np.linalg.norm(oc["points"].numpy() - vc.point, axis=1))) / longest,
        "o3d_sign_wrong": int(np.count_nonzero(np.signbit(osd) != np.signbit(vs))),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="*")
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    if not open3d_rays_hit() and not os.environ.get("VOXFX_BENCH_EMBREE_FIX"):
        run_with_embree_fix()
    data = os.environ.get("VOXFX_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "data"))
    dense = os.environ.get("VOXFX_DENSE_DIR", os.path.join(data, "dense"))
    paths = a.meshes or [os.path.join(data, "meshes", "bunny00.off"), os.path.join(data, "meshes", "armadillo.off"),
                         os.path.join(dense, "bunny1m.off")]
    print(f"voxfx {voxfx.__version__}, Open3D {o3d.__version__}, {os.cpu_count()} CPUs; {a.points:,} points, "
          f"best of {a.repeat}; ms (million points per second)")
    print("| mesh | triangles | points | voxfx closest_points | Open3D compute_distance | Open3D compute_closest_points"
          " | voxfx signed_distance | Open3D compute_signed_distance | Open3D distance error | Open3D signs wrong |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for p in paths:
        if not os.path.exists(p):
            print(f"skipping {p}: missing (scripts/fetch-data.sh, bench/dense-meshes.sh)", file=sys.stderr)
            continue
        mesh = voxfx.load_mesh(p)
        v, f = mesh
        for kind in ("uniform", "near"):
            r = compare(mesh, v, f, kind, a.points, a.repeat)

            def cell(t):
                return f"{t * 1e3:.0f} ({a.points / t / 1e6:.2f})"

            print(f"| {os.path.basename(p)} | {len(f):,} | {kind} | {cell(r['t_voxfx_closest'])} | "
                  f"{cell(r['t_o3d_distance'])} | {cell(r['t_o3d_closest'])} | {cell(r['t_voxfx_signed'])} | "
                  f"{cell(r['t_o3d_signed'])} | {r['o3d_max_err']:.1e} | {r['o3d_sign_wrong']:,} |", flush=True)


if __name__ == "__main__":
    main()
