"""Python-side figures for BENCHMARKS.md: Grid.indices() and Grid.centers() against np.argwhere on
the same grids (the dense route: to_numpy, then argwhere, then the centre arithmetic), and the
time of `import voxfx` beside `import numpy` in fresh interpreters. Best of `--repeat` runs.

    PYTHONPATH=build/python python3 bench/bench_python_arrays.py [--mesh data/meshes/bunny00.off]
                                                          [--resolutions 256 512 1024] [--repeat 3]
"""
import argparse
import os
import subprocess
import sys
import time

import numpy as np

import voxfx


def best(f, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - start)
        del out
    return min(times)


def import_time(statement, repeat):
    code = f"import time; t = time.perf_counter(); {statement}; print(time.perf_counter() - t)"
    env = dict(os.environ)
    return min(float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                    env=env).stdout) for _ in range(repeat))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--mesh", default="data/meshes/bunny00.off")
    p.add_argument("--resolutions", type=int, nargs="+", default=[256, 512, 1024])
    p.add_argument("--repeat", type=int, default=3)
    a = p.parse_args()
    mesh = voxfx.load_mesh(a.mesh)
    print(f"{os.path.basename(a.mesh)}, {mesh.triangle_count} triangles, solid, cube=True; best of {a.repeat}")
    print("| grid | filled cells | voxelize | indices() | centers() | to_numpy + np.argwhere | "
          "+ centres | argwhere / indices |")
    print("|---|---|---|---|---|---|---|---|")
    for r in a.resolutions:
        t_vox = best(lambda: voxfx.voxelize(mesh, resolution=r, cube=True), a.repeat)
        g = voxfx.voxelize(mesh, resolution=r, cube=True)
        t_idx = best(g.indices, a.repeat)
        t_ctr = best(g.centers, a.repeat)
        origin, cell = np.array(g.origin), np.array(g.cell_size)
        t_arg = best(lambda: np.argwhere(g.to_numpy()), a.repeat)
        t_arg_c = best(lambda: origin + (np.argwhere(g.to_numpy()) + 0.5) * cell, a.repeat)
        assert np.array_equal(g.indices(), np.argwhere(g.to_numpy()))
        print(f"| {r}^3 | {g.count():,} | {t_vox * 1e3:.0f} ms | {t_idx * 1e3:.1f} ms | {t_ctr * 1e3:.1f} ms | "
              f"{t_arg * 1e3:.0f} ms | {t_arg_c * 1e3:.0f} ms | {t_arg / t_idx:.0f}x |")
    t_np = import_time("import numpy", a.repeat)
    t_vx = import_time("import voxfx", a.repeat)
    print(f"\nimport numpy: {t_np * 1e3:.0f} ms; import voxfx (NumPy included): {t_vx * 1e3:.0f} ms, "
          f"{(t_vx - t_np) * 1e3:.0f} ms more")


if __name__ == "__main__":
    main()
