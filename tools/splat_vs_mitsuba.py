"""Splatting film against Mitsuba: fspec's default (splatted) film on a
Mitsuba XML scene against Mitsuba 3's render of the same file, with the
tolerance taken from measured noise.

For each seed it renders the scene with fspec (defaults: splatting, Sobol)
and with Mitsuba (`llvm_ad_spectral`), and reports the image-mean channel
ratios and the mean block ΔE2000 of `tools/mitsuba_conformance.py`
(`metrics`). The noise floor is the same metrics between two Mitsuba seeds;
fspec agrees when its ΔE against Mitsuba is within that floor plus three of
its standard deviations over the seeds, and its ratios are within 1 ± 3σ of
Mitsuba's seed-to-seed ratios. With `--old FSPEC` it also reports a second
fspec binary (a build before a film change) for comparison. Negative
control: `--fspec-args=--max-depth=2` (a wrong path length) must disagree.

Usage: python3 tools/splat_vs_mitsuba.py --fspec target/release/fspec
       [--old OTHER_FSPEC] [--scene target/bench-scenes/cornell/scene.xml]
       [--res 256] [--spp 64] [--seeds 4] [--fspec-args=...]
"""

import argparse
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import mitsuba_conformance as conformance  # noqa: E402


def fspec_image(mi, fspec, scene, res, spp, seed, out, extra):
    subprocess.run([fspec, "render", scene, "--width", str(res), "--height", str(res),
                    "--spp", str(spp), "--seed", str(seed), "--quiet", "--out", str(out),
                    *extra],
                   check=True, capture_output=True)
    return conformance.read_exr(mi, out)


def mitsuba_image(mi, scene, res, spp, seed):
    loaded = mi.load_file(scene, res=res, spp=spp)
    return np.array(mi.render(loaded, seed=seed), dtype=np.float64)[:, :, :3]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--fspec", required=True)
    parser.add_argument("--old")
    parser.add_argument("--scene", default="target/bench-scenes/cornell/scene.xml")
    parser.add_argument("--res", type=int, default=256)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--fspec-args", default="",
                        help="extra fspec render arguments, space-separated")
    args = parser.parse_args()
    import mitsuba as mi
    mi.set_variant(conformance.VARIANT)
    conformance.check_delta_e2000()
    binaries = {"fspec": args.fspec}
    if args.old:
        binaries["fspec (old)"] = args.old
    rows = {name: [] for name in [*binaries, "Mitsuba seed vs seed"]}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.seeds):
            reference = mitsuba_image(mi, args.scene, args.res, args.spp, seed)
            other = mitsuba_image(mi, args.scene, args.res, args.spp, seed + 1000)
            rows["Mitsuba seed vs seed"].append(conformance.metrics(other, reference))
            for name, binary in binaries.items():
                out = pathlib.Path(tmp) / f"{seed}.exr"
                image = fspec_image(mi, binary, args.scene, args.res, args.spp, seed, out,
                                    args.fspec_args.split())
                rows[name].append(conformance.metrics(image, reference))
    print(f"{args.scene}, {args.res}², {args.spp} spp, {args.seeds} seeds")
    print("| against Mitsuba | mean R | mean G | mean B | mean block ΔE2000 |")
    print("| --- | ---: | ---: | ---: | ---: |")
    summaries = {}
    for name, samples in rows.items():
        s = conformance.summary(samples)
        summaries[name] = s
        ratios = " | ".join(f"{m:.4f} ± {d:.4f}" for m, d in zip(s["ratio_mean"], s["ratio_sigma"]))
        print(f"| {name} | {ratios} | {s['mean_de_mean']:.3f} ± {s['mean_de_sigma']:.3f} |")
    floor = summaries["Mitsuba seed vs seed"]
    ok = True
    for name in binaries:
        s = summaries[name]
        de_bound = floor["mean_de_mean"] + 3 * max(floor["mean_de_sigma"], s["mean_de_sigma"])
        ratio_ok = all(abs(m - 1) <= 3 * max(d, fd) + 1e-3 for m, d, fd in
                       zip(s["ratio_mean"], s["ratio_sigma"], floor["ratio_sigma"]))
        agrees = s["mean_de_mean"] <= de_bound and ratio_ok
        ok &= agrees
        print(f"{name}: mean ΔE {s['mean_de_mean']:.3f} against the bound {de_bound:.3f}; "
              f"ratios {'within' if ratio_ok else 'outside'} 3σ: "
              f"{'agrees' if agrees else 'DISAGREES'}")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
