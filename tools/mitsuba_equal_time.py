#!/usr/bin/env python3
"""Error at equal time, fspec against Mitsuba 3 (issue 27): renders, timings
and references that `fspec experiment equal-time` turns into its table.

The scenes (written to OUT/scenes/, one Mitsuba 3 XML file each, read by
both renderers, so both render the very same file):

* `cornell`: Mitsuba's built-in Cornell box (`mi.cornell_box()`: its
  shapes' matrices, RGB reflectances and RGB area light, camera,
  independent sampler), film 128 x 128 with Mitsuba's default Gaussian
  filter (sigma 0.5 px), path tracer with max_depth 5.
* `laser`: the same box whose light emits three triangular laser lines of
  2 nm full width at half maximum (zero at centre +- 2 nm, the lines of
  fspec's built-in `laser` scene) at 450, 532 and 638 nm, weighted so that
  the light's CIE 1931 XYZ equals the box light's: Mitsuba's own spectrum
  of the box light (its `d65` upsampling of the RGB radiance, evaluated
  every 0.5 nm over 360-830 nm) integrated against `mi.cie1931_xyz` with
  Mitsuba's normalisation `MI_CIE_Y_NORMALIZATION` gives the target XYZ;
  each line's XYZ is integrated the same way (0.01 nm steps) and the three
  weights solve the 3 x 3 system. Both renderers then see the light as the
  same colour (the `check` step measures it in both).
* `colorchecker`, `lamps`, `laser-room`: fspec's built-in scenes
  `colorchecker`, `lamps` and `laser` (the room lit by three laser lines;
  renamed here, `laser` is the box above), written by
  `tools/mitsuba_builtin_scenes.py` (its docstring: the exact
  correspondence, and the one deviation, the coated spheres) at the same
  film, filter and depth, with their meshes in OUT/scenes/meshes-SCENE/.
  Only fspec's default configuration (`auto-splat-sobol`) runs on them.

Steps (all by default; `--only STEP` for one; results accumulate in
OUT/manifest.json, images are cached and reused unless `--force`):

* `scenes`: writes the two XML files (and those of the built-in scenes
  named in `--scenes`).
* `reference`: Mitsuba, variant `llvm_ad_spectral`, at `--reference-spp`
  (per scene) in passes of `PASS_SPP` with seeds `REFERENCE_SEED + pass`;
  writes OUT/reference-SCENE.exr (their mean) and the means of the even
  and the odd passes (OUT/reference-SCENE-even.exr, -odd.exr: two
  independent halves, whose difference measures the reference's noise).
* `mitsuba`: Mitsuba at each budget (`--budgets`, spp) and seed
  (`--seeds`, 1 ... S), timed in **CPU seconds** of the process
  (`getrusage(RUSAGE_SELF)`: user + system of every thread) around
  `mi.render` until the image is in memory (`dr.eval`, `dr.sync_thread`);
  the scene's load is not counted. The first render of each budget also
  compiles Dr.Jit's kernels; a budget's time is the median over its seeds,
  which the compiling render does not move with 3 or more seeds.
* `calibrate`: each fspec configuration (`CONFIGS`) renders each scene at
  `CALIBRATION_SPP` (two sample counts, `CALIBRATION_REPEATS` times each,
  the minimum kept) as a child process timed by `getrusage(RUSAGE_CHILDREN)`
  (user + system): the slope is fspec's CPU seconds per spp, the intercept
  its fixed cost (process start, scene build, EXR write), which is not
  counted, as Mitsuba's load is not.
* `fspec`: each configuration at each budget and seed with
  `spp = round(Mitsuba's median CPU s at that budget / CPU s per spp)`
  (at least 1): the same CPU time. Its own CPU seconds (less the fixed
  cost) are recorded beside, as the check that the calibration held.
* `check`: the light's mean colour (the pixels that see it) in the
  references of both scenes, Mitsuba and fspec: the laser light must be
  the box light's colour.
* `builtin-check` (not run by default): for each built-in scene in
  `--scenes`, fspec renders the built-in itself (`fspec render NAME` at
  the XML's film, filter and depth) and the XML, `BUILTIN_CHECK_SEEDS`
  seeds of `BUILTIN_CHECK_SPP` each, default configuration; per block of
  `BLOCK_PX` x `BLOCK_PX` pixels the difference of their seed means in
  units of its standard error (from the seed-to-seed spread; the XML at
  other seeds than the built-in), the largest block difference at the same
  seeds (the same paths where the scenes agree), and the image-mean colour
  of the XML renders against Mitsuba's reference.
  Written to OUT/builtin-check.json.

Both renderers run with `--threads` threads (default 1: CPU seconds of one
thread are the least disturbed by a loaded machine; Dr.Jit's
`set_thread_count`, fspec's `--threads`).

    pip install mitsuba==3.9.1 numpy     # and Debian's libllvm19
    cargo build --release -p cli
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        nice python3 tools/mitsuba_equal_time.py --fspec target/release/fspec
    target/release/fspec experiment equal-time \\
        --manifest target/equal-time/manifest.json --out results/equal-time

About 10-15 minutes of CPU on one thread with the defaults (the references
half of it); wall time on a loaded machine several times that.
"""

