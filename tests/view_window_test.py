#!/usr/bin/env python3
"""voxfx view under Xvfb, driven like a user: xdotool moves the mouse and presses keys, xwd takes a
screenshot of the window, and `voxfx render` of the scene file the viewer saved must give the
pixels the window shows.

    tests/view_window_test.py --voxfx build/voxfx [--size 320x180] [--screenshot OUT.png] [--keep DIR]

Steps: start Xvfb; `voxfx view --demo tree` at 320 x 180 (--size); wait for the full frame ("ready" in the
window title); save the untouched view (P); orbit (left drag), zoom (wheel), pan (right drag),
switch the shadow kind (S); wait for the full frame; save again; screenshot with the info overlay
(it must change only a panel at the top left, and draw text there); turn the overlay off (I) and
screenshot again. Checks:
  - the second saved camera differs from the first as the moves say: the wheel's dolly scales the
    distance to the target by 0.85 per notch (orbit and pan keep it), the pan moved the target,
    the orbit turned the view direction; the saved shadow kind is the one after the first in the
    list `voxfx view --help` prints;
  - `voxfx render view-002.json` writes exactly the saved view-002.png, and exactly the window's
    pixels without the overlay. Tolerance 0 (every byte equal): the viewer shows the renderer's
    frame 1:1 through the same 8-bit sRGB conversion as writePng (toSrgb8), the saved scene file
    holds every option and the camera bit for bit, and a render does not depend on the thread
    count, so any difference is a bug, not noise;
  - the same holds for the untouched view (view-001), and its camera is the scene's own.
Exit 77 (ctest: skipped) with the reason when Xvfb, xdotool or xwd is missing; the test command
installs them (scripts/install-deps.sh), so there it runs.
"""
import argparse
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

SKIP = 77
W, H = 320, 180


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


# ---- images -------------------------------------------------------------------------------------

