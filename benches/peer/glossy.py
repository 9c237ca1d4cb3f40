#!/usr/bin/env python3
"""Where Kiln's noise on glossy and glass materials stands against Mitsuba 3's (not in CI).

`glossy.kiln` here (a rough glass sphere and a rough copper sphere, GGX α = 0.09, on a
grey floor under a small area light of radiance 40 and a dim sky) is built again for
Mitsuba: `roughdielectric` (IOR 1.5), `roughconductor` with the copper colour as its
reflectance, `diffuse` floor, the same camera. Both render with independent samples, a
box filter of one pixel and unbounded depth, `--seeds` times at `--spp` each.

Each pixel's variance is estimated from the spread of its value over the seeds. For
each region (the glass sphere, the copper sphere, the floor) the script prints the mean
of each renderer and its noise: the root of the mean variance over the mean, a relative
standard deviation at `--spp` samples. The ratio of Kiln's noise to Mitsuba's is the
excess (or lack) of variance at equal samples; the means show both converge to about the
same image (they differ where the models do: Kiln's metal is Schlick's Fresnel of the
colour, Mitsuba's a constant, and Kiln restores the energy single-scattering GGX loses).

`--kiln BINARY` may be given several times (e.g. a build before a change and after):
each gets its rows, and `--images DIR` writes each renderer's per-pixel relative
standard deviation as a PNG on a shared scale (white: 1 or more).

Setup (once):
    apt-get install libllvm19
    python3 -m venv /tmp/mivenv && /tmp/mivenv/bin/pip install mitsuba numpy
Run from the repository root, after `cargo build --release`:
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        /tmp/mivenv/bin/python benches/peer/glossy.py [--spp 16] [--seeds 16] \\
        [--kiln target/release/kiln] [--images DIR]
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile

import mitsuba as mi
import numpy as np

WIDTH, HEIGHT = 96, 64
FOV_Y = 30.0
ORIGIN = np.array([0.0, 1.1, 4.2])
TARGET = np.array([0.0, 0.45, 0.0])
SPHERES = {"glass sphere": np.array([-0.6, 0.5, 0.0]), "copper sphere": np.array([0.6, 0.5, 0.0])}
RADIUS = 0.5
HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "glossy.kiln")


def mitsuba_scene(spp, seed):
    T = mi.ScalarTransform4f
    rough = 0.3 * 0.3
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sensor": {
            "type": "perspective",
            "fov": FOV_Y,
            "fov_axis": "y",
            "to_world": T().look_at(origin=ORIGIN.tolist(), target=TARGET.tolist(), up=[0, 1, 0]),
            "film": {
                "type": "hdrfilm", "width": WIDTH, "height": HEIGHT,
                "rfilter": {"type": "box"}, "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.05, 0.06, 0.08]}},
        # Mitsuba's rectangle is 2 × 2 in XY facing +Z; Kiln's quad 1 × 1 in XZ facing +Y.
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90) @ T().scale(10),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}},
        },
        "lamp": {
            "type": "rectangle",
            "to_world": T().translate([0.5, 3, 1]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.3),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 40.0}},
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}},
        },
        "glass": {
            "type": "sphere", "center": SPHERES["glass sphere"].tolist(), "radius": RADIUS,
            "bsdf": {"type": "roughdielectric", "distribution": "ggx", "alpha": rough,
                     "int_ior": 1.5, "ext_ior": 1.0},
        },
        "copper": {
            "type": "sphere", "center": SPHERES["copper sphere"].tolist(), "radius": RADIUS,
            "bsdf": {"type": "roughconductor", "distribution": "ggx", "alpha": rough,
                     "material": "none",
                     "specular_reflectance": {"type": "rgb", "value": [0.95, 0.64, 0.54]}},
        },
    })


def render_kiln(binary, spp, seed):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "kiln.exr")
        cmd = [
            binary, "render", SCENE, "-o", out, "--spp", str(spp), "--seed", str(seed),
            "--sampler", "independent", "--filter", "box", "--filter-width", "1",
            "--max-bounces", "1024",
        ]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return np.array(mi.Bitmap(out), dtype=np.float64)[:, :, :3]


def regions():
    """Each sphere's disc (within 0.85 of its projected radius) and the floor (the rest
    of the lower half of the image)."""
    forward = (TARGET - ORIGIN) / np.linalg.norm(TARGET - ORIGIN)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    scale = HEIGHT / 2 / math.tan(math.radians(FOV_Y / 2))
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH] + 0.5
    masks = {}
    for name, centre in SPHERES.items():
        d = centre - ORIGIN
        depth = d @ forward
        cx = WIDTH / 2 + scale * (d @ right) / depth
        cy = HEIGHT / 2 - scale * (d @ up) / depth
        r = scale * math.tan(math.asin(RADIUS / np.linalg.norm(d)))
        masks[name] = np.hypot(x - cx, y - cy) < 0.85 * r
    masks["floor"] = (y > HEIGHT * 0.75) & ~masks["glass sphere"] & ~masks["copper sphere"]
    return masks


def luminance(img):
    return img @ np.array([0.2126, 0.7152, 0.0722])


def statistics(images):
    """Per pixel: the mean luminance over the seeds and its variance per render."""
    lum = np.stack([luminance(i) for i in images])
    return lum.mean(axis=0), lum.var(axis=0, ddof=1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--spp", type=int, default=16, help="samples per pixel of each render")
    parser.add_argument("--seeds", type=int, default=16, help="renders per renderer")
    parser.add_argument("--kiln", action="append", help="Kiln binaries (default: the release build)")
    parser.add_argument("--images", help="write per-pixel relative standard deviation PNGs here")
    args = parser.parse_args()
    binaries = args.kiln or [os.path.join(HERE, "..", "..", "target", "release", "kiln")]
    for b in binaries:
        if not os.path.exists(b):
            sys.exit(f"no Kiln binary at {b}: cargo build --release")
    mi.set_variant("llvm_ad_rgb" if "DRJIT_LIBLLVM_PATH" in os.environ else "scalar_rgb")
    renderers = {}
    renderers["Mitsuba 3"] = statistics(
        [np.array(mi.render(mitsuba_scene(args.spp, s)), dtype=np.float64) for s in range(args.seeds)]
    )
    for b in binaries:
        name = "Kiln" if len(binaries) == 1 else f"Kiln ({b})"
        renderers[name] = statistics([render_kiln(b, args.spp, s + 1) for s in range(args.seeds)])
    masks = regions()
    reference = renderers["Mitsuba 3"]
    print(f"\n{WIDTH}×{HEIGHT}, {args.spp} spp × {args.seeds} seeds, independent samples, box filter, "
          "unbounded depth; luminance\n")
    print("| region | pixels | renderer | mean | relative noise | noise ÷ Mitsuba's |")
    print("|---|---:|---|---:|---:|---:|")
    for region, mask in masks.items():
        ref_mean = reference[0][mask].mean()
        ref_noise = math.sqrt(reference[1][mask].mean()) / ref_mean
        for name, (mean, var) in renderers.items():
            m = mean[mask].mean()
            noise = math.sqrt(var[mask].mean()) / m
            print(f"| {region} | {mask.sum()} | {name} | {m:.4f} | {noise:.3f} | {noise / ref_noise:.2f} |")
    if args.images:
        os.makedirs(args.images, exist_ok=True)
        for i, (name, (mean, var)) in enumerate(renderers.items()):
            rel = np.sqrt(var) / np.maximum(mean, 1e-3)
            img = np.clip(rel, 0.0, 1.0)
            path = os.path.join(args.images, f"noise-{i}.png")
            mi.util.write_bitmap(path, np.repeat(img[:, :, None], 3, axis=2).astype(np.float32))
            print(f"{path}: {name}")


if __name__ == "__main__":
    main()
