#!/usr/bin/env python3
"""Mean of an image over pixel boxes: sRGB 0-255 per channel for a PNG, linear luminance
(Rec. 709 weights) and RGB for a PFM; boxes as X0,Y0,X1,Y1 (exclusive ends, y down from the top).

    python3 scripts/region-mean.py IMAGE.png|IMAGE.pfm 520,300,600,340 365,195,435,215 ...
"""
import importlib.util
import os
import sys

import numpy as np


def read_pfm(path):
    with open(path, "rb") as f:
        f.readline()
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        a = np.frombuffer(f.read(), "<f4" if scale < 0 else ">f4").reshape(h, w, 3)
    return a[::-1]  # rows bottom to top in the file


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    path = sys.argv[1]
    if path.endswith(".pfm"):
        img = read_pfm(path).astype(np.float64)
    else:
        spec = importlib.util.spec_from_file_location("strip", os.path.join(os.path.dirname(__file__), "make-strip.py"))
        strip = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(strip)
        img = strip.read_png(path).astype(np.float64)
    for box in sys.argv[2:]:
        x0, y0, x1, y1 = (int(v) for v in box.split(","))
        m = img[y0:y1, x0:x1].reshape(-1, 3).mean(axis=0)
        lum = float(m @ [0.2126, 0.7152, 0.0722])
        print(f"{path} [{box}]: mean {m[0]:.3f} {m[1]:.3f} {m[2]:.3f}, luminance {lum:.3f}")


if __name__ == "__main__":
    main()
