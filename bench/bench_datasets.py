#!/usr/bin/env python3
"""Dataset preparation (#35): voxfx against Open3D where Open3D has the same operation, in one run.

  surface samples:  voxfx.sample_surface vs TriangleMesh.sample_points_uniformly (both area-weighted
                    with the face normals; Open3D's legacy mesh built outside the timing)
  near-surface SDF: voxfx.sample_near_surface (surface samples, Gaussian offsets, exact signed
                    distances) vs the same pipeline in Open3D: sample_points_uniformly, the offsets
                    in NumPy, RaycastingScene.compute_signed_distance (scene built inside the
                    timing, as voxfx builds its hierarchy); the signs compared with voxfx's exact
                    ones
  marching cubes:   voxfx.marching_cubes (OpenVDB's volumeToMesh) on a dense float array. Open3D
                    0.16 has no marching cubes of an array (only of its own TSDF volumes, filled
                    from depth images), so the reference row is scikit-image's
                    measure.marching_cubes (Debian python3-skimage) when installed.
  batch:            voxfx.voxelize_many of every CGAL mesh at 64^3 vs a Python loop of
                    voxfx.voxelize over the same meshes (no Open3D equivalent: its voxel grid is a
                    surface of one mesh).

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_datasets.py [--samples N] [--repeat R]
       [--embree-fix auto|off] [meshes...]   (default: bunny00, armadillo)
Timings are the best of R runs, wall clock, all threads of both libraries. Open3D's ray casting on
Debian needs the ray-mask shim of bench_python.py (applied the same way, see there).
"""
import argparse
import glob
import os
import sys
import time

import numpy as np

import voxfx

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_python import best, o3d, open3d_rays_hit, run_with_embree_fix  # noqa: E402

try:
    from skimage import measure as skimage_measure
except ImportError:  # pragma: no cover
    skimage_measure = None


def row(name, ours, theirs, extra=""):
    ratio = f"{theirs / ours:6.2f}x" if theirs else "     -"
    theirs_text = f"{theirs * 1e3:9.1f} ms" if theirs else "        -   "
    print(f"  {name:<34} voxfx {ours * 1e3:9.1f} ms   other {theirs_text}   other/voxfx {ratio}  {extra}")


def surface_samples(mesh, v, f, n, repeat):
    tm = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
    tm.compute_triangle_normals()
    ours, s = best(lambda: voxfx.sample_surface(mesh, n, seed=1), repeat)
    theirs, pc = best(lambda: tm.sample_points_uniformly(n, use_triangle_normal=True), repeat)
    assert len(pc.points) == n and len(s.points) == n
    row(f"surface samples ({n:,})", ours, theirs)


def near_surface(mesh, v, f, n, repeat):
    sigma = 0.01 * float(np.ptp(v, axis=0).max())
    tm = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
    rng = np.random.default_rng(1)

    def open3d_pipeline():
        pts = np.asarray(tm.sample_points_uniformly(n).points)
        pts = (pts + rng.normal(0, sigma, pts.shape)).astype(np.float32)
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
        return pts, scene.compute_signed_distance(o3d.core.Tensor(pts)).numpy()

    ours, s = best(lambda: voxfx.sample_near_surface(mesh, n, sigma, seed=1), repeat)
    theirs, (pts, sd) = best(open3d_pipeline, repeat)
    exact = voxfx.signed_distance(mesh, pts.astype(np.float64))
    wrong = int((np.signbit(sd) != np.signbit(exact)).sum())
    row(f"near-surface samples + SDF ({n:,})", ours, theirs, f"Open3D signs differing from exact: {wrong}")


def sphere_field(n):
    x = np.linspace(-1, 1, n, dtype=np.float32)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    return np.sqrt(X * X + Y * Y + Z * Z) - 0.7, float(x[1] - x[0])


def marching(name, field, spacing, repeat):
    ours, m = best(lambda: voxfx.marching_cubes(field, spacing=spacing), repeat)
    theirs = None
    extra = f"{len(m.faces):,} triangles"
    if skimage_measure is not None:
        theirs, out = best(lambda: skimage_measure.marching_cubes(field, 0.0, spacing=(spacing,) * 3), repeat)
        extra += f", scikit-image {len(out[1]):,} triangles"
    row(f"marching cubes {name}", ours, theirs, extra + " (other: scikit-image; Open3D has none)")


def batch(paths, repeat):
    def loop():
        return np.stack([voxfx.voxelize(voxfx.load_mesh(p), resolution=64, cube=True, padding=2).to_numpy()
                         for p in paths])

    ours, a = best(lambda: voxfx.voxelize_many(paths, 64, padding=2), repeat)
    theirs, b = best(loop, repeat)
    assert np.array_equal(a, b)
    row(f"voxelize_many {len(paths)} meshes, 64^3", ours, theirs, "(other: a Python loop of voxfx.voxelize)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="*")
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--embree-fix", choices=["auto", "off"], default="auto")
    args = ap.parse_args()
    if args.embree_fix == "auto" and not os.environ.get("VOXFX_BENCH_EMBREE_FIX") and not open3d_rays_hit():
        run_with_embree_fix()
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "meshes")
    meshes = args.meshes or [os.path.join(data, m) for m in ("bunny00.off", "armadillo.off")]
    print(f"voxfx {voxfx.__version__}, Open3D {o3d.__version__}, {os.cpu_count()} cores; best of {args.repeat}")
    for path in meshes:
        mesh = voxfx.load_mesh(path)
        v, f = mesh.vertices, mesh.faces
        print(f"{os.path.basename(path)}: {len(f):,} triangles")
        surface_samples(mesh, v, f, args.samples, args.repeat)
        near_surface(mesh, v, f, args.samples // 4, args.repeat)
    print("fields:")
    for n in (128, 256):
        field, h = sphere_field(n)
        marching(f"sphere {n}^3", field, h, args.repeat)
    bunny = voxfx.load_mesh(meshes[0])
    full = np.asarray(voxfx.sdf(bunny, resolution=192, band="full"))
    marching(f"{os.path.basename(meshes[0])} SDF {'x'.join(map(str, full.shape))}", full, 1.0, args.repeat)
    paths = []
    for p in sorted(glob.glob(os.path.join(data, "*.off"))):
        try:
            voxfx.voxelize(voxfx.load_mesh(p), resolution=8, cube=True)
            paths.append(p)
        except voxfx.Error:
            pass  # CGAL's deliberately broken files
    print("batches:")
    batch(paths, args.repeat)


if __name__ == "__main__":
    main()