import argparse
import datetime
import fcntl
import json
import os
import pathlib
import platform
import resource
import statistics
import subprocess
import sys

import numpy as np

import mitsuba_builtin_scenes

ROOT = pathlib.Path(__file__).resolve().parent.parent
VARIANT = "llvm_ad_spectral"
#: Film side, pixels (the issue's 128 x 128).
SIZE_PX = 128
#: Longest path, segments (Mitsuba's max_depth; the issue's 5).
MAX_DEPTH = 5
#: Samples per pixel of one Mitsuba pass (bounds the wavefront's memory:
#: 128^2 x 1024 lanes).
PASS_SPP = 1024
#: Seed of the first reference pass (budget renders use seeds 1 ... S).
REFERENCE_SEED = 1000
#: Laser lines: centres, nm, and the half base of each triangle, nm (2 nm
#: full width at half maximum, as fspec's built-in `laser` scene).
LASER_CENTRES_NM = (450.0, 532.0, 638.0)
LASER_HALF_BASE_NM = 2.0
#: The visible range of Mitsuba's spectral variants, nm (MI_CIE_MIN/MAX).
CIE_RANGE_NM = (360.0, 830.0)
#: fspec configurations: name -> (render arguments, scenes it runs on).
#: `--sampler independent` where the configuration was measured before the
#: Sobol sampler existed (and became the default).
CONFIGS = {
    "fourier12-sample": (["--coeffs", "12", "--film", "sample", "--sampler", "independent"],
                         ("cornell", "laser")),
    "fourier12-splat": (["--coeffs", "12", "--film", "splat", "--sampler", "independent"],
                        ("cornell", "laser")),
    "fourier12-splat-sobol": (["--coeffs", "12", "--film", "splat", "--sampler", "sobol"],
                              ("cornell", "laser")),
    "fourier16-splat": (["--coeffs", "16", "--film", "splat", "--sampler", "independent"],
                        ("laser",)),
    "fourier24-splat": (["--coeffs", "24", "--film", "splat", "--sampler", "independent"],
                        ("laser",)),
    # fspec's --coeffs auto (N chosen from the scene's spectra), measured
    # with the independent sampler; with sobol it is fspec's defaults.
    "auto-splat": (["--coeffs", "auto", "--film", "splat", "--sampler", "independent"],
                   ("cornell", "laser")),
    "auto-splat-sobol": (["--coeffs", "auto", "--film", "splat", "--sampler", "sobol"],
                         ("cornell", "laser", "colorchecker", "lamps", "laser-room")),
    "hero4-splat": (
        ["--transport", "sampled", "--wavelengths", "4", "--sampling", "hero",
         "--film", "splat", "--sampler", "independent"],
        ("cornell",),
    ),
}
#: Sample counts of the calibration renders.
CALIBRATION_SPP = (16, 256)
#: Repeats of each calibration render (the minimum is kept).
CALIBRATION_REPEATS = 2
#: Default reference spp per scene: the laser box converges slowly in
#: Mitsuba (its wavelengths are not drawn from the light's spectrum), and so
#: does the laser room (the same kind of light; at 32768 spp its reference
#: noise, 0.38 ΔE2000, is still a tenth of Mitsuba's 256-spp error). The
#: other built-ins: 16384 spp, about 1 CPU minute for the colorchecker's
#: 1024-spp passes of 4 CPU s, 7 for the lamps' of 25 CPU s.
REFERENCE_SPP = {"cornell": 8192, "laser": 16384, "colorchecker": 16384, "lamps": 16384,
                 "laser-room": 32768}
