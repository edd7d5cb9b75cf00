#!/usr/bin/env python3
"""Frames per second of the preview loop of voxfx view from Python (voxfx.Renderer), per shadow kind.

    PYTHONPATH=build/python python3 bench/bench_preview.py SCENE KIND[,KIND...]

For each kind: a Renderer at 640 x 360, the first preview untimed (it loads modules), then 24
preview frames of a turn about the scene timed together (frames per second, ms per frame, and
the mean of the frames' "shadows" pass, the light's build that does not depend on the camera),
and one full frame. Wall-clock on whatever else the machine runs: compare kinds within one run.
"""
import math
import sys
import time

import voxfx


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    scene = voxfx.load_scene(sys.argv[1])
    for shadows in sys.argv[2].split(","):
        r = voxfx.Renderer(scene, shadows=shadows, width=640, height=360)
        cam = r.camera()
        r.render(cam, preview=True)
        n, t0, shadow_ms = 24, time.perf_counter(), 0.0
        for k in range(n):
            frame, report = r.render(cam.orbit(k * math.pi / 12), preview=True, report=True)
            shadow_ms += report["passes_ms"].get("shadows", 0) / n
        preview = (time.perf_counter() - t0) / n
        t0 = time.perf_counter()
        r.render(cam)
        full = time.perf_counter() - t0
        print(f"{shadows:13} preview {frame.shape[1]}x{frame.shape[0]}: {1 / preview:4.1f} frames/s "
              f"({preview * 1000:.0f} ms, shadow build {shadow_ms:.0f} ms); full 640x360: {full:.2f} s")


if __name__ == "__main__":
    main()
