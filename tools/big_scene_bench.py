#!/usr/bin/env python3
"""Compare `fspec render` with Mitsuba 3.9.1's own `mitsuba` command on the
large scenes of tools/bench_scenes.py: whole-process wall time, CPU time and
peak resident memory of a full render, the same for loading alone, and the
image means of both renders (to check that both rendered the same scene).

Both renderers read the same Mitsuba scene file. Per scene, after one
unmeasured warm-up run of each renderer in each mode (file cache, Dr.Jit's
kernel cache), the runs alternate fspec, Mitsuba, fspec, Mitsuba, ...:

* full render: the file's 512 x 512 film, 64 spp, path max_depth 5;
  `fspec render SCENE --spp 64 --threads 2 --out F.exr` and
  `mitsuba -m llvm_ad_spectral -t 3 SCENE -o M.exr`;
* loading: the same commands on an 8 x 8 film at 1 spp (`--spp 1 --width 8
  --height 8` for fspec, `-D spp=1 -D res=8` for Mitsuba): parse, mesh
  loading, acceleration structure, and for Mitsuba its JIT kernel (from the
  warm kernel cache).

Each run's wall time is measured here around the process (time.perf_counter);
/usr/bin/time gives its peak resident memory and CPU time (`%M %U %S`). Mitsuba is run as the native executable
that the pip package's `mitsuba` script starts (the script only adds a
Python start-up and a second process). Its thread count is 3 by default:
`-t 1` and `-t 2` hang in Mitsuba 3.9.1 while it writes the OpenEXR output,
and 3 is Mitsuba's own default on a 2-core machine; on 2 cores both
renderers keep both cores busy. The tables report medians over --repeats
alternated pairs with min-max; bytes per triangle is (peak RSS on the scene
- peak RSS on the 36-triangle Cornell box) / triangles, so it counts what
the geometry costs beyond the fixed film and program memory (for the
instanced bunnies: per instanced triangle).

Needs: pip install mitsuba==3.9.1 numpy; Debian's libllvm19 (the LLVM
variants need libLLVM >= 17; DRJIT_LIBLLVM_PATH is set to
/usr/lib/x86_64-linux-gnu/libLLVM-19.so when unset); GNU time.
    python3 tools/bench_scenes.py
    python3 tools/big_scene_bench.py --fspec target/release/fspec
    python3 tools/big_scene_bench.py --fspec F --scenes cornell icospheres --repeats 5
    python3 tools/big_scene_bench.py --fspec F --modes load --repeats 7
"""

import argparse
import importlib.util
import json
import os
import statistics
import subprocess
import tempfile
import threading
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_SCENES = os.path.join(REPO, "target", "bench-scenes")
DEBIAN_LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
GNU_TIME = "/usr/bin/time"
KIB = 1024
MIB = 1024 * 1024
BASELINE_SCENE = "cornell"  # the tiny scene whose peak memory is the baseline
FULL_SPP = 64
LOAD_SPP = 1
LOAD_RESOLUTION = 8
RUN_TIMEOUT_S = 1800  # a run that takes longer is hung (see -t above)


def mitsuba_executable():
    """The native `mitsuba` inside the pip package (what its script runs)."""
    spec = importlib.util.find_spec("mitsuba")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit("mitsuba is not installed: pip install mitsuba==3.9.1")
    return os.path.join(spec.submodule_search_locations[0], "mitsuba")