#: The built-in scenes: name here -> name of fspec's built-in scene.
BUILTIN_SCENES = {"colorchecker": "colorchecker", "lamps": "lamps", "laser-room": "laser"}
#: `builtin-check`: seeds and spp of each render (fspec's default
#: configuration), and the side of the compared blocks, pixels.
BUILTIN_CHECK_SEEDS = 5
BUILTIN_CHECK_SPP = 256
BLOCK_PX = 16
#: `builtin-check`: the block differences counted, in standard errors.
CHECK_SIGMAS = (3, 5)
#: `builtin-check`: floors of a standard error and of a block's value when
#: dividing by them (black blocks: the colorchecker's backdrop).
CHECK_TINY = 1e-12
CHECK_BLACK = 1e-3

SCENE_TEMPLATE = """<?xml version="1.0" encoding="utf-8"?>
<!-- {title}
     Written by tools/mitsuba_equal_time.py from mi.cornell_box() (Mitsuba
     {mitsuba_version}); read by Mitsuba and by fspec. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <integrator type="path">
        <integer name="max_depth" value="{max_depth}"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="39.3077"/>
        <string name="fov_axis" value="smaller"/>
        <transform name="to_world">
            <lookat origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="{size}"/>
            <integer name="height" value="{size}"/>
            <rfilter type="gaussian"/>
        </film>
    </sensor>
{bsdfs}
{shapes}
</scene>
"""


def cpu_self():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def mitsuba(threads):
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(VARIANT)
    dr.set_thread_count(threads)
    return mi, dr


def light_xyz(mi, dr, rgb):
    """XYZ of Mitsuba's spectrum of an RGB area light (its `d65` texture)."""
    texture = mi.load_dict({"type": "d65", "color": rgb})
    step_nm = 0.5
    lambda_nm = np.arange(CIE_RANGE_NM[0], CIE_RANGE_NM[1] + step_nm / 2, step_nm)
    si = dr.zeros(mi.SurfaceInteraction3f, len(lambda_nm))
    lam = mi.Float(lambda_nm)
    si.wavelengths = mi.Spectrum(lam, lam, lam, lam)
    values = np.array(texture.eval(si)[0])
    return (values[:, None] * cmf_table(mi, lambda_nm)).sum(axis=0) * step_nm \
        * mi.MI_CIE_Y_NORMALIZATION


def cmf_table(mi, lambda_nm):
    """Mitsuba's CIE 1931 colour matching functions at `lambda_nm`, (n, 3)."""
    return np.array(mi.cie1931_xyz(mi.Float(lambda_nm))).T


def laser_weights(mi, target_xyz):
    """Peak values of the three triangular lines whose sum has `target_xyz`."""
    step_nm = 0.01
    columns = []
    for c in LASER_CENTRES_NM:
        lam = np.arange(c - LASER_HALF_BASE_NM, c + LASER_HALF_BASE_NM + step_nm / 2, step_nm)
        tri = 1.0 - np.abs(lam - c) / LASER_HALF_BASE_NM
        columns.append((tri[:, None] * cmf_table(mi, lam)).sum(axis=0) * step_nm * mi.MI_CIE_Y_NORMALIZATION)
    weights = np.linalg.solve(np.array(columns).T, target_xyz)
    if not np.all(weights > 0):
        raise SystemExit(f"laser weights not all positive: {weights}")
    return weights


