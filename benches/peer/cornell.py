#!/usr/bin/env python3
"""Kiln against Mitsuba 3 on the bundled Cornell box, side by side (not in CI).

The geometry, materials and camera are read from `assets/scenes/cornell-box.kiln` and
built for Mitsuba as meshes (Lambertian materials, the light an area emitter on its two
triangles). Both render with a box filter of one pixel and unbounded depth (Russian
roulette), `SIZE`×`SIZE` pixels. The common reference is Mitsuba at `--reference-spp`,
cached in `benches/peer/.cache/`.

It prints, for Kiln (each sampler) and Mitsuba (`independent`, its default): the
whole-process time of `kiln render` at `--spp` (after a warm-up that fills Mesa's shader
cache), Mitsuba's time for the same samples (`mi.render` in this process, its first call:
JIT compilation included), the RMSE against
the reference with the light's edge pixels left out, the RMSE at equal time (Mitsuba given
the samples it renders in Kiln's time), and the ratios.

Setup (once):
    apt-get install libllvm19
    python3 -m venv /tmp/mivenv && /tmp/mivenv/bin/pip install mitsuba numpy
Run from the repository root, after `cargo build --release`:
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        /tmp/mivenv/bin/python benches/peer/cornell.py [--spp 64] [--reference-spp 8192]
"""

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

import mitsuba as mi
import numpy as np

SIZE = 256
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
SCENE = os.path.join(ROOT, "assets", "scenes", "cornell-box.kiln")
MAX_BOUNCES = 1024


def numbers(text):
    return [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?", text)]


def tuples(text):
    return [numbers(t) for t in re.findall(r"\(([^()]*)\)", text)]


def read_kiln_scene():
    """The Cornell box's camera, materials, inline meshes and instances, by pattern: the
    file is the bundled one, whose shape this script knows."""
    src = re.sub(r"//[^\n]*", "", open(SCENE).read())
    camera = {
        "position": numbers(re.search(r"position:\s*\(([^)]*)\)", src).group(1)),
        "look_at": numbers(re.search(r"look_at:\s*\(([^)]*)\)", src).group(1)),
        "fov_y": float(re.search(r"fov_y:\s*([\d.]+)", src).group(1)),
    }
    materials = {}
    for name, body in re.findall(r'"([^"]+)":\s*\((base_color:[^\n]*)\),\n', src):
        color = numbers(re.search(r"base_color:\s*\(([^)]*)\)", body).group(1))
        emission = re.search(r"emission:\s*\(([^)]*)\)", body)
        materials[name] = (color, numbers(emission.group(1)) if emission else None)
    meshes = {}
    for name, body in re.findall(r'"([^"]+)":\s*Inline\((.*?)\),\n', src, re.S):
        positions = tuples(re.search(r"positions:\s*\[(.*?)\]", body, re.S).group(1))
        indices = tuples(re.search(r"indices:\s*\[(.*?)\]", body, re.S).group(1))
        meshes[name] = (positions, indices)
    instances = []
    listed = src[src.index("instances:"):]
    for body in listed.split("(mesh:")[1:]:
        mesh = re.search(r'"([^"]+)"', body).group(1)
        material = re.search(r'material:\s*"([^"]+)"', body).group(1)
        transform = {}
        for key in ("translate", "rotate", "scale"):
            m = re.search(key + r":\s*\(([^)]*)\)", body)
            if m:
                transform[key] = numbers(m.group(1))
        instances.append((mesh, material, transform))
    return camera, materials, meshes, instances


def mitsuba_scene(spp, seed):
    camera, materials, meshes, instances = read_kiln_scene()
    T = mi.ScalarTransform4f
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sensor": {
            "type": "perspective",
            "fov": camera["fov_y"],
            "fov_axis": "y",
            "to_world": T().look_at(origin=camera["position"], target=camera["look_at"], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
    }
    for i, (mesh, material, transform) in enumerate(instances):
        color, emission = materials[material]
        shape = {"bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": color}}}
        if emission:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": emission}}
        if mesh in meshes:
            shape.update({"type": "ply", "filename": ply(mesh, *meshes[mesh]), "face_normals": True})
            scene[f"shape {i}"] = shape
            continue
        # Kiln's Cube: the unit cube centred on the origin; Mitsuba's spans [-1, 1].
        s = transform.get("scale", [1, 1, 1])
        r = transform.get("rotate", [0, 0, 0])
        t = transform.get("translate", [0, 0, 0])
        to_world = (
            T().translate(t)
            @ T().rotate([0, 0, 1], r[2])
            @ T().rotate([0, 1, 0], r[1])
            @ T().rotate([1, 0, 0], r[0])
            @ T().scale([v / 2 for v in s])
        )
        shape.update({"type": "cube", "to_world": to_world})
        scene[f"shape {i}"] = shape
    return mi.load_dict(scene)


