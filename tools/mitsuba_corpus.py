#!/usr/bin/env python3
"""Mitsuba 3's own scene files rendered by fspec and by Mitsuba, side by side.

The scenes of Mitsuba's data repository (github.com/mitsuba-renderer/
mitsuba-data: the documentation's example scenes and the scenes of its
test suite, with their meshes and textures) are scenes written by Mitsuba's
authors for Mitsuba, not for fspec. This script renders every one of them
with `fspec render` and with Mitsuba 3.9.1 (variant `llvm_ad_spectral`) at
the same sample count and resolution (each file's own film; the sample
count is lowered for large films so that a scene's pixels times samples
stay under `SAMPLE_BUDGET`), and reports for each scene:

* whether fspec renders it, and if not its one-line refusal (and whether
  Mitsuba 3.9.1 itself loads it: some files are for other versions or
  variants, such as the polarised ones);
* the image-mean ratio fspec / Mitsuba per channel (linear sRGB);
* the mean and largest ΔE2000 of 8 x 8-pixel block means (both images
  clipped to [0, 1] first, as the conformance suite compares them);
* `noise`: the same block ΔE2000 between two Mitsuba renders of different
  seeds, which says how much of the difference the sample count explains.

A screen, not a test: the conformance suite (cli/tests/conformance/) holds
the one-feature scenes with tolerances from measured noise. A scene whose
ratio is off by more than its noise points at a feature to check there.

    pip install mitsuba==3.9.1 numpy   # and Debian's libllvm19
    git clone https://github.com/mitsuba-renderer/mitsuba-data DATA
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        python3 tools/mitsuba_corpus.py --data DATA --fspec target/release/fspec

Writes target/mitsuba-corpus/results.json and prints a Markdown table.
"""

import argparse
import json
import pathlib
import re
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from mitsuba_conformance import delta_e2000, lab  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
VARIANT = "llvm_ad_spectral"
#: Samples per pixel unless the film is large.
DEFAULT_SPP = 64
#: Largest pixels x samples per render (a 1280 x 720 film gets 4 spp).
SAMPLE_BUDGET = 1 << 22
#: Fewest samples per pixel.
MIN_SPP = 4
#: Edge of the compared pixel blocks (the conformance suite's `BLOCK`).
BLOCK = 8
#: Values above this are clipped before ΔE2000 (a display's white).
DISPLAY_WHITE = 1.0
#: Folders of fragments that other files include (not scenes themselves).
FRAGMENT_DIRS = {"include", "fragments"}
#: Seconds before a render is given up.
TIMEOUT_S = 600


def scene_files(data, pattern):
    for path in sorted(data.rglob("*.xml")):
        relative = path.relative_to(data)
        if FRAGMENT_DIRS & set(relative.parts[:-1]):
            continue
        if pattern and not re.search(pattern, str(relative)):
            continue
        yield relative