def matrix_text(transform):
    m = np.array(transform.matrix)
    return ", ".join(f"{v:.9g}" for v in m.reshape(-1))


def write_scenes(out, threads):
    mi, dr = mitsuba(threads)
    d = mi.cornell_box()
    bsdfs = []
    for name in ("white", "red", "green"):
        rgb = ", ".join(f"{v:.9g}" for v in d[name]["reflectance"]["value"])
        bsdfs.append(
            f'    <bsdf type="diffuse" id="{name}">\n'
            f'        <rgb name="reflectance" value="{rgb}"/>\n    </bsdf>'
        )
    light_rgb = list(d["light"]["emitter"]["radiance"]["value"])
    xyz = light_xyz(mi, dr, light_rgb)
    weights = laser_weights(mi, xyz)
    points = [(CIE_RANGE_NM[0], 0.0)]
    for c, w in zip(LASER_CENTRES_NM, weights):
        points += [(c - LASER_HALF_BASE_NM, 0.0), (c, w), (c + LASER_HALF_BASE_NM, 0.0)]
    points.append((CIE_RANGE_NM[1], 0.0))
    emitters = {
        "cornell": '<rgb name="radiance" value="{}"/>'.format(
            ", ".join(f"{v:.9g}" for v in light_rgb)),
        "laser": '<spectrum name="radiance" value="{}"/>'.format(
            ", ".join(f"{l:g}:{v:.9g}" for l, v in points)),
    }
    titles = {
        "cornell": "Mitsuba's Cornell box, 128 x 128, max_depth 5, Gaussian filter.",
        "laser": "The same box lit by three 2 nm laser lines (450, 532, 638 nm) "
                 f"of the box light's XYZ {', '.join(f'{v:.6g}' for v in xyz)}.",
    }
    paths = {}
    (out / "scenes").mkdir(parents=True, exist_ok=True)
    for scene, emitter in emitters.items():
        shapes = []
        for name in ("floor", "ceiling", "back", "green-wall", "red-wall",
                     "small-box", "large-box", "light"):
            s = d[name]
            inner = f'        <ref id="{s["bsdf"]["id"]}"/>'
            if name == "light":
                inner += f'\n        <emitter type="area">\n            {emitter}\n        </emitter>'
            shapes.append(
                f'    <shape type="{s["type"]}" id="{name}">\n'
                f'        <transform name="to_world">\n'
                f'            <matrix value="{matrix_text(s["to_world"])}"/>\n'
                f'        </transform>\n{inner}\n    </shape>'
            )
        text = SCENE_TEMPLATE.format(
            title=titles[scene], mitsuba_version=mi.MI_VERSION, max_depth=MAX_DEPTH,
            size=SIZE_PX, bsdfs="\n".join(bsdfs), shapes="\n".join(shapes))
        path = out / "scenes" / f"{scene}.xml"
        path.write_text(text)
        paths[scene] = str(path.relative_to(out))
    return {"scenes": paths, "light_xyz": list(map(float, xyz)),
            "laser_peaks": list(map(float, weights)),
            "laser_centres_nm": list(LASER_CENTRES_NM)}


def write_builtin_scenes(out, names):
    """The XML files of the built-in scenes among `names`."""
    paths = {}
    for name in names:
        if name in BUILTIN_SCENES:
            path = mitsuba_builtin_scenes.write_scene(BUILTIN_SCENES[name], out / "scenes",
                                                      SIZE_PX, MAX_DEPTH, stem=name)
            paths[name] = str(path.relative_to(out))
    return {"scenes": paths} if paths else {}


