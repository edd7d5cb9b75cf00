#!/usr/bin/env python3
"""How much two PFM images (linear floats, as scripts/image-regression.sh writes them) differ:
the share of pixels that differ at all, of those more than 1 % of the first image's mean luminance
apart, the mean absolute difference per channel over the whole image relative to that mean, and
the largest. Pure Python (struct), so it runs where NumPy is not installed:

    scripts/pfm-diff.py a.pfm b.pfm
"""
import struct
import sys


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind not in (b"PF", b"Pf"):
            sys.exit(f"{path}: not a PFM file")
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        channels = 3 if kind == b"PF" else 1
        n = w * h * channels
        values = struct.unpack(("<" if scale < 0 else ">") + "f" * n, f.read(4 * n))
    return w, h, channels, values


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    wa, ha, ca, a = read_pfm(sys.argv[1])
    wb, hb, cb, b = read_pfm(sys.argv[2])
    if (wa, ha, ca) != (wb, hb, cb):
        sys.exit("the images differ in size or channels")
    pixels = wa * ha
    lum = (lambda v, i: 0.2126 * v[3 * i] + 0.7152 * v[3 * i + 1] + 0.0722 * v[3 * i + 2]) if ca == 3 else (
        lambda v, i: v[i])
    mean = sum(lum(a, i) for i in range(pixels)) / pixels or 1.0
    diff = [abs(x - y) for x, y in zip(a, b)]
    per_pixel = [max(diff[ca * i:ca * (i + 1)]) for i in range(pixels)]
    differ = sum(d > 0 for d in per_pixel)
    visible = sum(d > 0.01 * mean for d in per_pixel)
    print(f"{100 * differ / pixels:.1f} % of pixels differ, {100 * visible / pixels:.1f} % by more than 1 % "
          f"of the mean luminance; mean |difference| {100 * sum(diff) / len(diff) / mean:.2f} % of it, "
          f"largest {max(diff) / mean:.2f} x it")


if __name__ == "__main__":
    main()
