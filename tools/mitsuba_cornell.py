#!/usr/bin/env python3
"""Render Mitsuba 3's built-in Cornell box as the reference image of
simd-tracer/tests/mitsuba_reference.rs.

What it does: takes `mi.cornell_box()` unchanged (camera: perspective,
39.3077 deg along the smaller axis, at (0, 0, 3.9) looking along -z; Gaussian
reconstruction filter, stddev 0.5 px; diffuse RGB reflectances and an RGB
area emitter, upsampled by Mitsuba's spectral variants) and only overrides
the film size, the sample count and the path tracer's max_depth. The image
is rendered in passes of --pass-spp samples with seeds 0, 1, ... and the
passes are averaged (a JIT variant such as llvm_ad_spectral keeps one lane
per sample in memory; passes bound that).
The output is Mitsuba's film as is: linear sRGB (D65), float32, RGB.

Made with: mitsuba 3.9.1 (drjit 1.5.0) from PyPI, variant scalar_spectral
(llvm_ad_spectral aborted on this machine in LLVM instruction selection,
"Cannot select ... fminimum", with the system libLLVM).

Rerun (about 4 minutes on 2 shared cores; writes a float32 ZIP EXR, 50 KB):
    pip install mitsuba==3.9.1
    nice -n 10 python3 tools/mitsuba_cornell.py \
        --width 64 --height 64 --spp 8192 --max-depth 8 \
        --out simd-tracer/tests/data/mitsuba-cornell-64x64-8192spp.exr
Our side of the comparison, same settings (the test renders it in-process):
    fspec render cornell --width 64 --height 64 --spp 4096 --max-depth 8 --out ours.exr
"""

import argparse
import time

import mitsuba as mi
import numpy as np


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--width", type=int, default=64)
    p.add_argument("--height", type=int, default=64)
    p.add_argument("--spp", type=int, default=8192)
    p.add_argument("--pass-spp", type=int, default=4096)
    p.add_argument("--max-depth", type=int, default=8)
    p.add_argument("--variant", default="scalar_spectral")
    p.add_argument("--out", required=True)
    a = p.parse_args()

    mi.set_variant(a.variant)
    d = mi.cornell_box()
    d["sensor"]["film"]["width"] = a.width
    d["sensor"]["film"]["height"] = a.height
    d["integrator"]["max_depth"] = a.max_depth
    pass_spp = min(a.pass_spp, a.spp)
    if a.spp % pass_spp:
        raise SystemExit("--spp must be a multiple of --pass-spp")
    d["sensor"]["sampler"]["sample_count"] = pass_spp
    scene = mi.load_dict(d)

    passes = a.spp // pass_spp
    acc = np.zeros((a.height, a.width, 3), dtype=np.float64)
    start = time.time()
    for i in range(passes):
        img = np.array(mi.render(scene, spp=pass_spp, seed=i), dtype=np.float64)
        acc += img[:, :, :3]
    acc /= passes
    print(f"{passes} passes x {pass_spp} spp in {time.time() - start:.1f} s")
    print("mean RGB", acc.reshape(-1, 3).mean(axis=0))

    bmp = mi.Bitmap(acc.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.write(a.out)


if __name__ == "__main__":
    main()