def block_de(a, b):
    h, w, _ = a.shape
    hb, wb = max(1, h // BLOCK), max(1, w // BLOCK)
    step_h, step_w = h // hb, w // wb

    def blocks(x):
        x = np.clip(x[:hb * step_h, :wb * step_w], 0.0, DISPLAY_WHITE)
        return x.reshape(hb, step_h, wb, step_w, 3).mean(axis=(1, 3))

    de = delta_e2000(lab(blocks(a)), lab(blocks(b)))
    return float(de.mean()), float(de.max())


def image_rgb(mi, film):
    """The film's colour channels (`R, G, B`, or `name.R, …` of a nested
    integrator's image: `moment`, `aov`), as linear sRGB."""
    bitmap = film.bitmap(raw=False)
    names = [bitmap.struct_()[k].name for k in range(bitmap.channel_count())]
    data = np.array(bitmap, dtype=np.float64)
    for k, name in enumerate(names):
        prefix = name[:-1]
        if name.endswith("R") and not prefix.startswith("m2_") and names[k + 1:k + 3] == [
                prefix + "G", prefix + "B"]:
            return data[:, :, k:k + 3]
    raise RuntimeError(f"no R, G, B channels among {names}")


def mitsuba_load(mi, path, spp):
    """The scene, with `spp` given as a parameter where the file uses one."""
    try:
        return mi.load_file(str(path), spp=spp)
    except RuntimeError as err:
        if "unused parameters" not in str(err):
            raise
    return mi.load_file(str(path))


def mitsuba_render(mi, scene, spp, seed):
    import drjit as dr
    dr.eval(mi.render(scene, spp=spp, seed=seed))
    return image_rgb(mi, scene.sensors()[0].film())


def film_size(mi, scene):
    size = scene.sensors()[0].film().crop_size()
    return int(size[0]), int(size[1])


def fspec_render(fspec, data, relative, spp, out):
    start = time.perf_counter()
    run = subprocess.run(
        [str(fspec), "render", str(relative), "-D", f"spp={spp}", "--spp", str(spp),
         "--out", str(out)],
        cwd=data, capture_output=True, text=True, timeout=TIMEOUT_S)
    seconds = time.perf_counter() - start
    lines = [line for line in run.stderr.splitlines() if not line.startswith("fspec: coeff")]
    errors = [line for line in lines if "error" in line]
    warnings = [line for line in lines if "warning" in line]
    return run.returncode, (errors or lines or [""])[-1], warnings, seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=pathlib.Path, required=True,
                        help="a checkout of mitsuba-data")
    parser.add_argument("--fspec", type=pathlib.Path, default=ROOT / "target/release/fspec")
    parser.add_argument("--only", default="", help="regular expression on the scene paths")
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "target/mitsuba-corpus")
    args = parser.parse_args()

    import mitsuba as mi
    mi.set_variant(VARIANT)
    args.out.mkdir(parents=True, exist_ok=True)
    fspec = args.fspec.resolve()
    data = args.data.resolve()
    results = []
    for relative in scene_files(data, args.only):
        row = {"scene": str(relative)}
        results.append(row)
        try:
            scene = mitsuba_load(mi, data / relative, DEFAULT_SPP)
        except Exception as err:  # Mitsuba's own refusal, reported as such.
            row["mitsuba"] = str(err).splitlines()[0][:200]
            scene = None
        spp = DEFAULT_SPP
        if scene is not None:
            width, height = film_size(mi, scene)
            spp = max(MIN_SPP, min(DEFAULT_SPP, SAMPLE_BUDGET // (width * height)))
            row["film"] = [width, height]
        row["spp"] = spp
        out = args.out / (str(relative).replace("/", "__") + ".exr")
        rc, message, warnings, seconds = fspec_render(fspec, data, relative, spp, out)
        row["fspec_exit"] = rc
        row["fspec_message"] = message
        row["fspec_warnings"] = warnings
        row["fspec_seconds"] = seconds
        if rc != 0 or scene is None:
            print(f"{relative}: fspec {rc} {message} | mitsuba {row.get('mitsuba', 'ok')}",
                  flush=True)
            continue
        start = time.perf_counter()
        reference = mitsuba_render(mi, scene, spp, 0)
        row["mitsuba_seconds"] = time.perf_counter() - start
        second = mitsuba_render(mi, scene, spp, 1)
        ours = np.array(mi.Bitmap(str(out)), dtype=np.float64)[:, :, :3]
        if ours.shape != reference.shape:
            row["error"] = f"shape {ours.shape} against {reference.shape}"
            print(f"{relative}: {row['error']}", flush=True)
            continue
        means = reference.reshape(-1, 3).mean(0)
        row["ratio"] = [float(x) for x in ours.reshape(-1, 3).mean(0) / np.maximum(means, 1e-12)]
        row["mitsuba_mean"] = [float(x) for x in means]
        row["noise_ratio"] = [float(x) for x in second.reshape(-1, 3).mean(0)
                              / np.maximum(means, 1e-12)]
        row["de_mean"], row["de_max"] = block_de(ours, reference)
        row["noise_de_mean"], row["noise_de_max"] = block_de(second, reference)
        print(f"{relative}: ratio {np.round(row['ratio'], 4)} "
              f"(noise {np.round(row['noise_ratio'], 4)}) ΔE {row['de_mean']:.2f} "
              f"(noise {row['noise_de_mean']:.2f}) max {row['de_max']:.2f} "
              f"(noise {row['noise_de_max']:.2f})", flush=True)
    (args.out / "results.json").write_text(json.dumps(results, indent=1) + "\n")
    print()
    print("| scene | spp | fspec / Mitsuba R, G, B | two Mitsuba seeds | block ΔE2000 mean "
          "(two Mitsuba seeds) | max (two Mitsuba seeds) |")
    print("| --- | ---: | --- | --- | --- | --- |")
    for row in results:
        if "ratio" in row:
            ratio = " / ".join(f"{x:.3f}" for x in row["ratio"])
            noise = " / ".join(f"{x:.3f}" for x in row["noise_ratio"])
            print(f"| {row['scene']} | {row['spp']} | {ratio} | {noise} | {row['de_mean']:.2f} "
                  f"({row['noise_de_mean']:.2f}) | {row['de_max']:.2f} "
                  f"({row['noise_de_max']:.2f}) |")
    print()
    print("| scene | fspec | Mitsuba 3.9.1 |")
    print("| --- | --- | --- |")
    for row in results:
        if "ratio" not in row:
            message = row["fspec_message"].split(": error: ")[-1] if row["fspec_exit"] else "renders"
            print(f"| {row['scene']} | {message} | {row.get('mitsuba', row.get('error', 'renders'))} |")


if __name__ == "__main__":
    main()
