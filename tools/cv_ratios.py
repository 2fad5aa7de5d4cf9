#!/usr/bin/env python3
"""Control-variate / plain error ratios of `fspec experiment colorchecker`
for every built-in illuminant and the spiky lamps of data/.

    python3 tools/cv_ratios.py FSPEC_BINARY OUT_DIR [--illuminants=a,b,…] [--runs 100] [--max-samples 1024]

For each illuminant it runs the experiment and reads its CSV
(`colorchecker-<slug>.csv`; `--illuminants=` picks some, a name
ending in .csv is a file of data/: method, samples, mean ΔE2000, mean ΔE76,
standard error of the ΔE2000 mean over runs). For each strategy
(uniform, stratified, hero) it prints the ratio of the control variate's
mean ΔE2000 (8 wavelengths + 4 coefficients) to the same 8 wavelengths
without it (`<strategy>-8`, the same random numbers):

* `geo`: the geometric mean of the ratios over n >= 4 samples (the
  experiment's own claim uses the same average);
* `last`: the ratio at the largest n, with two standard errors
  (propagated from the two means' standard errors, treated as
  independent: the common random numbers make the true band narrower).

Output: a Markdown table on stdout.
"""

import csv
import math
import pathlib
import subprocess
import sys

BUILTIN = ["d65", "d50", "a", "fl2", "fl7", "fl11", "led-b1", "led-b2", "led-b3",
           "led-b4", "led-b5", "led-bh1", "led-rgb1", "led-v1", "led-v2"]
LAMPS = ["lamp_hps.csv", "lamp_lps.csv", "lamp_mercury.csv", "lamp_metal_halide.csv"]
STRATEGIES = ["uniform", "stratified", "hero"]
MIN_SAMPLES = 4


def slug(name):
    return "".join(c.lower() if c.isalnum() else "-" for c in name)


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    binary, out = args[0], pathlib.Path(args[1])
    data = pathlib.Path(__file__).resolve().parent.parent / "data"
    illuminants = BUILTIN + [str(data / lamp) for lamp in LAMPS]
    chosen = [a for a in args[2:] if a.startswith("--illuminants=")]
    extra = [a for a in args[2:] if not a.startswith("--illuminants=")]
    if chosen:
        names = chosen[-1].split("=", 1)[1].split(",")
        illuminants = [str(data / n) if n.endswith(".csv") else n for n in names]
    print("| illuminant | " + " | ".join(f"{s} geo | {s} last ± 2σ" for s in STRATEGIES) + " |")
    print("|---" * (1 + 2 * len(STRATEGIES)) + "|")
    for illuminant in illuminants:
        name = pathlib.Path(illuminant).stem if illuminant.endswith(".csv") else illuminant
        folder = out / slug(name)
        subprocess.run([binary, "experiment", "colorchecker", "--illuminant", illuminant,
                        "--out", str(folder), *extra], check=True, capture_output=True)
        rows = {}
        with open(folder / f"colorchecker-{slug(name)}.csv") as f:
            for row in csv.DictReader(f):
                rows.setdefault(row["method"], []).append(
                    (int(row["samples"]), float(row["mean_delta_e2000"]),
                     float(row["stderr_delta_e2000"])))
        cells = []
        for s in STRATEGIES:
            cv, plain = rows[f"cv-{s}"], rows[f"{s}-8"]
            logs = [math.log(a[1] / b[1]) for a, b in zip(cv, plain) if a[0] >= MIN_SAMPLES]
            geo = math.exp(sum(logs) / len(logs))
            a, b = cv[-1], plain[-1]
            ratio = a[1] / b[1]
            band = 2 * ratio * math.hypot(a[2] / a[1], b[2] / b[1])
            cells += [f"{geo:.3f}", f"{ratio:.3f} ± {band:.3f}"]
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