def write_exr(mi, dr, path, rgb):
    """Writes a float32 RGB EXR. With one Dr.Jit thread Mitsuba 3.9.1's
    `Bitmap.write` never returns (its EXR writer waits on the thread pool),
    so the pool has two threads while it writes."""
    threads = dr.thread_count()
    dr.set_thread_count(max(threads, 2))
    bmp = mi.Bitmap(rgb.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.write(str(path))
    dr.set_thread_count(threads)


def read_exr(mi, dr, path):
    threads = dr.thread_count()
    dr.set_thread_count(max(threads, 2))
    rgb = np.array(mi.Bitmap(str(path)), dtype=np.float64)[:, :, :3]
    dr.set_thread_count(threads)
    return rgb


def render_mitsuba(mi, dr, scene, spp, seed):
    """One render; returns (image, CPU seconds)."""
    start = cpu_self()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    return np.array(img, dtype=np.float64)[:, :, :3], cpu_self() - start


def reference(out, manifest, scenes, ref_spp, threads, force):
    mi, dr = mitsuba(threads)
    refs = manifest.setdefault("references", {})
    for name in scenes:
        spp = ref_spp.get(name, REFERENCE_SPP[name])
        path = out / f"reference-{name}.exr"
        known = refs.get(name)
        if not force and path.exists() and known and known["spp"] == spp:
            print(f"reference {name}: cached")
            continue
        scene = mi.load_file(str(out / manifest["scenes"][name]))
        pass_spp = min(PASS_SPP, spp // 2)
        passes = spp // pass_spp
        if passes < 2 or passes % 2:
            raise SystemExit(f"--reference-spp {spp}: an even number of passes of {pass_spp}")
        halves = [np.zeros((SIZE_PX, SIZE_PX, 3)), np.zeros((SIZE_PX, SIZE_PX, 3))]
        cpu = 0.0
        for i in range(passes):
            img, seconds = render_mitsuba(mi, dr, scene, pass_spp, REFERENCE_SEED + i)
            halves[i % 2] += img
            cpu += seconds
            print(f"reference {name}: pass {i + 1}/{passes} ({seconds:.1f} CPU s)", flush=True)
        for h in halves:
            h /= passes // 2
        write_exr(mi, dr, path, (halves[0] + halves[1]) / 2)
        write_exr(mi, dr, out / f"reference-{name}-even.exr", halves[0])
        write_exr(mi, dr, out / f"reference-{name}-odd.exr", halves[1])
        refs[name] = {"image": path.name, "even": f"reference-{name}-even.exr",
                      "odd": f"reference-{name}-odd.exr", "spp": spp,
                      "seeds": [REFERENCE_SEED, REFERENCE_SEED + passes - 1],
                      "cpu_s": cpu}
        save(out, manifest, ["references"])


def budget_renders(out, manifest, scenes, budgets, seeds, threads, force):
    mi, dr = mitsuba(threads)
    runs = manifest.setdefault("mitsuba", [])
    (out / "mitsuba").mkdir(exist_ok=True)
    for name in scenes:
        scene = mi.load_file(str(out / manifest["scenes"][name]))
        for spp in budgets:
            for seed in range(1, seeds + 1):
                image = pathlib.Path("mitsuba") / f"{name}-{spp}spp-seed{seed}.exr"
                if not force and find(runs, name, spp, seed) and (out / image).exists():
                    continue
                img, seconds = render_mitsuba(mi, dr, scene, spp, seed)
                write_exr(mi, dr, out / image, img)
                replace(runs, {"scene": name, "budget_spp": spp, "seed": seed,
                               "spp": spp, "cpu_s": seconds, "image": str(image)})
                print(f"mitsuba {name} {spp} spp seed {seed}: {seconds:.2f} CPU s", flush=True)
                save(out, manifest, ["mitsuba"])


def find(runs, scene, budget, seed, config=None):
    return next((r for r in runs if r["scene"] == scene and r["budget_spp"] == budget
                 and r["seed"] == seed and r.get("config") == config), None)


def replace(runs, row):
    old = find(runs, row["scene"], row["budget_spp"], row["seed"], row.get("config"))
    if old:
        runs.remove(old)
    runs.append(row)


def run_fspec(fspec, scene_path, args, spp, seed, threads, image):
    """One fspec render as a child process; returns its CPU seconds."""
    command = [fspec, "render", str(scene_path), "--spp", str(spp), "--seed", str(seed),
               "--threads", str(threads), "--quiet", *args, "--out", str(image)]
    start = cpu_children()
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)}: {done.stderr.strip()}")
    return cpu_children() - start