def timed(command, cwd, log_path):
    """Run command under GNU time; return wall s, peak MiB, CPU s.

    The wall time is taken around a blocking wait: `subprocess.run` with a
    timeout polls the child with sleeps growing to 50 ms, which rounded
    every run longer than about 0.06 s up to the next poll (a quarter of a
    0.2 s load). A timer kills a hung run instead."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as report, open(
        log_path, "w", encoding="utf-8"
    ) as log:
        full = [GNU_TIME, "-f", "%M %U %S", "-o", report.name] + command
        start = time.perf_counter()
        child = subprocess.Popen(full, cwd=cwd, stdout=log, stderr=subprocess.STDOUT)
        watchdog = threading.Timer(RUN_TIMEOUT_S, child.kill)
        watchdog.start()
        try:
            returncode = child.wait()
        finally:
            watchdog.cancel()
        wall = time.perf_counter() - start
        fields = report.read().split()
    if returncode != 0:
        with open(log_path, encoding="utf-8", errors="replace") as log:
            tail = log.read()[-2000:]
        raise SystemExit(f"failed ({returncode}): {' '.join(command)}\n{tail}")
    peak_kib, user, system = (float(x) for x in fields[-3:])
    return {"wall_s": wall, "peak_mib": peak_kib * KIB / MIB, "cpu_s": user + system}


def commands(a, scene_file, mode, out_stem):
    """fspec's and Mitsuba's command lines for one mode ('full' or 'load')."""
    fspec = [a.fspec, "render", scene_file, "--threads", str(a.threads), "--quiet"]
    mitsuba = [a.mitsuba, "-m", a.variant, "-t", str(a.mitsuba_threads), scene_file]
    if mode == "full":
        fspec += ["--spp", str(FULL_SPP)]
    else:
        fspec += ["--spp", str(LOAD_SPP), "--width", str(LOAD_RESOLUTION)]
        fspec += ["--height", str(LOAD_RESOLUTION)]
        mitsuba += ["-D", f"spp={LOAD_SPP}", "-D", f"res={LOAD_RESOLUTION}"]
    fspec += ["--out", f"{out_stem}-fspec.exr"]
    mitsuba += ["-o", f"{out_stem}-mitsuba.exr"]
    return {"fspec": fspec, "mitsuba": mitsuba}


def bench_scene(a, name, info, work):
    scene_file = os.path.join(a.scene_dir, info["file"])
    cwd = os.path.dirname(scene_file)
    samples = {(mode, who): [] for mode in a.modes for who in ("fspec", "mitsuba")}
    for mode in a.modes:
        stem = os.path.join(work, f"{name}-{mode}")
        cmds = commands(a, scene_file, mode, stem)
        runs = ([] if a.no_warmup else [False]) + [True] * a.repeats
        for measured in runs:
            for who in ("fspec", "mitsuba"):  # alternated: A B A B ...
                r = timed(cmds[who], cwd, f"{stem}-{who}.log")
                if measured:
                    samples[(mode, who)].append(r)
                    print(
                        f"  {name} {mode:4} {who:7} {r['wall_s']:7.3f} s "
                        f"{r['peak_mib']:8.1f} MiB {r['cpu_s']:7.2f} CPU s",
                        flush=True,
                    )
    return samples


def median_of(runs, key):
    return statistics.median(r[key] for r in runs)


def spread(runs, key, digits):
    values = [r[key] for r in runs]
    return (
        f"{statistics.median(values):.{digits}f} "
        f"({min(values):.{digits}f}–{max(values):.{digits}f})"
    )


def image_means(work, name):
    """Mean linear RGB of both full renders, or None without mitsuba/numpy."""
    try:
        import mitsuba as mi
        import numpy as np
    except ImportError:
        return None
    mi.set_variant("scalar_rgb")
    means = {}
    for who in ("fspec", "mitsuba"):
        pixels = np.array(mi.Bitmap(os.path.join(work, f"{name}-full-{who}.exr")))
        means[who] = pixels[..., :3].reshape(-1, 3).mean(axis=0)
    return means


def report(a, manifest, results, work):
    base = results.get(BASELINE_SCENE)
    if "full" in a.modes:
        report_full(a, manifest, results, base)
    if "load" in a.modes:
        report_load(results)
    if "full" in a.modes:
        report_means(results, work)


def report_full(a, manifest, results, base):
    print(
        f"\nFull render ({FULL_SPP} spp, the file's 512 x 512 film); "
        f"median (min–max) of {a.repeats} alternated pairs\n"
    )
    print(
        "| scene | triangles | fspec s | Mitsuba s | ratio | fspec CPU s | Mitsuba CPU s "
        "| fspec peak MiB | Mitsuba peak MiB | ratio | fspec B/tri | Mitsuba B/tri |"
    )
    print("| --- |" + " ---: |" * 11)
    for name, s in results.items():
        tri = manifest[name]["triangles"]
        f, m = s[("full", "fspec")], s[("full", "mitsuba")]
        per_tri = []
        for who, runs in (("fspec", f), ("mitsuba", m)):
            if base is None or name == BASELINE_SCENE:
                per_tri.append("–")
            else:
                extra = median_of(runs, "peak_mib") - median_of(base[("full", who)], "peak_mib")
                per_tri.append(f"{extra * MIB / tri:.0f}")
        print(
            f"| {name} | {tri:,} | {spread(f, 'wall_s', 2)} | {spread(m, 'wall_s', 2)} "
            f"| {median_of(f, 'wall_s') / median_of(m, 'wall_s'):.2f} "
            f"| {median_of(f, 'cpu_s'):.1f} | {median_of(m, 'cpu_s'):.1f} "
            f"| {spread(f, 'peak_mib', 0)} | {spread(m, 'peak_mib', 0)} "
            f"| {median_of(f, 'peak_mib') / median_of(m, 'peak_mib'):.2f} "
            f"| {per_tri[0]} | {per_tri[1]} |"
        )


def report_load(results):
    print(
        f"\nLoading ({LOAD_RESOLUTION} x {LOAD_RESOLUTION} px, {LOAD_SPP} spp, whole process)\n"
    )
    print("| scene | fspec s | Mitsuba s | ratio | fspec peak MiB | Mitsuba peak MiB | ratio |")
    print("| --- |" + " ---: |" * 6)
    for name, s in results.items():
        f, m = s[("load", "fspec")], s[("load", "mitsuba")]
        print(
            f"| {name} | {spread(f, 'wall_s', 3)} | {spread(m, 'wall_s', 3)} "
            f"| {median_of(f, 'wall_s') / median_of(m, 'wall_s'):.3f} "
            f"| {median_of(f, 'peak_mib'):.0f} | {median_of(m, 'peak_mib'):.0f} "
            f"| {median_of(f, 'peak_mib') / median_of(m, 'peak_mib'):.2f} |"
        )


def report_means(results, work):
    print("\nImage means (linear sRGB, last full render of each)\n")
    print("| scene | fspec mean RGB | Mitsuba mean RGB | ratio R | ratio G | ratio B |")
    print("| --- | --- | --- | ---: | ---: | ---: |")
    for name in results:
        means = image_means(work, name)
        if means is None:
            print(f"| {name} | (needs mitsuba and numpy) | | | | |")
            continue
        f, m = means["fspec"], means["mitsuba"]
        ratio = f / m
        print(
            f"| {name} | {f[0]:.4f} {f[1]:.4f} {f[2]:.4f} | {m[0]:.4f} {m[1]:.4f} {m[2]:.4f} "
            f"| {ratio[0]:.3f} | {ratio[1]:.3f} | {ratio[2]:.3f} |"
        )


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fspec", required=True, help="the fspec binary to test")
    p.add_argument("--mitsuba", default=None, help="Mitsuba's executable (default: pip's)")
    p.add_argument("--scene-dir", default=DEFAULT_SCENES, help="tools/bench_scenes.py's --out")
    p.add_argument("--scenes", nargs="+", help="scene names (default: all in scenes.json)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--threads", type=int, default=2, help="fspec's worker threads")
    p.add_argument("--mitsuba-threads", type=int, default=3, help="Mitsuba's -t (see above)")
    p.add_argument("--variant", default="llvm_ad_spectral")
    p.add_argument("--no-warmup", action="store_true")
    p.add_argument("--work", default=None, help="folder for images and logs (default: temporary)")
    p.add_argument("--json", default=None, help="also write every run's figures here")
    p.add_argument(
        "--modes", nargs="+", choices=("full", "load"), default=["full", "load"],
        help="what to time: the full render, loading alone, or both (default)",
    )
    a = p.parse_args()
    a.fspec = os.path.abspath(a.fspec)
    a.mitsuba = os.path.abspath(a.mitsuba or mitsuba_executable())
    a.scene_dir = os.path.abspath(a.scene_dir)
    if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(DEBIAN_LLVM):
        os.environ["DRJIT_LIBLLVM_PATH"] = DEBIAN_LLVM
    with open(os.path.join(a.scene_dir, "scenes.json"), encoding="utf-8") as source:
        manifest = json.load(source)
    names = a.scenes or list(manifest)
    if BASELINE_SCENE in names:  # the baseline first, then the others in order
        names = [BASELINE_SCENE] + [n for n in names if n != BASELINE_SCENE]
    work = a.work or tempfile.mkdtemp(prefix="big-scene-bench-")
    os.makedirs(work, exist_ok=True)
    print(f"fspec {a.fspec}\nMitsuba {a.mitsuba} ({a.variant})\nimages and logs in {work}")
    results = {}
    for name in names:
        results[name] = bench_scene(a, name, manifest[name], work)
    report(a, manifest, results, work)
    if a.json:
        with open(a.json, "w", encoding="utf-8") as out:
            json.dump(
                {name: {f"{mode}/{who}": runs for (mode, who), runs in s.items()}
                 for name, s in results.items()},
                out,
                indent=2,
            )


if __name__ == "__main__":
    main()
