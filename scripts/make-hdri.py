#!/usr/bin/env python3
"""Writes a small synthetic outdoor HDR environment map with a sun (an equirectangular .pfm).

    python3 scripts/make-hdri.py OUT.pfm [--width 1024]

The map is in voxfx's equirectangular convention (environment.cpp: u = 0.5 + atan2(x, -z) / 2 pi,
v = acos(y) / pi, v = 0 at the zenith; PFM rows bottom to top) and holds, in linear radiance:

- a clear sky: a blue zenith brightening towards a pale horizon, brighter around the sun;
- a ground below the horizon (albedo 0.3, lit by the sun and sky, a little darker at the nadir);
- a sun disc of 1 degree angular radius, towards (-0.75, 0.55, 0.35) (elevation 33.7 degrees; the
  jade dragon scene's sun), whose radiance gives a normal irradiance of 3.

Like a real clear-day HDRI, the sun carries most of the direct light on a level plane: the script
prints the figures (the irradiance of a level plane from the sun, the sky and the ground) computed
from the texels it writes. Numpy only; the map is generated, not committed (used by the HDRI strip
of README's "Before and after the physical sky").
"""
import argparse
import sys

import numpy as np

SUN_TOWARDS = np.array([-0.75, 0.55, 0.35])
SUN_RADIUS_DEG = 1.0
SUN_NORMAL_IRRADIANCE = 3.0
SUN_COLOUR = np.array([1.0, 0.95, 0.88])
ZENITH = np.array([0.040, 0.070, 0.150])  # sky radiance at the zenith
HORIZON = np.array([0.150, 0.165, 0.180])  # and at the horizon
GROUND_ALBEDO = np.array([0.30, 0.28, 0.24])


def directions(w, h, ss=1):
    """Unit directions at the centres of w x h texels (ss x ss subsamples each, averaged by the caller)."""
    u = (np.arange(w * ss) + 0.5) / (w * ss)
    v = (np.arange(h * ss) + 0.5) / (h * ss)
    phi = (u - 0.5) * 2 * np.pi
    theta = v * np.pi
    st = np.sin(theta)[:, None]
    return np.stack([st * np.sin(phi)[None, :], np.cos(theta)[:, None] * np.ones_like(phi)[None, :],
                     -st * np.cos(phi)[None, :]], axis=-1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--width", type=int, default=1024)
    a = ap.parse_args()
    w, h = a.width, a.width // 2
    sun = SUN_TOWARDS / np.linalg.norm(SUN_TOWARDS)
    d = directions(w, h)
    y = d[..., 1]

    # Sky: zenith-to-horizon blend, plus a soft glow (aureole) around the sun.
    t = np.clip(y, 0, 1) ** 0.5
    sky = HORIZON * (1 - t)[..., None] + ZENITH * t[..., None]
    cos_sun = np.clip(d @ sun, -1, 1)
    sky *= (1 + 0.8 * np.exp((cos_sun - 1) / 0.02))[..., None]

    # The sun disc's radiance: normal irradiance / disc solid angle, the edge texels by coverage.
    omega_sun = 2 * np.pi * (1 - np.cos(np.radians(SUN_RADIUS_DEG)))
    l_sun = SUN_NORMAL_IRRADIANCE / omega_sun
    ss = 8
    ds = directions(w, h, ss)
    inside = (ds @ sun) >= np.cos(np.radians(SUN_RADIUS_DEG))
    coverage = inside.reshape(h, ss, w, ss).mean(axis=(1, 3))

    # Ground: Lambert of GROUND_ALBEDO under the sun (at its elevation) and the sky above (pi * mean sky
    # radiance of the upper hemisphere, roughly), darker towards the nadir.
    sky_irr = np.pi * 0.5 * (ZENITH + HORIZON)
    ground_irr = SUN_NORMAL_IRRADIANCE * SUN_COLOUR * sun[1] + sky_irr
    ground = GROUND_ALBEDO * ground_irr / np.pi
    gfade = 1 - 0.25 * np.clip(-y, 0, 1)
    img = np.where((y >= 0)[..., None], sky, ground * gfade[..., None])
    img = img * (1 - coverage)[..., None] + (l_sun * SUN_COLOUR)[None, None, :] * coverage[..., None]
    img = img.astype(np.float32)

    # Figures from the texels: irradiance of a level plane (normal +y) from each part.
    rows = np.arange(h)
    omega_row = 2 * np.pi / w * (np.cos(rows * np.pi / h) - np.cos((rows + 1) * np.pi / h))
    omega = np.repeat(omega_row[:, None], w, axis=1)
    lum = img @ np.array([0.2126, 0.7152, 0.0722])
    cos_up = np.clip(y, 0, None)
    sun_mask = coverage > 0
    l_sun_lum = float(l_sun * SUN_COLOUR @ np.array([0.2126, 0.7152, 0.0722]))
    e_sun = float((l_sun_lum * coverage * omega * cos_up).sum())
    e_all = float((lum * omega * cos_up).sum())
    e_sky = e_all - e_sun
    e_down = float((lum * omega * np.clip(-y, 0, None)).sum())
    mean = float((lum * omega).sum() / (4 * np.pi))
    print(f"{a.out}: {w} x {h}, sun towards ({sun[0]:.3f}, {sun[1]:.3f}, {sun[2]:.3f}), elevation "
          f"{np.degrees(np.arcsin(sun[1])):.1f} deg, radius {SUN_RADIUS_DEG} deg ({omega_sun:.3g} sr), "
          f"radiance {l_sun:.0f} x colour (1, 0.95, 0.88), {int(sun_mask.sum())} texels", file=sys.stderr)
    print(f"  level plane facing up: sun {e_sun:.3f}, sky {e_sky:.3f} (sun {100 * e_sun / e_all:.0f} % of "
          f"{e_all:.3f}); facing down (ground) {e_down:.3f}; zenith {float(lum[0].mean()):.3f}, horizon "
          f"{float(lum[h // 2 - 1].mean()):.3f}, map mean {mean:.4f}, peak / mean {float(lum.max()) / mean:.0f}",
          file=sys.stderr)

    with open(a.out, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        f.write(np.ascontiguousarray(img[::-1]).astype("<f4").tobytes())  # rows bottom to top


if __name__ == "__main__":
    main()
