#!/usr/bin/env python3
"""Noise at equal CPU time and cost per sample of the hybrid transport.

    python3 tools/hybrid_noise.py FSPEC OUT_DIR [--side 128] [--seeds 4]
                                               [--budget-spp 256]

1. Cost: CPU seconds (user + system of the child, `getrusage`) per sample
   per pixel of `fspec render` for the Fourier transport and the hybrid on
   `cornell` (nothing disperses) and on `prism`, and for the sampled
   transport (hero wavelengths and `--sampling lights`) and the hybrid
   with C = 1, 4, 8 (its default `--sampling lights`), with C = 4 and
   hero wavelengths, and with C = 4 tracing every wavelength of a split
   on its own path (`--dispersion-paths all`), and with C = 4 and N = 12
   with its caustics left to the camera paths (`--caustics camera`; the
   other hybrids trace light paths, fspec's default) on `prism`; the renders of
   each round are alternated and the median of three rounds is kept.
2. Noise at equal time: every transport gets the CPU time of the hybrid
   (C = 4) at `--budget-spp` samples per pixel, converted to its own spp by
   its measured cost; `--seeds` renders each, written as partial films
   with an XYZ buffer (`.fspart`: the f64 sums, read here without an EXR
   library). Colour noise per pixel is the standard deviation over the
   seeds of CIELAB a* and b* (sqrt(var a* + var b*); white: equal-energy,
   Y = 1), averaged over three regions of the `prism` image: `sphere` (the
   diffuse sphere under the FL11 lamp, no glass on its paths' first
   bounce), `caustic` (the spectrum the prism casts on the wall) and
   `glass` (the prism itself). A third table splits the hybrids' films into
   their two parts: the light of paths that never split (the Fourier part)
   and of paths after their split (the sampled part).

Every transport runs with fspec's defaults otherwise, so `--coeffs auto`
gives the Fourier transport and the hybrid with C = 4 the same N (32 on
`prism`), and the hybrid with C = 1 or 8 N = 12 (the sizes compiled in);
the rows "fourier N=12" and "hybrid N=12 C=4" compare both transports at
that N too.

Prints Markdown tables (docs/results.md, "Hybrid transport").
"""

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys

import numpy as np

# Regions of the prism image as fractions of (width, height): x0, y0, x1, y1.
REGIONS = {
    "sphere": (0.05, 0.48, 0.30, 0.70),
    "caustic": (0.445, 0.27, 0.56, 0.66),
    "glass": (0.69, 0.35, 0.875, 0.74),
}

TRANSPORTS = {
    "fourier": ["--transport", "fourier"],
    "fourier N=12": ["--transport", "fourier", "--coeffs", "12"],
    "sampled C=4": ["--transport", "sampled", "--wavelengths", "4"],
    "sampled C=4 lights": ["--transport", "sampled", "--wavelengths", "4", "--sampling", "lights"],
    "hybrid C=1": ["--transport", "hybrid", "--wavelengths", "1"],
    "hybrid C=4": ["--transport", "hybrid", "--wavelengths", "4"],
    "hybrid N=12 C=4": ["--transport", "hybrid", "--wavelengths", "4", "--coeffs", "12"],
    "hybrid N=12 C=4 camera": ["--transport", "hybrid", "--wavelengths", "4", "--coeffs", "12",
                               "--caustics", "camera"],
    "hybrid C=4 hero": ["--transport", "hybrid", "--wavelengths", "4", "--sampling", "hero"],
    "hybrid C=8": ["--transport", "hybrid", "--wavelengths", "8"],
    "hybrid C=4 all": ["--transport", "hybrid", "--wavelengths", "4", "--dispersion-paths", "all"],
}


def cpu_seconds(command):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def render(fspec, scene, transport, side, spp, seed, out, extra=()):
    return [fspec, "render", scene, *TRANSPORTS[transport], "--width", str(side),
            "--height", str(side), "--spp", str(spp), "--seed", str(seed),
            "--quiet", *extra, "--out", out]


def cost_per_spp(fspec, out_dir, side, cases, spp, rounds=3):
    """Median CPU seconds per spp of each (scene, transport), alternated."""
    times = {case: [] for case in cases}
    png = os.path.join(out_dir, "cost.png")
    for _ in range(rounds):
        for scene, transport in cases:
            seconds = cpu_seconds(render(fspec, scene, transport, side, spp, 1, png))
            times[(scene, transport)].append(seconds / spp)
    return {case: statistics.median(v) for case, v in times.items()}