def calibrate(out, manifest, scenes, fspec, threads, force, configs):
    cal = manifest.setdefault("calibration", {})
    tmp = out / "calibration.exr"
    for config, (args, on) in CONFIGS.items():
        for name in scenes:
            if name not in on or config not in configs:
                continue
            key = f"{name}/{config}"
            if not force and key in cal:
                continue
            seconds = []
            for spp in CALIBRATION_SPP:
                best = min(run_fspec(fspec, out / manifest["scenes"][name], args, spp, 1,
                                     threads, tmp) for _ in range(CALIBRATION_REPEATS))
                seconds.append(best)
            (a, b), (ta, tb) = CALIBRATION_SPP, seconds
            per_spp = (tb - ta) / (b - a)
            if not per_spp > 0:
                raise SystemExit(f"calibration of {key}: CPU time did not grow with spp")
            cal[key] = {"cpu_s_per_spp": per_spp, "fixed_cpu_s": max(ta - a * per_spp, 0.0),
                        "spp": list(CALIBRATION_SPP), "cpu_s": seconds}
            print(f"calibrated {key}: {per_spp * 1000:.2f} CPU ms per spp, "
                  f"fixed {cal[key]['fixed_cpu_s']:.2f} CPU s", flush=True)
            save(out, manifest, ["calibration"])
    tmp.unlink(missing_ok=True)


def fspec_renders(out, manifest, scenes, budgets, seeds, fspec, threads, force, configs):
    runs = manifest.setdefault("fspec", [])
    (out / "fspec").mkdir(exist_ok=True)
    for config, (args, on) in CONFIGS.items():
        for name in scenes:
            if name not in on or config not in configs:
                continue
            cal = manifest["calibration"][f"{name}/{config}"]
            for budget in budgets:
                times = [r["cpu_s"] for r in manifest["mitsuba"]
                         if r["scene"] == name and r["budget_spp"] == budget]
                if not times:
                    raise SystemExit(f"no Mitsuba timing of {name} at {budget} spp: run --only mitsuba")
                spp = max(1, round(statistics.median(times) / cal["cpu_s_per_spp"]))
                for seed in range(1, seeds + 1):
                    image = pathlib.Path("fspec") / f"{name}-{config}-b{budget}-seed{seed}.exr"
                    old = find(runs, name, budget, seed, config)
                    if not force and old and old["spp"] == spp and (out / image).exists():
                        continue
                    total = run_fspec(fspec, out / manifest["scenes"][name], args, spp, seed,
                                      threads, out / image)
                    replace(runs, {"scene": name, "config": config, "budget_spp": budget,
                                   "seed": seed, "spp": spp,
                                   "cpu_s": max(total - cal["fixed_cpu_s"], 0.0),
                                   "image": str(image)})
                    print(f"fspec {config} {name} budget {budget}: {spp} spp seed {seed}, "
                          f"{total:.2f} CPU s", flush=True)
                    save(out, manifest, ["fspec"])


def check(out, manifest, fspec, threads):
    """Mean colour of the light's pixels (luminance above the walls')."""
    mi, dr = mitsuba(threads)
    for name in manifest.get("references", {}):
        img = read_exr(mi, dr, out / manifest["references"][name]["image"])
        light = img.sum(axis=2) > 3 * 3.0
        tmp = out / f"check-{name}.exr"
        run_fspec(fspec, out / manifest["scenes"][name], [], 256, 1, threads, tmp)
        ours = read_exr(mi, dr, tmp)
        print(f"{name}: light pixels {light.sum()}, Mitsuba RGB {img[light].mean(axis=0)}, "
              f"fspec RGB {ours[light].mean(axis=0)}")
        tmp.unlink()


