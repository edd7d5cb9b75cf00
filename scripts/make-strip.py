#!/usr/bin/env python3
"""Composes a before/after strip: two PNGs of the same size side by side, 4 white pixels between,
each labelled in its top-left corner (white capitals on a dark box), as docs/images/strip-*.png.

    python3 scripts/make-strip.py BEFORE.png AFTER.png OUT.png --left "BEFORE: 0B6E894" --right "AFTER: DF8EAF6"

Numpy and zlib only (8-bit RGB/RGBA PNGs, non-interlaced); labels use a built-in 5x7 font
(capitals, digits and a few signs), drawn at 2x.
"""
import argparse
import struct
import zlib

import numpy as np

GAP = 4

# 5x7 glyphs, one string of 7 rows of 5 bits each.
FONT = {
    "A": "01110 10001 10001 11111 10001 10001 10001", "B": "11110 10001 10001 11110 10001 10001 11110",
    "C": "01110 10001 10000 10000 10000 10001 01110", "D": "11110 10001 10001 10001 10001 10001 11110",
    "E": "11111 10000 10000 11110 10000 10000 11111", "F": "11111 10000 10000 11110 10000 10000 10000",
    "G": "01110 10001 10000 10111 10001 10001 01111", "H": "10001 10001 10001 11111 10001 10001 10001",
    "I": "01110 00100 00100 00100 00100 00100 01110", "J": "00111 00010 00010 00010 00010 10010 01100",
    "K": "10001 10010 10100 11000 10100 10010 10001", "L": "10000 10000 10000 10000 10000 10000 11111",
    "M": "10001 11011 10101 10101 10001 10001 10001", "N": "10001 10001 11001 10101 10011 10001 10001",
    "O": "01110 10001 10001 10001 10001 10001 01110", "P": "11110 10001 10001 11110 10000 10000 10000",
    "Q": "01110 10001 10001 10001 10101 10010 01101", "R": "11110 10001 10001 11110 10100 10010 10001",
    "S": "01111 10000 10000 01110 00001 00001 11110", "T": "11111 00100 00100 00100 00100 00100 00100",
    "U": "10001 10001 10001 10001 10001 10001 01110", "V": "10001 10001 10001 10001 10001 01010 00100",
    "W": "10001 10001 10001 10101 10101 10101 01010", "X": "10001 10001 01010 00100 01010 10001 10001",
    "Y": "10001 10001 01010 00100 00100 00100 00100", "Z": "11111 00001 00010 00100 01000 10000 11111",
    "0": "01110 10001 10011 10101 11001 10001 01110", "1": "00100 01100 00100 00100 00100 00100 01110",
    "2": "01110 10001 00001 00010 00100 01000 11111", "3": "11111 00010 00100 00010 00001 10001 01110",
    "4": "00010 00110 01010 10010 11111 00010 00010", "5": "11111 10000 11110 00001 00001 10001 01110",
    "6": "00110 01000 10000 11110 10001 10001 01110", "7": "11111 00001 00010 00100 01000 01000 01000",
    "8": "01110 10001 10001 01110 10001 10001 01110", "9": "01110 10001 10001 01111 00001 00010 01100",
    " ": "00000 00000 00000 00000 00000 00000 00000", ":": "00000 01100 01100 00000 01100 01100 00000",
    ".": "00000 00000 00000 00000 00000 01100 01100", ",": "00000 00000 00000 00000 01100 00100 01000",
    "-": "00000 00000 00000 11111 00000 00000 00000", "+": "00000 00100 00100 11111 00100 00100 00000",
    "(": "00010 00100 01000 01000 01000 00100 00010", ")": "01000 00100 00010 00010 00010 00100 01000",
    "/": "00001 00010 00010 00100 01000 01000 10000", "#": "01010 01010 11111 01010 11111 01010 01010",
    "=": "00000 00000 11111 00000 11111 00000 00000",
}


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and ctype in (2, 6) and interlace == 0, (path, depth, ctype, interlace)
            ch = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, 1 + w * ch)
    out = np.zeros((h, w * ch), np.int32)
    prev = np.zeros(w * ch, np.int32)
    for y in range(h):
        f, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        cur = np.zeros(w * ch, np.int32)
        if f == 0:
            cur = line
        elif f == 2:
            cur = (line + prev) & 255
        else:
            for x in range(w * ch):
                a = cur[x - ch] if x >= ch else 0
                b = prev[x]
                c = prev[x - ch] if x >= ch else 0
                if f == 1:
                    p = a
                elif f == 3:
                    p = (a + b) // 2
                else:
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                cur[x] = (line[x] + p) & 255
        out[y] = cur
        prev = cur
    return out.reshape(h, w, ch)[..., :3].astype(np.uint8)


def write_png(path, img):
    h, w, _ = img.shape
    # Filter per row: up (2) or none (0), whichever sums smaller (small files, simple).
    rows = []
    prev = np.zeros((w * 3,), np.int16)
    for y in range(h):
        cur = img[y].reshape(-1).astype(np.int16)
        up = ((cur - prev) & 255).astype(np.uint8)
        none = cur.astype(np.uint8)
        score = lambda r: np.minimum(r, 256 - r.astype(np.int16)).sum()
        rows.append(b"\x02" + up.tobytes() if score(up) < score(none) else b"\x00" + none.tobytes())
        prev = cur

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(b"".join(rows), 9)) + chunk(b"IEND", b""))


def label(img, text, x0=6, y0=6, scale=2):
    text = text.upper()
    cw = 6 * scale
    bw, bh = len(text) * cw + 2 * scale, 7 * scale + 4 * scale // 2 + 2
    region = img[y0:y0 + bh, x0:x0 + bw].astype(np.float32)
    img[y0:y0 + bh, x0:x0 + bw] = (region * 0.25 + 20).astype(np.uint8)
    for k, ch in enumerate(text):
        rows = FONT.get(ch, FONT[" "]).split()
        for r, bits in enumerate(rows):
            for c, bit in enumerate(bits):
                if bit == "1":
                    y = y0 + 2 + r * scale
                    x = x0 + scale + k * cw + c * scale
                    img[y:y + scale, x:x + scale] = 255


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("out")
    ap.add_argument("--left", default="BEFORE")
    ap.add_argument("--right", default="AFTER")
    a = ap.parse_args()
    b, c = read_png(a.before), read_png(a.after)
    assert b.shape == c.shape, (b.shape, c.shape)
    h, w, _ = b.shape
    label(b, a.left)
    label(c, a.right)
    strip = np.full((h, 2 * w + GAP, 3), 255, np.uint8)
    strip[:, :w] = b
    strip[:, w + GAP:] = c
    write_png(a.out, strip)


if __name__ == "__main__":
    main()
