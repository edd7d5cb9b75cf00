"""voxfx.Renderer and voxfx.Camera: the preview loop of `voxfx view` from Python (an orbit animated
in a notebook). Frames of an orbit have the right shape and differ; a preview is the full render of
the preview's options (through voxfx.render, another path), and cheaper than a full frame by the
work the renders count (samples that showed geometry, pixels shaded at every sample), not by the
clock; the camera moves keep what they promise.
"""
import math
import subprocess

import numpy as np
import pytest

import voxfx


@pytest.fixture(scope="module")
def bunny(data_path):
    return voxfx.load_scene(data_path("meshes/bunny00.off"))


@pytest.fixture(scope="module")
def tree(cli, tmp_path_factory):
    """The demo tree as glTF (its camera has no target of its own: the loader's is a unit ahead)."""
    out = tmp_path_factory.mktemp("tree")
    subprocess.run([cli, "demo", "--scenes", "tree", "--shadows", "none", "--write-scenes", str(out), "-o", str(out),
                    "--width", "16", "--height", "9", "-q"], check=True)
    return voxfx.load_scene(str(out / "tree.glb"))


def test_an_orbit_gives_frames_of_the_preview_size_that_differ(bunny):
    r = voxfx.Renderer(bunny, shadows="map", map_resolution=512, width=160, height=90)
    assert (r.width, r.height, r.preview_scale, r.shadows) == (160, 90, 4, "map")
    cam = r.camera()
    frames = [r.render(cam.orbit(k * math.pi / 6), preview=True) for k in range(4)]
    for f in frames:
        assert f.shape == (23, 40, 3) and f.dtype == np.uint8  # 90 / 4 rounded up
    for a, b in zip(frames, frames[1:]):
        assert np.count_nonzero(np.any(a != b, axis=2)) > 20
    full = r.render(cam)
    assert full.shape == (90, 160, 3) and full.dtype == np.uint8


def test_a_preview_is_the_render_of_the_preview_options_and_counts_less_work(bunny):
    r = voxfx.Renderer(bunny, shadows="map", map_resolution=512, width=160, height=90)
    cam = r.camera().orbit(0.4, 0.2)
    preview, small = r.render(cam, preview=True, linear=True, report=True)
    full, big = r.render(cam, linear=True, report=True)
    # The same frame through voxfx.render: 1/4 of the size, one sample per pixel, no occlusion.
    direct = voxfx.render(bunny, camera=cam, shadows="map", map_resolution=512, width=40, height=23, aa="off",
                          ao="off")
    assert np.array_equal(preview, direct)
    assert not np.array_equal(preview, voxfx.render(bunny, camera=cam, shadows="map", map_resolution=512, width=40,
                                                    height=23, aa="off"))  # occlusion would change it
    assert (small["width"], small["height"], small["preview"]) == (40, 23, True)
    assert (big["width"], big["height"], big["preview"]) == (160, 90, False)
    # Counted work: full frames hold 2x2 samples per pixel of a 4x4 larger image (about 64 times
    # the samples showing the bunny) and shade edge pixels at every sample; previews do neither.
    assert small["covered_pixels"] > 0 and big["covered_pixels"] > 40 * small["covered_pixels"]
    assert small["refined_pixels"] == 0 < big["refined_pixels"]
    # The 8-bit frame is the sRGB encoding of the linear one (IEC 61966-2-1, rounded).
    srgb = r.render(cam, preview=True)
    v = np.clip(preview, 0, 1)
    expected = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055) * 255
    assert np.max(np.abs(srgb - expected)) <= 0.5 + 1e-3


def test_the_renderers_camera_turns_about_the_scene_and_shows_the_same_image(tree):
    r = voxfx.Renderer(tree, shadows="none", width=64, height=36, ao="off")
    own = tree.camera(0, 64 / 36)
    aimed = r.camera()
    assert aimed.position == own.position and aimed.fov_y == own.fov_y
    # The glTF camera's target is a unit ahead; the renderer's lies at the depth of the tree.
    d_own = np.linalg.norm(np.subtract(own.target, own.position))
    d_aimed = np.linalg.norm(np.subtract(aimed.target, aimed.position))
    assert abs(d_own - 1) < 1e-9 and d_aimed > 3
    direction = np.subtract(aimed.target, aimed.position) / d_aimed
    assert np.allclose(direction, np.subtract(own.target, own.position) / d_own, atol=1e-12)
    assert np.array_equal(r.render(aimed), r.render(own))
    assert np.array_equal(r.render(0), r.render(own))  # an index is the scene's camera


def test_camera_moves_keep_what_they_promise():
    cam = voxfx.Camera((3, 2, 5), (0.5, 0.25, -0.5), fov_y=0.7, name="c")
    d = np.linalg.norm(np.subtract(cam.target, cam.position))
    turned = cam.orbit(1.0, 0.3)
    assert turned.target == cam.target and turned.up == cam.up
    assert abs(np.linalg.norm(np.subtract(turned.target, turned.position)) - d) < 1e-12
    assert cam.orbit(2 * math.pi).position == pytest.approx(cam.position, abs=1e-12)
    moved = cam.pan(0.25, -0.1)
    shift = np.subtract(moved.target, cam.target)
    assert np.allclose(np.subtract(moved.position, cam.position), shift, atol=1e-12)
    assert abs(np.linalg.norm(shift) - math.hypot(0.25, 0.1) * 2 * d * math.tan(0.35)) < 1e-12
    closer = cam.dolly(0.5)
    assert abs(np.linalg.norm(np.subtract(closer.target, closer.position)) - d / 2) < 1e-12
    assert closer.near == cam.near / 2 and cam == voxfx.Camera((3, 2, 5), (0.5, 0.25, -0.5), fov_y=0.7, name="c")
    assert "voxfx.Camera 'c'" in repr(cam)
    with pytest.raises(voxfx.ArgumentError):
        cam.dolly(0)
    with pytest.raises(voxfx.ArgumentError):
        voxfx.Camera((0, 0, 0), (0, 0, 0))
    with pytest.raises(voxfx.ArgumentError):
        voxfx.Camera((0, 0, 1), (0, 0, 0), fov_y=4)
    with pytest.raises(voxfx.ArgumentError):
        voxfx.Camera((0, 0, 1), (0, 0))


def test_bad_renderer_arguments_are_refused(bunny):
    with pytest.raises(voxfx.ArgumentError):
        voxfx.Renderer(bunny, preview_scale=0)
    with pytest.raises(voxfx.ArgumentError):
        voxfx.Renderer(bunny, shadows="soft")
    r = voxfx.Renderer(bunny, width=32, height=18)
    with pytest.raises(voxfx.ArgumentError):
        r.render(3)  # the bunny has no cameras but the default one
    with pytest.raises(voxfx.ArgumentError):
        r.render("front")
