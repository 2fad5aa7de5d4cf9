#!/usr/bin/env python3
"""A white diffuse sphere under scenes/assets/envmap2.exr, rendered by
Mitsuba 3 (scalar_spectral): the reference of
cli/tests/environment_reference.rs, which renders the same scene from
scenes/envmap-sphere.toml. The map is seen directly around the sphere, so
the comparison checks the map's orientation and texel positions as well as
its RGB-illuminant spectra and the sphere's lighting (NEE + MIS).

Scene: a 64 x 64 perspective camera at (0, 0, 4) looking at the origin,
40 degrees field of view, box filter; a sphere of radius 1 at the origin,
`diffuse` reflectance 0.8; an `envmap` of envmap2.exr rotated 60 degrees
about +y; `path` integrator, max_depth 4.

    pip install mitsuba==3.9.1 numpy
    python3 tools/mitsuba_envmap.py --spp 4096 \\
        --out simd-tracer/tests/data/mitsuba-envmap-sphere-64x64-4096spp.exr
"""

import argparse
import pathlib

import mitsuba as mi

ROOT = pathlib.Path(__file__).resolve().parent.parent


def scene(spp, seed):
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 4},
        "sensor": {
            "type": "perspective",
            "fov": 40.0,
            "fov_axis": "x",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]
            ),
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
            "film": {
                "type": "hdrfilm",
                "width": 64,
                "height": 64,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
        "sphere": {
            "type": "sphere",
            "radius": 1.0,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}},
        },
        "env": {
            "type": "envmap",
            "filename": str(ROOT / "scenes" / "assets" / "envmap2.exr"),
            "to_world": mi.ScalarTransform4f().rotate(axis=[0, 1, 0], angle=60.0),
        },
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--spp", type=int, default=4096)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    mi.set_variant("scalar_spectral")
    image = mi.render(mi.load_dict(scene(args.spp, args.seed)))
    mi.Bitmap(image).write(args.out)


if __name__ == "__main__":
    main()
