"""voxfx.render: scenes rendered with every shadow kind's and glass method's options as keywords.

Oracles: a closed form (a ground quad under a sun, no shadows: ambient + albedo/pi * E * cos), the
command line's PFM output of the same options (the keywords must reach the library as the flags
do: same pixels, bit for bit), and the options catalog (every technique's options are keywords).
"""
import os
import re
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import voxfx

GROUND = "OFF\n4 2 0\n-4 0 -4\n4 0 -4\n4 0 4\n-4 0 4\n3 0 2 1\n3 0 3 2\n"
CUBE = (
    "OFF\n8 12 0\n-0.5 0.5 -0.5\n0.5 0.5 -0.5\n0.5 1.5 -0.5\n-0.5 1.5 -0.5\n"
    "-0.5 0.5 0.5\n0.5 0.5 0.5\n0.5 1.5 0.5\n-0.5 1.5 0.5\n"
    "3 0 3 2\n3 0 2 1\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n3 3 7 6\n3 3 6 2\n3 0 4 7\n3 0 7 3\n3 1 2 6\n3 1 6 5\n"
)


def write_scene(tmp_path, cube=True, settings=""):
    (tmp_path / "ground.off").write_text(GROUND)
    (tmp_path / "cube.off").write_text(CUBE)
    meshes = ('{"file": "ground.off", "name": "ground", "castsShadow": false,'
              ' "material": {"baseColor": [0.5, 0.5, 0.5], "specular": 0}}')
    if cube:
        meshes += ', {"file": "cube.off", "name": "cube", "material": {"baseColor": [0.2, 0.6, 0.3], "opacity": 0.5}}'
    text = (
        '{"meshes": [' + meshes + '],'
        ' "lights": [{"type": "directional", "direction": [0.3, -1, 0.2], "intensity": 2}],'
        ' "cameras": [{"position": [0, 6, 6], "target": [0, 0, 0], "fovYDegrees": 40}]' + settings + "}"
    )
    path = tmp_path / "scene.json"
    path.write_text(text)
    return path


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4").reshape(h, w, 3)
    return data[::-1]  # PFM rows run bottom to top


def test_an_unshadowed_ground_has_the_closed_form_radiance(tmp_path):
    scene = voxfx.load_scene(write_scene(tmp_path, cube=False))
    assert scene.triangle_count == 2 and scene.light_count == 1
    img = voxfx.render(scene, shadows="none", width=64, height=48, ambient=(0.1, 0.1, 0.1), background=(0, 0, 1),
                       sky="flat", sky_light=0, anti_aliasing="off", tone_map="clamp", exposure=1)
    assert img.shape == (48, 64, 3) and img.dtype == np.float32
    # The sun on the ground (normal up): ambient * albedo + albedo / pi * E * cos(angle to the normal).
    cosine = 1 / np.sqrt(0.3**2 + 1 + 0.2**2)
    want = 0.1 * 0.5 + 0.5 / np.pi * 2.0 * cosine
    centre = img[24, 32]
    assert np.allclose(centre, want, atol=1e-5), centre
    assert np.array_equal(img[0, 0], np.array([0, 0, 1], dtype=np.float32))  # sky above the ground's edge


@pytest.mark.parametrize(
    "shadows, options, flags",
    [
        ("map", {"map_resolution": 512, "pcf": 2}, "--map-resolution 512 --pcf 2"),
        ("transmittance", {"grid_resolution": 64, "slicing": "local", "bilinear": True},
         "--grid 64 --slicing local --bilinear"),
        ("absorption", {"grid_resolution": 48, "opaque_absorption": 4.0}, "--grid 48 --opaque-absorption 4"),
        ("translucency", {"grid_resolution": 40, "extinction": 2.5, "fill": "parity"},
         "--grid 40 --extinction 2.5 --fill parity"),
        ("volumes", {"volume_culling": False}, "--no-volume-culling"),
        ("deep", {"dsm_resolution": 96, "dsm_storage": "fixed", "fixed_nodes": 8, "termination": 0.01,
                  "dsm_step": 0.5, "clusters": 2, "cluster_threshold": 0.1},
         "--dsm-resolution 96 --dsm-storage fixed --fixed-nodes 8 --termination 0.01 --dsm-step 0.5 --clusters 2 "
         "--cluster-threshold 0.1"),
    ],
)
def test_keywords_reach_the_library_as_the_command_line_flags_do(tmp_path, cli, shadows, options, flags):
    scene = write_scene(tmp_path)
    img, report = voxfx.render(scene, shadows=shadows, width=48, height=36, report=True, **options)
    # Every keyword is in the options the technique ran with ("fixed_nodes 8" for fixed_nodes=8).
    # Split at the commas between options, not inside a triple's "(1, 1, 1)".
    ran = dict(item.split(" ", 1) for item in re.split(r", (?![^(]*\))", report["shadow_options"]))
    for name, value in options.items():
        want = {True: "on", False: "off"}.get(value, value) if isinstance(value, bool) else value
        assert ran[name] == str(want) if not isinstance(want, float) else float(ran[name]) == want, (name, ran)
    out = tmp_path / "cli.pfm"
    subprocess.run([cli, "render", str(scene), "-o", str(out), "--width", "48", "--height", "36", "--shadows",
                    shadows, "-q", "--tone-map", "filmic"] + flags.split(), check=True)
    assert np.array_equal(img, read_pfm(out))  # the array is filmic unless tone_map says otherwise
    # And the options matter: the defaults give another image (the technique's options reached it).
    if shadows != "volumes":  # culling changes no pixel, by design
        assert not np.array_equal(img, voxfx.render(scene, shadows=shadows, width=48, height=36))


