#!/usr/bin/env python3
"""Kiln's volumetric path tracer against Mitsuba 3's `volpath`, side by side (not in CI).

A unit sphere filled with a chromatic scattering medium (σs = (2, 1, 0.5), σa = (0.1,
0.2, 0.4) per unit, Henyey–Greenstein g = 0.3) under a 2 × 2 area light of radiance 5, in
a uniform environment of 0.1, seen from 4 units away: once with an index-matched boundary
(a bare volume in Kiln, a `null` BSDF in Mitsuba) and once behind a smooth dielectric of
IOR 1.5. The Kiln scenes are `sphere_medium.kiln` and `sphere_medium_in_glass.kiln` here.

For each region of the image (the sphere's upper and lower halves, its rim, the whole
disc) it prints the mean per channel from Kiln and from Mitsuba (each the mean of two
seeds), their relative difference, and each renderer's seed-to-seed difference: the noise
that the difference between the renderers should be of the order of.

Setup (once):
    python3 -m venv /tmp/mivenv && /tmp/mivenv/bin/pip install mitsuba numpy
Run from the repository root (the release build of kiln is used if it is there):
    /tmp/mivenv/bin/python benches/peer/volumes.py [--spp 512] [--reference-spp N] [--only glass]
"""

import argparse
import os
import subprocess
import sys
import tempfile

import mitsuba as mi
import numpy as np

SIZE = 64
FOV_Y = 35.0
SIGMA_S = [2.0, 1.0, 0.5]
SIGMA_A = [0.1, 0.2, 0.4]
G = 0.3
HERE = os.path.dirname(os.path.abspath(__file__))


def mitsuba_scene(glass, spp, seed):
    T = mi.ScalarTransform4f
    sigma_t = [s + a for s, a in zip(SIGMA_S, SIGMA_A)]
    medium = {
        "type": "homogeneous",
        "albedo": {"type": "rgb", "value": [s / t for s, t in zip(SIGMA_S, sigma_t)]},
        # RGB values are reflectances (within [0, 1]): σt is given over its largest channel.
        "sigma_t": {"type": "rgb", "value": [t / max(sigma_t) for t in sigma_t]},
        "scale": max(sigma_t),
        "phase": {"type": "hg", "g": G},
    }
    surface = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0} if glass else {"type": "null"}
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": -1},
        "sensor": {
            "type": "perspective",
            "fov": FOV_Y,
            "fov_axis": "y",
            "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "tent"}},
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
        "environment": {"type": "constant", "radiance": {"type": "rgb", "value": 0.1}},
        "light": {
            "type": "rectangle",
            # Mitsuba's rectangle is 2 × 2 in XY facing +Z: turned to face down.
            "to_world": T().translate([0, 3, 0]) @ T().rotate([1, 0, 0], 90),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 5.0}},
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}},
        },
        "sphere": {"type": "sphere", "bsdf": surface, "interior": medium},
    })


def kiln_binary():
    for build in ["release", "debug"]:
        path = os.path.join(HERE, "..", "..", "target", build, "kiln")
        if os.path.exists(path):
            return path
    sys.exit("build kiln first: cargo build --release")


def render_kiln(glass, spp, seed):
    scene = os.path.join(HERE, "sphere_medium_in_glass.kiln" if glass else "sphere_medium.kiln")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "kiln.exr")
        cmd = [kiln_binary(), "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed)]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        return np.array(mi.Bitmap(out))[:, :, :3].astype(np.float64)


def regions():
    # The sphere's silhouette: radius tan(asin(1/4)) / tan(fov/2) of the half height.
    half = np.tan(np.radians(FOV_Y / 2))
    radius = np.tan(np.arcsin(0.25)) / half * SIZE / 2
    y, x = np.mgrid[0:SIZE, 0:SIZE] + 0.5
    r = np.hypot(x - SIZE / 2, y - SIZE / 2) / radius
    inside = r < 0.9
    return {
        "upper half": inside & (y < SIZE / 2),
        "lower half": inside & (y >= SIZE / 2),
        "rim (0.6-0.9 R)": (r > 0.6) & inside,
        "whole disc": inside,
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--spp", type=int, default=512, help="Kiln's samples per pixel, per seed")
    parser.add_argument("--reference-spp", type=int, help="Mitsuba's, per seed (default: --spp)")
    parser.add_argument("--only", choices=["index-matched", "glass"], help="one of the two cases")
    args = parser.parse_args()
    ref_spp = args.reference_spp or args.spp
    mi.set_variant("scalar_rgb")
    for glass in [False, True]:
        if args.only and args.only != ("glass" if glass else "index-matched"):
            continue
        name = "behind glass (IOR 1.5)" if glass else "index-matched"
        kiln = [render_kiln(glass, args.spp, s) for s in (1, 2)]
        ref = [np.array(mi.render(mitsuba_scene(glass, ref_spp, s)), dtype=np.float64) for s in (1, 2)]
        print(f"\n### {name}, {SIZE}×{SIZE}, Kiln {args.spp} spp × 2 seeds, Mitsuba {ref_spp} spp × 2 seeds\n")
        print("| region | channel | Kiln | Mitsuba | Kiln − Mitsuba | Kiln seed 1 − seed 2 | Mitsuba seed 1 − seed 2 |")
        print("|---|---|---:|---:|---:|---:|---:|")
        for region, mask in regions().items():
            for c, channel in enumerate("RGB"):
                k1, k2 = kiln[0][mask, c].mean(), kiln[1][mask, c].mean()
                m1, m2 = ref[0][mask, c].mean(), ref[1][mask, c].mean()
                k, m = (k1 + k2) / 2, (m1 + m2) / 2
                print(
                    f"| {region} | {channel} | {k:.4f} | {m:.4f} | {100 * (k - m) / m:+.2f}% "
                    f"| {100 * (k1 - k2) / m:+.2f}% | {100 * (m1 - m2) / m:+.2f}% |"
                )


if __name__ == "__main__":
    main()