def read_png(path):
    """An 8-bit RGB or RGBA PNG (what writePng writes) as (width, height, bytes RGB row-major)."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(path + ": not a PNG")
    at, idat, ihdr = 8, b"", None
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    w, h, depth, colour, _, _, interlace = ihdr
    if depth != 8 or colour not in (2, 6) or interlace:
        fail(f"{path}: PNG depth {depth} colour type {colour} interlace {interlace} not handled")
    bpp = 3 if colour == 2 else 4
    raw, stride = zlib.decompress(idat), w * bpp
    out, prev = bytearray(), bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        prev = line
        for x in range(w):
            out += line[x * bpp:x * bpp + 3]
    return w, h, bytes(out)


def write_png(path, w, h, rgb):
    rows = b"".join(b"\0" + rgb[y * w * 3:(y + 1) * w * 3] for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


def read_xwd(data):
    """An xwd dump of a TrueColor window (ZPixmap, 32 bits per pixel) as (width, height, RGB)."""
    header = struct.unpack(">25I", data[:100])
    (header_size, _version, pixmap_format, _depth, w, h, _xoff, byte_order, _unit, _bit_order, _pad, bpp,
     bytes_per_line, _visual, red_mask, green_mask, blue_mask, _bits_rgb, _cmap, ncolors) = header[:20]
    if pixmap_format != 2 or bpp != 32:
        fail(f"xwd: pixmap format {pixmap_format}, {bpp} bits per pixel: not handled")
    at = header_size + 12 * ncolors
    order = "<" if byte_order == 0 else ">"

    def shift(mask):
        return (mask & -mask).bit_length() - 1
    rs, gs, bs = shift(red_mask), shift(green_mask), shift(blue_mask)
    out = bytearray()
    for y in range(h):
        row = struct.unpack(order + f"{w}I", data[at + y * bytes_per_line:at + y * bytes_per_line + 4 * w])
        for p in row:
            out += bytes(((p & red_mask) >> rs, (p & green_mask) >> gs, (p & blue_mask) >> bs))
    return w, h, bytes(out)


def differing(a, b, w):
    """The pixels where two RGB images differ: (count, bounding box (x0, y0, x1, y1) or None, max diff)."""
    count, box, worst = 0, None, 0
    for i in range(0, len(a), 3):
        d = max(abs(a[i + k] - b[i + k]) for k in range(3))
        if d:
            count += 1
            worst = max(worst, d)
            x, y = (i // 3) % w, (i // 3) // w
            box = (x, y, x, y) if box is None else (min(box[0], x), min(box[1], y), max(box[2], x), max(box[3], y))
    return count, box, worst


# ---- the X session ------------------------------------------------------------------------------

class Session:
    def __init__(self, voxfx, workdir):
        self.voxfx, self.workdir = voxfx, workdir
        read, write = os.pipe()
        self.xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "800x600x24", "-nolisten",
                                      "tcp", "-nocursor"], pass_fds=[write], stderr=subprocess.DEVNULL)
        os.close(write)
        number = b""
        with os.fdopen(read, "rb") as f:
            while not number.endswith(b"\n"):
                c = f.read(1)
                if not c:
                    fail("Xvfb did not start")
                number += c
        self.env = dict(os.environ, DISPLAY=":" + number.decode().strip())
        self.env.pop("WAYLAND_DISPLAY", None)
        self.viewer = None

    def run(self, *args, check=True):
        r = subprocess.run(list(args), env=self.env, cwd=self.workdir, capture_output=True, text=True)
        if check and r.returncode != 0:
            state = ""
            if self.viewer is not None:
                code = self.viewer.poll()
                state = (f"\nvoxfx view {'runs' if code is None else f'exited with {code}'}; its output:\n"
                         + self.output())
            fail(f"{' '.join(args)}: exit {r.returncode}\n{r.stdout}{r.stderr}{state}")
        return r

    def start_viewer(self, *args):
        self.out = open(os.path.join(self.workdir, "viewer.out"), "w+")
        self.viewer = subprocess.Popen([self.voxfx, "view", *args], env=self.env, cwd=self.workdir,
                                       stdout=self.out, stderr=subprocess.STDOUT)
        # 0.7 s alone; a sanitizer build beside the rest of the suite on 2 cores needs far more.
        deadline = time.time() + 120
        while time.time() < deadline:
            window = self.find_window()
            if window:
                self.window = window
                return
            if self.viewer.poll() is not None:
                fail("voxfx view exited: " + self.output())
            time.sleep(0.1)
        fail("no voxfx view window after 120 s: " + self.output())

    def output(self):
        self.out.flush()
        self.out.seek(0)
        return self.out.read()

    def find_window(self):
        r = self.run("xdotool", "search", "--name", "^voxfx view", check=False)
        return r.stdout.split()[0] if r.returncode == 0 and r.stdout.split() else None

    def title(self):
        r = self.run("xdotool", "getwindowname", self.window, check=False)
        if r.returncode != 0:
            # The window found first can be gone a moment later (the viewer's first X window
            # replaced while it starts: BadWindow, seen once in a loaded run): find it again.
            time.sleep(0.2)
            self.window = self.find_window() or self.window
            r = self.run("xdotool", "getwindowname", self.window)
        return r.stdout.strip()

    def wait_ready(self, what, seconds=60):
        deadline = time.time() + seconds
        while time.time() < deadline:
            t = self.title()
            if t.endswith("| ready"):
                return t
            if t.endswith("| error") or self.viewer.poll() is not None:
                fail(f"{what}: the viewer shows an error: {t}\n{self.output()}")
            time.sleep(0.05)
        fail(f"{what}: no full frame after {seconds} s (title '{self.title()}')\n{self.output()}")

    def xdotool(self, *args):
        self.run("xdotool", *args)

    def key(self, name, check=True):
        self.run("xdotool", "mousemove", "--window", self.window, str(W // 2), str(H // 2), "key", name, check=check)

    def drag(self, button, x0, y0, x1, y1, steps=8):
        self.xdotool("mousemove", "--window", self.window, str(x0), str(y0), "mousedown", str(button))
        for k in range(1, steps + 1):
            self.xdotool("mousemove", "--window", self.window, str(x0 + (x1 - x0) * k // steps),
                         str(y0 + (y1 - y0) * k // steps))
            time.sleep(0.02)
        self.xdotool("mouseup", str(button))

    def save(self, stem):
        before = self.output().count("saved ")
        self.key("p")
        deadline = time.time() + 60
        while time.time() < deadline:
            if self.output().count("saved ") > before:
                break
            if self.viewer.poll() is not None:
                fail("voxfx view exited while saving: " + self.output())
            time.sleep(0.05)
        else:
            fail("P saved nothing in 60 s: " + self.output())
        for ext in (".png", ".json"):
            if not os.path.exists(os.path.join(self.workdir, stem + ext)):
                fail(f"P did not write {stem}{ext}: {self.output()}")

    def screenshot(self):
        r = subprocess.run(["xwd", "-silent", "-id", self.window], env=self.env, capture_output=True)
        if r.returncode != 0:
            fail("xwd: " + r.stderr.decode())
        return read_xwd(r.stdout)

    def close(self):
        if self.viewer and self.viewer.poll() is None:
            self.viewer.kill()
            self.viewer.wait()
        self.xvfb.terminate()
        self.xvfb.wait()


def camera_of(workdir, stem):
    doc = json.load(open(os.path.join(workdir, stem + ".json")))
    return doc, doc["cameras"][0]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def norm(v):
    return math.sqrt(sum(x * x for x in v))


def check_render_matches(session, stem, shot, what):
    """voxfx render STEM.json gives STEM.png and the screenshot, byte for byte."""
    session.run(session.voxfx, "render", stem + ".json", "-o", stem + "-render.png", "-q")
    rw, rh, rendered = read_png(os.path.join(session.workdir, stem + "-render.png"))
    sw, sh, saved = read_png(os.path.join(session.workdir, stem + ".png"))
    if (rw, rh) != (W, H) or (sw, sh) != (W, H):
        fail(f"{what}: sizes: render {rw}x{rh}, saved {sw}x{sh}, expected {W}x{H}")
    n, box, worst = differing(saved, rendered, W)
    print(f"{what}: saved {stem}.png vs voxfx render {stem}.json: {n} pixels differ (max {worst}/255)")
    if n:
        fail(f"{what}: the saved frame and the render of the saved scene differ in {n} pixels, box {box}")
    if shot is not None:
        n, box, worst = differing(shot, rendered, W)
        print(f"{what}: window screenshot vs voxfx render {stem}.json: {n} of {W * H} pixels differ "
              f"(max {worst}/255)")
        if n:
            fail(f"{what}: the window and the render differ in {n} pixels (max {worst}/255), box {box}")
    return rendered


def main():
    global W, H
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--voxfx", required=True)
    parser.add_argument("--screenshot", help="also write the window with its overlay here (PNG)")
    parser.add_argument("--keep", help="work in this folder and keep it")
    parser.add_argument("--size", default=f"{W}x{H}", help="the window, WIDTHxHEIGHT (default %(default)s)")
    a = parser.parse_args()
    W, H = (int(v) for v in a.size.split("x"))
    missing = [t for t in ("Xvfb", "xdotool", "xwd") if not shutil.which(t)]
    if missing:
        print("SKIP: " + ", ".join(missing) + " not installed (Debian: xvfb xdotool x11-apps; "
              "scripts/install-deps.sh installs them)")
        return SKIP
    voxfx = os.path.abspath(a.voxfx)
    workdir = a.keep or tempfile.mkdtemp(prefix="voxfx-view-")
    os.makedirs(workdir, exist_ok=True)
    session = Session(voxfx, workdir)
    start = time.time()
    try:
        kinds = []
        help_text = session.run(voxfx, "view", "--help").stdout
        block = help_text.split("Shadow kinds (--shadows):\n", 1)[1].split("\n\n", 1)[0]
        kinds = [line.split()[0] for line in block.splitlines() if line.strip()]
        session.start_viewer("--demo", "tree", "--width", str(W), "--height", str(H), "-j", "2")
        first = session.wait_ready("first frame")
        print("first frame: " + first)
        if "shadows map" not in first:
            fail("the tree demo should start with shadow maps: " + first)
        session.save("view-001")
        shot0 = session.screenshot()

        session.drag(1, W // 2, H // 2, W // 2 + W * 3 // 16, H // 2 + H // 9)  # orbit
        session.xdotool("click", "--repeat", "2", "4")                         # wheel: two notches in
        session.drag(3, W // 2, H // 2, W // 2 - W * 3 // 32, H // 2 - H // 18)  # pan
        session.key("s")                                    # the next shadow kind
        moved = session.wait_ready("after the moves")
        print("after the moves: " + moved)
        session.save("view-002")
        shot_overlay = session.screenshot()
        session.key("i")                                    # overlay off
        time.sleep(0.3)
        shot = session.screenshot()
        # The window closes at the key's press: xdotool's release may then find it gone (BadWindow).
        session.key("q", check=False)
        try:
            code = session.viewer.wait(timeout=20)
        except subprocess.TimeoutExpired:
            fail("Q did not close the viewer in 20 s")
        if code != 0:
            fail(f"voxfx view exited with {code}: {session.output()}")
        print(session.output().strip())

        for name, (w, h, _) in (("first", shot0), ("overlay", shot_overlay), ("plain", shot)):
            if (w, h) != (W, H):
                fail(f"{name} screenshot is {w}x{h}, the window should be {W}x{H}")

        # The cameras: the first is the scene's own, the second moved as the input says.
        doc1, cam1 = camera_of(workdir, "view-001")
        doc2, cam2 = camera_of(workdir, "view-002")
        d1 = norm(sub(cam1["target"], cam1["position"]))
        d2 = norm(sub(cam2["target"], cam2["position"]))
        notches = math.log(d2 / d1) / math.log(0.85)
        print(f"camera: position {cam1['position']} -> {cam2['position']}, target {cam1['target']} -> "
              f"{cam2['target']}, distance {d1:.6g} -> {d2:.6g} ({notches:.6f} wheel notches of 0.85)")
        if cam1 == cam2:
            fail("the saved camera did not move")
        if not (abs(notches - round(notches)) < 1e-6 and round(notches) >= 1):
            fail(f"the distance changed by {d2 / d1}, not a whole number of 0.85 wheel notches")
        if norm(sub(cam1["target"], cam2["target"])) < 1e-6 * d1:
            fail("the right-button drag did not pan (the target did not move)")
        f1 = [x / d1 for x in sub(cam1["target"], cam1["position"])]
        f2 = [x / d2 for x in sub(cam2["target"], cam2["position"])]
        if norm(sub(f1, f2)) < 1e-3:
            fail("the left-button drag did not orbit (the view direction did not change)")
        expected = kinds[(kinds.index("map") + 1) % len(kinds)]
        if doc1["render"]["shadows"] != "map" or doc2["render"]["shadows"] != expected:
            fail(f"saved shadows {doc1['render']['shadows']}, {doc2['render']['shadows']}; expected map, {expected}")

        check_render_matches(session, "view-001", None, "untouched view")
        rendered = check_render_matches(session, "view-002", shot[2], "moved view")

        # With the overlay: a panel at the top left holds text (bright and dark pixels), and
        # nothing else differs from the render.
        n, box, worst = differing(shot_overlay[2], rendered, W)
        print(f"overlay: {n} pixels differ from the render, within {box}")
        if not n or box[0] != 0 or box[1] != 0 or box[2] >= W or box[3] >= H // 2:
            fail(f"the overlay should be a panel at the top left: {n} pixels differ, box {box}")
        panel = [shot_overlay[2][3 * (y * W + x)] for y in range(box[3] + 1) for x in range(box[2] + 1)]
        if not any(p == 255 for p in panel) or sum(p < 80 for p in panel) < len(panel) // 2:
            fail("the overlay panel shows no white text on a dark background")
        if a.screenshot:
            write_png(a.screenshot, W, H, shot_overlay[2])
    finally:
        session.close()
        if not a.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    print(f"passed in {time.time() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
