#!/usr/bin/env python3
"""A rough glass sphere in Mitsuba 3's Cornell box, rendered by Mitsuba and
compared with fspec's render of the same scene.

The scene: `mi.cornell_box()` without its two boxes, plus a sphere of
radius 0.5 at (0, -0.5, 0) (resting on the floor) made of Mitsuba's
`roughdielectric` (GGX, alpha 0.3, interior IOR 1.5, exterior 1.0). fspec's
side is the same box (scenes/cornell/cornell.obj without the box faces)
with the sphere tessellated to 64 x 128 outward-facing triangles and the
`dielectric` material with `ior = 1.5`, `roughness = 0.3` (roughness is
GGX alpha). `--write-fspec-scene DIR` writes that OBJ and TOML.

Compared: the image mean of linear sRGB and the mean over the pixels whose
centre ray hits the sphere, as fspec / Mitsuba ratios.

    pip install mitsuba==3.9.1 numpy
    python3 tools/mitsuba_rough_glass.py --write-fspec-scene /tmp/rg
    fspec render /tmp/rg/scene.toml --out /tmp/rg/ours.exr
    python3 tools/mitsuba_rough_glass.py --spp 1024 --out /tmp/rg/mitsuba.exr \\
        --compare /tmp/rg/ours.exr
"""

import argparse
import math
import pathlib

import mitsuba as mi
import numpy as np

CENTRE = (0.0, -0.5, 0.0)
RADIUS = 0.5
ALPHA = 0.3
IOR = 1.5
EYE_Z = 3.9
FOV_DEG = 39.3077


def write_fspec_scene(folder, width, height, spp, max_depth):
    folder.mkdir(parents=True, exist_ok=True)
    root = pathlib.Path(__file__).resolve().parent.parent / "scenes" / "cornell"
    lines, skip = [], False
    for line in (root / "cornell.obj").read_text().splitlines():
        if line.startswith("o "):
            skip = line.split()[1] in ("small-box", "large-box")
        if line.startswith("f ") and skip:
            continue
        if line.startswith("mtllib"):
            line = "mtllib scene.mtl"
        lines.append(line)
    base = sum(1 for line in lines if line.startswith("v "))
    theta_steps, phi_steps = 64, 128
    lines += ["o sphere", "usemtl glass"]
    for i in range(theta_steps + 1):
        theta = math.pi * i / theta_steps
        for j in range(phi_steps):
            phi = 2 * math.pi * j / phi_steps
            x = CENTRE[0] + RADIUS * math.sin(theta) * math.cos(phi)
            y = CENTRE[1] + RADIUS * math.cos(theta)
            z = CENTRE[2] + RADIUS * math.sin(theta) * math.sin(phi)
            lines.append(f"v {x:.7f} {y:.7f} {z:.7f}")

    def vertex(i, j):
        return base + 1 + i * phi_steps + j % phi_steps

    for i in range(theta_steps):
        for j in range(phi_steps):
            a, b, c, d = vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1)
            if i > 0:
                lines.append(f"f {a} {d} {c}")
            if i < theta_steps - 1:
                lines.append(f"f {a} {c} {b}")
    (folder / "scene.obj").write_text("\n".join(lines) + "\n")
    # The box's MTL and a name for the sphere, mapped to the glass below.
    mtl = (root / "cornell.mtl").read_text()
    (folder / "scene.mtl").write_text(mtl + "\nnewmtl glass\nKd 1 1 1\n")
    (folder / "scene.toml").write_text(
        f"""[render]
width = {width}
height = {height}
spp = {spp}
max_depth = {max_depth}
seed = 1

[camera]
position = [0, 0, {EYE_Z}]
target = [0, 0, 0]
up = [0, 1, 0]
fov_deg = {FOV_DEG}

[materials.glass]
type = "dielectric"
ior = {IOR}
roughness = {ALPHA}

[[meshes]]
obj = "scene.obj"
materials = {{ glass = "glass" }}
"""
    )


def sphere_mask(width, height):
    """Pixels whose centre ray hits the sphere (pinhole, fov along the
    smaller axis, looking down -z from (0, 0, EYE_Z))."""
    tan_half = math.tan(math.radians(FOV_DEG) / 2)
    scale = tan_half / (min(width, height) / 2)
    mask = np.zeros((height, width), dtype=bool)
    o = np.array([0.0, 0.0, EYE_Z]) - np.array(CENTRE)
    for py in range(height):
        for px in range(width):
            d = np.array([(px + 0.5 - width / 2) * scale, (height / 2 - py - 0.5) * scale, -1.0])
            b = np.dot(o, d)
            disc = b * b - np.dot(d, d) * (np.dot(o, o) - RADIUS * RADIUS)
            mask[py, px] = disc > 0
    return mask


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--width", type=int, default=64)
    p.add_argument("--height", type=int, default=64)
    p.add_argument("--spp", type=int, default=1024)
    p.add_argument("--max-depth", type=int, default=8)
    p.add_argument("--variant", default="scalar_spectral")
    p.add_argument("--out", type=pathlib.Path)
    p.add_argument("--compare", type=pathlib.Path, nargs="*", default=[])
    p.add_argument("--write-fspec-scene", type=pathlib.Path)
    a = p.parse_args()
    if a.write_fspec_scene:
        write_fspec_scene(a.write_fspec_scene, a.width, a.height, a.spp, a.max_depth)
        if not a.out:
            return
    mi.set_variant(a.variant)
    scene = mi.cornell_box()
    del scene["small-box"], scene["large-box"]
    scene["sphere"] = {
        "type": "sphere",
        "center": mi.ScalarPoint3f(*CENTRE),
        "radius": RADIUS,
        "bsdf": {"type": "roughdielectric", "distribution": "ggx", "alpha": ALPHA,
                 "int_ior": IOR, "ext_ior": 1.0},
    }
    scene["integrator"]["max_depth"] = a.max_depth
    scene["sensor"]["film"]["width"] = a.width
    scene["sensor"]["film"]["height"] = a.height
    scene["sensor"]["sampler"]["sample_count"] = a.spp
    image = np.array(mi.render(mi.load_dict(scene)))
    if a.out:
        mi.Bitmap(image).write(str(a.out))
    mask = sphere_mask(a.width, a.height)
    for other in a.compare:
        ours = np.array(mi.Bitmap(str(other)))[:, :, :3]
        whole = ours.reshape(-1, 3).mean(0) / image.reshape(-1, 3).mean(0)
        sphere = ours[mask].mean(0) / image[mask].mean(0)
        print(f"{other.name}: image mean ratio {np.round(whole, 4)}, "
              f"sphere ({mask.sum()} px) ratio {np.round(sphere, 4)}")


if __name__ == "__main__":
    main()
