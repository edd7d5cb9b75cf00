#!/usr/bin/env python3
"""Counts the pixels of PNG B more than N levels darker than PNG A (8-bit RGB, no alpha; the
luma of the stored sRGB values with Rec. 709 weights, and any one channel), and those brighter.
Pure Python (zlib), so it runs where NumPy and Pillow are not installed:

    scripts/darker-pixels.py map.png volumes.png [N=30]
"""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"{path}: not a PNG file")
    pos, idat, w, h = 8, b"", 0, 0
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, colour = struct.unpack(">IIBB", body[:10])
            if depth != 8 or colour != 2 or body[12] != 0:
                sys.exit(f"{path}: only 8-bit RGB, non-interlaced PNG files")
        elif kind == b"IDAT":
            idat += body
    raw, stride = zlib.decompress(idat), w * 3
    out, prev = bytearray(h * stride), bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b, c = prev[x], (prev[x - 3] if x >= 3 else 0)
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out[y * stride:(y + 1) * stride], prev = line, line
    return w, h, out


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    wa, ha, a = read_png(sys.argv[1])
    wb, hb, b = read_png(sys.argv[2])
    if (wa, ha) != (wb, hb):
        sys.exit("the images differ in size")
    n = float(sys.argv[3]) if len(sys.argv) == 4 else 30

    def luma(px, i):
        return 0.2126 * px[3 * i] + 0.7152 * px[3 * i + 1] + 0.0722 * px[3 * i + 2]

    pixels = range(wa * ha)
    differ = sum(a[3 * i:3 * i + 3] != b[3 * i:3 * i + 3] for i in pixels)
    darker = sum(luma(b, i) < luma(a, i) - n for i in pixels)
    channel = sum(max(a[3 * i + k] - b[3 * i + k] for k in range(3)) > n for i in pixels)
    brighter = sum(luma(b, i) > luma(a, i) + n for i in pixels)
    print(f"{differ} pixels differ; {darker} more than {n:g} levels darker (luma), {channel} (a channel); "
          f"{brighter} brighter")


if __name__ == "__main__":
    main()