def block_means(img):
    """Mean RGB of each BLOCK_PX x BLOCK_PX block, (rows, columns, 3)."""
    h, w, _ = img.shape
    return img.reshape(h // BLOCK_PX, BLOCK_PX, w // BLOCK_PX, BLOCK_PX, 3).mean(axis=(1, 3))


def builtin_check(out, manifest, scenes, fspec, threads):
    """fspec's built-in scene against its XML (both in fspec), and the XML
    in fspec against Mitsuba's reference (image means)."""
    mi, dr = mitsuba(threads)
    args = CONFIGS["auto-splat-sobol"][0]
    film = ["--width", str(SIZE_PX), "--height", str(SIZE_PX), "--max-depth", str(MAX_DEPTH),
            "--filter", "gaussian"]
    tmp = out / "builtin-check.exr"
    results = {}
    seeds = range(1, BUILTIN_CHECK_SEEDS + 1)
    for name in scenes:
        if name not in BUILTIN_SCENES:
            continue
        # The built-in at seeds 1 ... S; the XML at the same seeds (the same
        # paths wherever the two scenes agree) and at seeds S + 1 ... 2S
        # (independent noise, for the test in standard errors).
        renders = (("builtin", BUILTIN_SCENES[name], film, 0),
                   ("xml-same-seeds", out / manifest["scenes"][name], [], 0),
                   ("xml", out / manifest["scenes"][name], [], BUILTIN_CHECK_SEEDS))
        images = {}
        for kind, source, extra, offset in renders:
            images[kind] = []
            for seed in seeds:
                run_fspec(fspec, source, args + extra, BUILTIN_CHECK_SPP, seed + offset, threads,
                          tmp)
                images[kind].append(read_exr(mi, dr, tmp))
        blocks = {k: np.array([block_means(i) for i in v]) for k, v in images.items()}
        b, x = blocks["builtin"], blocks["xml"]
        diff = b.mean(axis=0) - x.mean(axis=0)
        # Standard error of the difference of two means of S seeds each.
        se = np.sqrt((b.var(axis=0, ddof=1) + x.var(axis=0, ddof=1)) / BUILTIN_CHECK_SEEDS)
        z = np.abs(diff) / np.maximum(se, CHECK_TINY)
        over = z > CHECK_SIGMAS[0]
        paired = np.abs(b.mean(axis=0) - blocks["xml-same-seeds"].mean(axis=0))
        scale = np.maximum(np.abs(b.mean(axis=0)), CHECK_BLACK)
        row = {"blocks": int(z[..., 0].size), "block_px": BLOCK_PX,
               "max_z": float(z.max()), "mean_abs_z": float(z.mean()),
               **{f"blocks_over_{k}_sigma": int((z > k).any(axis=2).sum())
                  for k in CHECK_SIGMAS},
               f"blocks_over_{CHECK_SIGMAS[0]}_sigma_row_col": [
                   [int(r), int(c)] for r, c in zip(*np.nonzero(over.any(axis=2)))],
               "worst_block_row_col_channel": [int(v) for v in np.unravel_index(z.argmax(),
                                                                                z.shape)],
               "same_seeds_max_rel_block_diff": float((paired / scale).max()),
               "same_seeds_max_abs_block_diff": float(paired.max()),
               "builtin_mean_rgb": images_mean(images["builtin"]),
               "xml_mean_rgb": images_mean(images["xml"]),
               "spp": BUILTIN_CHECK_SPP, "seeds": BUILTIN_CHECK_SEEDS}
        ref = manifest.get("references", {}).get(name)
        if ref:
            row["mitsuba_reference_mean_rgb"] = list(
                map(float, read_exr(mi, dr, out / ref["image"]).mean(axis=(0, 1))))
            row["xml_over_mitsuba"] = [a / b for a, b in zip(row["xml_mean_rgb"],
                                                             row["mitsuba_reference_mean_rgb"])]
        results[name] = row
        print(name, json.dumps(row), flush=True)
    tmp.unlink(missing_ok=True)
    path = out / "builtin-check.json"
    old = json.loads(path.read_text()) if path.exists() else {}
    path.write_text(json.dumps({**old, **results}, indent=1) + "\n")


def images_mean(images):
    return list(map(float, np.mean([i.mean(axis=(0, 1)) for i in images], axis=0)))


def save(out, manifest, keys):
    """Writes `keys` of `manifest` into OUT/manifest.json, keeping the other
    keys on disk: steps run as separate processes at the same time (each
    owns its key) without losing each other's rows."""
    path = out / "manifest.json"
    with open(out / "manifest.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        disk = load(out)
        for k in keys:
            if k not in manifest:
                continue
            if isinstance(manifest[k], list) and all(isinstance(r, dict) for r in manifest[k]):
                # Render rows: the disk's, each replaced by ours of the same
                # scene, config, budget and seed (two processes may render
                # different configurations at once).
                rows = list(disk.get(k, []))
                for row in manifest[k]:
                    replace(rows, row)
                disk[k] = rows
            elif isinstance(manifest[k], dict):
                disk[k] = {**disk.get(k, {}), **manifest[k]}
            else:
                disk[k] = manifest[k]
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(disk, indent=1) + "\n")
        os.replace(tmp, path)


def load(out):
    path = out / "manifest.json"
    return json.loads(path.read_text()) if path.exists() else {}


def machine():
    model = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "target" / "equal-time")
    p.add_argument("--fspec", default=str(ROOT / "target" / "release" / "fspec"))
    p.add_argument("--only", choices=["scenes", "reference", "mitsuba", "calibrate",
                                      "fspec", "check", "builtin-check"])
    p.add_argument("--scenes", nargs="+", default=["cornell", "laser"],
                   choices=["cornell", "laser", *BUILTIN_SCENES])
    p.add_argument("--budgets", type=int, nargs="+", default=[64, 256, 1024])
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--configs", nargs="+", default=list(CONFIGS), choices=list(CONFIGS),
                   help="fspec configurations calibrated and rendered (default: all)")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--reference-spp", nargs="*", default=[], metavar="SCENE=SPP",
                   help="reference spp per scene (default: " + " ".join(
                       f"{k}={v}" for k, v in REFERENCE_SPP.items()) + ")")
    p.add_argument("--force", action="store_true")
    a = p.parse_args()
    ref_spp = {}
    for item in a.reference_spp:
        name, _, spp = item.partition("=")
        ref_spp[name] = int(spp)
    a.out.mkdir(parents=True, exist_ok=True)
    manifest = load(a.out)
    import mitsuba as mi

    meta = {
        "format": "fspec-equal-time-v1",
        "machine": machine(),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "mitsuba_version": mi.MI_VERSION,
        "mitsuba_variant": VARIANT,
        "threads": a.threads,
        "time": "CPU seconds (user + system) of the renderer at the thread count above; "
                "fspec: calibrated CPU seconds per spp, fixed cost excluded",
    }
    manifest.update(meta)
    save(a.out, manifest, list(meta))
    step = lambda s: a.only in (None, s)  # noqa: E731
    if step("scenes") or "scenes" not in manifest:
        scenes = write_scenes(a.out, a.threads)
        manifest.update(scenes)
        save(a.out, manifest, list(scenes))
    if step("scenes") or any(s not in manifest["scenes"] for s in a.scenes):
        builtins = write_builtin_scenes(a.out, a.scenes)
        if builtins:
            manifest["scenes"].update(builtins["scenes"])
            save(a.out, manifest, ["scenes"])
    if step("reference"):
        reference(a.out, manifest, a.scenes, ref_spp, a.threads, a.force)
    if step("mitsuba"):
        budget_renders(a.out, manifest, a.scenes, a.budgets, a.seeds, a.threads, a.force)
    if step("calibrate"):
        calibrate(a.out, manifest, a.scenes, a.fspec, a.threads, a.force, a.configs)
    if step("fspec"):
        fspec_renders(a.out, manifest, a.scenes, a.budgets, a.seeds, a.fspec, a.threads, a.force,
                      a.configs)
    if a.only == "check":
        check(a.out, manifest, a.fspec, a.threads)
    if a.only == "builtin-check":
        builtin_check(a.out, manifest, a.scenes, a.fspec, a.threads)


if __name__ == "__main__":
    sys.exit(main())
