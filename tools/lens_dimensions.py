#!/usr/bin/env python3
"""Error of a thin-lens render against Mitsuba's reference for two fspec
builds: RMSE (linear sRGB) of `cli/tests/conformance/scenes/camera_thinlens.xml`
rendered with the Sobol sampler at 16 and 64 spp, 12 seeds each, against
`cli/tests/conformance/reference/camera_thinlens.exr` (Mitsuba 3.9.1, 4096
spp). Used to choose the aperture's sampler dimensions (docs/results.md,
"Thin lens: the aperture's Sobol dimensions").

    python3 tools/lens_dimensions.py NAME=FSPEC NAME=FSPEC

Needs `pip install mitsuba==3.9.1 numpy` (to read the EXRs).
"""
import os
import subprocess
import sys

import numpy as np

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
import mitsuba as mi  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "cli/tests/conformance/scenes/camera_thinlens.xml")
REFERENCE = os.path.join(ROOT, "cli/tests/conformance/reference/camera_thinlens.exr")
SEEDS = range(1, 13)


def main():
    mi.set_variant("scalar_rgb")
    ref = np.array(mi.Bitmap(REFERENCE), dtype=np.float64)[:, :, :3]
    builds = dict(arg.split("=", 1) for arg in sys.argv[1:])
    for spp in (16, 64):
        for name, exe in builds.items():
            errs = []
            for seed in SEEDS:
                out = f"/tmp/lens-dimensions-{name}.exr"
                subprocess.run([exe, "render", SCENE, "--quiet", "--sampler", "sobol",
                                "--spp", str(spp), "--seed", str(seed), "--out", out],
                               check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                img = np.array(mi.Bitmap(out), dtype=np.float64)[:, :, :3]
                errs.append(np.sqrt(np.mean((img - ref) ** 2)))
            errs = np.array(errs)
            print(f"spp {spp} {name}: RMSE mean {errs.mean():.5f} "
                  f"(standard error {errs.std(ddof=1) / np.sqrt(len(errs)):.5f})", flush=True)


if __name__ == "__main__":
    main()