def test_scene_settings_apply_and_keywords_override_them(tmp_path):
    path = write_scene(tmp_path, settings=', "render": {"shadows": "transmittance", "gridResolution": 32, "width": 40, "height": 30}')
    scene = voxfx.load_scene(path)
    assert scene.settings["shadows"] == "transmittance"
    img, report = voxfx.render(scene, report=True)
    assert img.shape == (30, 40, 3)
    assert report["shadows"] == "transmittance" and "light grid" in report["shadow_stats"]
    assert set(report["passes_ms"]) == {"flatten", "G-buffer", "occlusion", "shadows", "shading",
                                         "translucency", "glass", "ray casting", "resolve"}
    wide = voxfx.render(scene, width=50)
    assert wide.shape == (30, 50, 3)


def test_every_technique_option_is_a_keyword_and_bad_ones_are_refused(tmp_path):
    names = {o["name"] for o in voxfx.render_options()}
    for n in ("fixed_nodes", "dsm_step", "termination", "cluster_threshold", "grid_resolution", "glass_grid",
              "frosted_blur", "receiver_slices", "empty_space_skipping", "crease_angle"):
        assert n in names, n
    kinds = [k for k, _ in voxfx.shadow_kinds()]
    assert kinds == ["none", "map", "transmittance", "absorption", "translucency", "volumes", "exact", "deep"]
    assert [m for m, _ in voxfx.glass_methods()] == ["none", "exact", "multi", "two-surface", "frosted"]
    scene = write_scene(tmp_path)
    with pytest.raises(voxfx.ArgumentError, match="unknown render option 'shininess'"):
        voxfx.render(scene, shininess=3)
    with pytest.raises(voxfx.ArgumentError, match=r"grid_resolution: expected a whole number in \[1, 16384\]"):
        voxfx.render(scene, shadows="transmittance", grid_resolution=0)
    with pytest.raises(voxfx.ArgumentError, match="is not an option of shadows map"):
        voxfx.render(scene, shadows="map", epsilon=0.1)
    with pytest.raises(voxfx.ArgumentError, match="unknown shadow kind 'soft'"):
        voxfx.render(scene, shadows="soft")


class Interrupted(Exception):
    """What SIGINT raises here (not KeyboardInterrupt, which would stop pytest if it came late)."""


def test_ctrl_c_stops_a_render_between_tiles(tmp_path):
    scene = voxfx.load_scene(write_scene(tmp_path))
    # One sample per supersample (aa="post"): with adaptive anti-aliasing (on where the blended cube
    # is drawn too) the frame below would allocate 8 x 8 samples per pixel before its first tile.

    def small_frame():  # 1/256 of the samples of the frame below
        start = time.perf_counter()
        voxfx.render(scene, shadows="exact", width=320, height=180, aa="post")
        return time.perf_counter() - start

    small = small_frame()
    old = signal.signal(signal.SIGINT, lambda signum, frame: (_ for _ in ()).throw(Interrupted()))
    timer = threading.Timer(0.2, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.perf_counter()
    try:
        with pytest.raises(Interrupted):
            voxfx.render(scene, shadows="exact", width=1280, height=720, supersample=4, aa="post")
    finally:
        timer.cancel()
        timer.join()
        signal.signal(signal.SIGINT, old)
    elapsed = time.perf_counter() - start
    # Uninterrupted, that frame takes about 256 x small (seconds); it stops at the next tile instead,
    # so well within a quarter of it. The small frame is timed before and after, the slower counting,
    # so that a test beside this one (ctest -j) slows the bound as it slows the frame.
    small = max(small, small_frame())
    assert elapsed < 0.2 + 64 * small + 0.5, f"{elapsed:.2f} s after SIGINT at 0.2 s (small frame {small:.3f} s)"