def ply(name, positions, indices):
    """An inline mesh of the scene file as a PLY file for Mitsuba (in the temporary folder)."""
    path = os.path.join(tempfile.gettempdir(), "kiln_peer_" + name.replace(" ", "_") + ".ply")
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"element vertex {len(positions)}\nproperty float x\nproperty float y\nproperty float z\n")
        f.write(f"element face {len(indices)}\nproperty list uchar int vertex_indices\nend_header\n")
        for p in positions:
            f.write(" ".join(str(v) for v in p) + "\n")
        for t in indices:
            f.write("3 " + " ".join(str(int(v)) for v in t) + "\n")
    return path


def render_mitsuba(spp, seed):
    start = time.perf_counter()
    image = np.array(mi.render(mitsuba_scene(spp, seed)), dtype=np.float64)[:, :, :3]
    return image, time.perf_counter() - start


def kiln_binary():
    path = os.path.join(ROOT, "target", "release", "kiln")
    if not os.path.exists(path):
        sys.exit("build kiln first: cargo build --release")
    return path


def render_kiln(spp, sampler, seed=1):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "kiln.exr")
        cmd = [
            kiln_binary(), "render", SCENE, "-o", out, "--quiet",
            "--size", f"{SIZE}x{SIZE}", "--spp", str(spp), "--seed", str(seed),
            "--max-bounces", str(MAX_BOUNCES), "--filter", "box", "--filter-width", "1",
            "--sampler", sampler,
        ]
        start = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        seconds = time.perf_counter() - start
        return np.array(mi.Bitmap(out), dtype=np.float64)[:, :, :3], seconds


def reference(spp):
    os.makedirs(os.path.join(HERE, ".cache"), exist_ok=True)
    path = os.path.join(HERE, ".cache", f"cornell_{SIZE}_{spp}.npy")
    if not os.path.exists(path):
        print(f"rendering the reference: Mitsuba, {spp} spp (cached in {path})", file=sys.stderr)
        np.save(path, render_mitsuba(spp, 1000)[0])
    return np.load(path)


def compared(ref):
    """Pixels away from the light's edge: not within a pixel of the light's own pixels."""
    light = ref.max(axis=2) > 2.0
    near = light.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near |= np.roll(np.roll(light, dy, axis=0), dx, axis=1)
    return ~near


def rmse(image, ref, mask):
    return math.sqrt(((image - ref) ** 2)[mask].mean())


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--reference-spp", type=int, default=8192)
    args = parser.parse_args()
    mi.set_variant("llvm_ad_rgb" if "DRJIT_LIBLLVM_PATH" in os.environ else "scalar_rgb")
    ref = reference(args.reference_spp)
    mask = compared(ref)
    # Mesa compiles Kiln's kernel at its first dispatch and caches it on disk; Mitsuba
    # compiles its kernels in every process. Warm Kiln's cache so that neither timing below
    # holds Mesa's one-time compile.
    for sampler in ("independent", "sobol"):
        render_kiln(1, sampler)
    mitsuba, t_mitsuba = render_mitsuba(args.spp, 1)
    e_mitsuba = rmse(mitsuba, ref, mask)
    print(f"\n{SIZE}×{SIZE}, {args.spp} spp, box filter, unbounded depth; Mitsuba {mi.variant()}; "
          f"reference: Mitsuba {args.reference_spp} spp; {mask.sum()} of {mask.size} pixels compared\n")
    print("| renderer | seconds | RMSE | RMSE at equal time (Mitsuba in Kiln's time) | time ÷ Mitsuba's | RMSE ÷ Mitsuba's, equal spp | equal time |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    print(f"| Mitsuba 3 ({mi.variant()}, independent) | {t_mitsuba:.2f} | {e_mitsuba:.5f} | | 1 | 1 | 1 |")
    for sampler in ("independent", "sobol"):
        kiln, t_kiln = render_kiln(args.spp, sampler)
        e_kiln = rmse(kiln, ref, mask)
        # Mitsuba's samples in Kiln's time, at its measured rate.
        equal_spp = max(1, round(args.spp * t_kiln / t_mitsuba))
        mitsuba_equal, _ = render_mitsuba(equal_spp, 2)
        e_equal = rmse(mitsuba_equal, ref, mask)
        print(f"| Kiln ({sampler}) | {t_kiln:.2f} | {e_kiln:.5f} | Mitsuba {equal_spp} spp: {e_equal:.5f} "
              f"| {t_kiln / t_mitsuba:.2f} | {e_kiln / e_mitsuba:.2f} | {e_kiln / e_equal:.2f} |")


if __name__ == "__main__":
    main()