def read_xyz(path, part="both"):
    """Per-pixel XYZ of a partial film rendered with an XYZ buffer; of a
    hybrid film `part` picks the sum of both parts, the `sampled` part (the
    light of paths after their split) or the `fourier` part (the rest)."""
    with open(path, "rb") as f:
        data = f.read()
    first = data.index(b"\n")
    second = data.index(b"\n", first + 1)
    header = json.loads(data[first + 1:second])
    pixels = np.frombuffer(data[second + 1:], dtype="<f8").reshape(-1, header["values_per_pixel"])
    count, sums = pixels[:, -1:], pixels[:, :-1]
    # Hybrid: three sampled sums, then the Fourier part's three XYZ sums.
    if sums.shape[1] == 6:
        xyz = {"both": sums[:, 0:3] + sums[:, 3:6], "sampled": sums[:, 0:3],
               "fourier": sums[:, 3:6]}[part]
    else:
        xyz = sums[:, 0:3]
    return xyz / np.maximum(count, 1e-300)


def region_noise(paths, side, part="both"):
    """Mean over each region of the per-pixel a* b* standard deviation over
    the seeds' films `paths`."""
    labs = np.stack([lab(read_xyz(path, part)).reshape(side, side, 3) for path in paths])
    chroma = np.sqrt(labs[..., 1].var(axis=0, ddof=1) + labs[..., 2].var(axis=0, ddof=1))
    return [chroma[int(y0 * side):int(y1 * side), int(x0 * side):int(x1 * side)].mean()
            for (x0, y0, x1, y1) in REGIONS.values()]


def lab(xyz):
    def f(t):
        return np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
    fx, fy, fz = f(xyz[:, 0]), f(xyz[:, 1]), f(xyz[:, 2])
    return np.stack([116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)], axis=1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("fspec")
    parser.add_argument("out_dir")
    parser.add_argument("--side", type=int, default=128)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--budget-spp", type=int, default=256)
    parser.add_argument("--cost-spp", type=int, default=64)
    args = parser.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)

    cases = [("cornell", "fourier"), ("cornell", "hybrid C=4")]
    cases += [("prism", t) for t in TRANSPORTS]
    costs = cost_per_spp(args.fspec, args.out_dir, args.side, cases, args.cost_spp)
    print(f"CPU seconds per spp at {args.side}², median of 3 alternated rounds:\n")
    print("| scene | transport | CPU s / spp | ÷ Fourier |")
    print("| --- | --- | --- | --- |")
    for scene, transport in cases:
        ratio = costs[(scene, transport)] / costs[(scene, "fourier")]
        print(f"| {scene} | {transport} | {costs[(scene, transport)]:.4f} | {ratio:.3f} |")

    budget = costs[("prism", "hybrid C=4")] * args.budget_spp
    print(f"\nNoise at equal CPU time ({budget:.1f} s per render, {args.seeds} seeds), "
          "mean per-pixel sqrt(var a* + var b*):\n")
    print("| transport | spp | " + " | ".join(REGIONS) + " |")
    print("| --- | --- | " + " | ".join("---" for _ in REGIONS) + " |")
    side = args.side
    films = {}
    for transport in TRANSPORTS:
        spp = max(1, round(budget / costs[("prism", transport)]))
        paths = []
        for seed in range(args.seeds):
            path = os.path.join(args.out_dir, f"{transport.replace(' ', '_')}_{seed}.fspart")
            subprocess.run(render(args.fspec, "prism", transport, side, spp, 10 + seed, path,
                                  ["--buffer", "rgb"]),
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            paths.append(path)
        films[transport] = paths
        cells = [f"{v:.2f}" for v in region_noise(paths, side)]
        print(f"| {transport} | {spp} | " + " | ".join(cells) + " |")

    print("\nThe hybrids' two parts apart (the same films; each part's a* b* as if it were "
          "the image):\n")
    print("| transport | part | " + " | ".join(REGIONS) + " |")
    print("| --- | --- | " + " | ".join("---" for _ in REGIONS) + " |")
    for transport, paths in films.items():
        if not transport.startswith("hybrid"):
            continue
        for part in ("fourier", "sampled"):
            cells = [f"{v:.2f}" for v in region_noise(paths, side, part)]
            print(f"| {transport} | {part} | " + " | ".join(cells) + " |")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
