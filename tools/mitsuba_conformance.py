#!/usr/bin/env python3
"""Mitsuba 3 reference images of the conformance scenes
(cli/tests/conformance/scenes/*.xml), the inputs those scenes read, and the
noise measurements behind the tolerances of cli/tests/mitsuba_conformance.rs.

Steps (all by default; `--only STEP` for one):

* `assets`: writes the files the scenes read that the project makes itself:
  textures/colours.png (4 x 4 sRGB texels), textures/grey.png (4 x 4, one
  channel), textures/normal_bumps.png (16 x 16 tangent-space normals of
  domes), spectra/led.spd (a white-LED-like emission spectrum) and
  meshes/ball.obj (a 12 x 8 UV sphere without normals). Deterministic.
* `reference`: renders every scene with Mitsuba 3.9.1, variant
  `llvm_ad_spectral`, at the scene's reference sample count (`SCENES`), in
  passes of `PASS_SPP` samples with seeds `REFERENCE_SEED + pass` averaged,
  and writes cli/tests/conformance/reference/NAME.exr (linear sRGB, RGB,
  half float: 11 significant bits, far below the noise). It also times one
  render at `TIMING_SPP` (after a first render that compiles the kernels),
  for the fspec-vs-Mitsuba time comparison, with the 1-minute load
  average of the machine at that moment (other work on it slows Mitsuba).
* `timing`: that timing alone, for every scene (on a quiet machine).
* `table`: prints the noise table of cli/tests/mitsuba_conformance.rs
  (its `conformance!` rows) from the manifest.
* `calibrate`: renders every scene with `CALIBRATION_SEEDS` seeds at
  `TEST_SPP` (the sample count of the Rust harness) and compares each with
  the reference exactly as the harness does (`Metrics`); renders each
  negative control (a `<default>` overridden, as Mitsuba's `-D`) at
  `TEST_SPP` and compares it too. Mitsuba stands in for fspec here: its
  noise at `TEST_SPP` bounds the noise part of the tolerances, and a
  negative control that Mitsuba itself cannot tell from the reference
  would not be a control.

Everything is recorded in cli/tests/conformance/reference/manifest.json
(versions, sample counts, seeds, times, the measurements).

    pip install mitsuba==3.9.1 numpy   # and Debian's libllvm19
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        nice python3 tools/mitsuba_conformance.py

About 20 minutes on 2 shared cores.
"""

import argparse
import json
import math
import os
import pathlib
import platform
import struct
import time
import zlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
SUITE = ROOT / "cli" / "tests" / "conformance"
SCENE_DIR = SUITE / "scenes"
REFERENCE_DIR = SUITE / "reference"
MANIFEST = REFERENCE_DIR / "manifest.json"

VARIANT = "llvm_ad_spectral"
#: Samples per pixel of the Rust harness's renders (`SPP` there).
TEST_SPP = 128
#: Samples per pixel of the timed render.
TIMING_SPP = 256
#: Seeds of the calibration renders: 1 ... CALIBRATION_SEEDS.
CALIBRATION_SEEDS = 8
#: Samples per pixel of one reference pass (bounds the wavefront's memory).
PASS_SPP = 1024
#: Seed of the first reference pass (calibration seeds are far below it).
REFERENCE_SEED = 1000
#: Edge of the square pixel blocks compared (`BLOCK` in the harness).
BLOCK = 8
#: Two references compared by `metrics` for the harness's check that its
#: comparison is this one (`metric_check` in the manifest).
METRIC_CHECK = ("conductor_cu", "conductor_au")

# Reference samples per pixel: 4096 = 32 x TEST_SPP for every scene (the
# whole run then fits in about 20 minutes on 2 cores). The reference's
# noise adds (TEST_SPP / ref_spp)^(1/2) = 0.18 of the test's standard
# deviation, i.e. 1.6 % to the combined one.
# `negative`: the <default> overridden for the scene's negative control.
SCENES = {
    # materials
    "diffuse_box": {"suite": "materials", "ref_spp": 4096},
    "conductor_au": {"suite": "materials", "ref_spp": 4096},
    "conductor_cu": {"suite": "materials", "ref_spp": 4096},
    "conductor_default": {"suite": "materials", "ref_spp": 4096},
    "conductor_tinted": {"suite": "materials", "ref_spp": 4096, "negative": {"blue": "0.7"}},
    "conductor_eta_k_spectra": {"suite": "materials", "ref_spp": 4096},
    "roughconductor_ggx_a010": {
        "suite": "materials", "ref_spp": 4096, "negative": {"alpha": "0.3"}},
    "roughconductor_beckmann_a030": {"suite": "materials", "ref_spp": 4096},
    "dielectric_bk7": {"suite": "materials", "ref_spp": 4096},
    "roughdielectric_ggx_a030": {
        "suite": "materials", "ref_spp": 4096, "negative": {"int_ior": "2.0"}},
    "roughdielectric_beckmann_a010": {"suite": "materials", "ref_spp": 4096},
    "thindielectric_pane": {"suite": "materials", "ref_spp": 4096},
    "plastic_linear": {"suite": "materials", "ref_spp": 4096},
    "plastic_nonlinear": {
        "suite": "materials", "ref_spp": 4096, "negative": {"nonlinear": "false"}},
    "plastic_nonlinear_textured": {
        "suite": "materials", "ref_spp": 4096, "negative": {"nonlinear": "false"}},
    "roughplastic_ggx_a010": {"suite": "materials", "ref_spp": 4096},
    "roughplastic_beckmann_a030": {"suite": "materials", "ref_spp": 4096},
    "sidedness": {"suite": "materials", "ref_spp": 4096},
    "bsdf_mask": {"suite": "materials", "ref_spp": 4096, "negative": {"alpha": "0.65"}},
    "twosided_faces": {"suite": "materials", "ref_spp": 4096, "negative": {"blue": "0.35"}},
    "bsdf_blend": {"suite": "materials", "ref_spp": 4096, "negative": {"weight": "0.7"}},
    "bsdf_normalmap": {"suite": "materials", "ref_spp": 4096, "negative": {"angle": "90"}},
    "bsdf_bumpmap": {"suite": "materials", "ref_spp": 4096, "negative": {"scale": "-0.3"}},
    "bsdf_principled": {"suite": "materials", "ref_spp": 4096, "negative": {"metallic": "0.5"}},
    "bsdf_principled_glass": {
        "suite": "materials", "ref_spp": 4096, "negative": {"eta": "1.2"}},
    "bsdf_anisotropic": {"suite": "materials", "ref_spp": 4096, "negative": {"angle": "90"}},
    "bsdf_tinted_dielectric": {
        "suite": "materials", "ref_spp": 4096, "negative": {"trans": "0.2, 0.5, 0.9"}},
    "bsdf_roughness_map": {"suite": "materials", "ref_spp": 4096, "negative": {"raw": "false"}},
    "texture_checkerboard_fractions": {
        "suite": "materials", "ref_spp": 4096, "negative": {"shift": "0.5"}},
    # lights
    "point_light": {"suite": "lights", "ref_spp": 4096, "negative": {"light_x": "1.4"}},
    "spot_light": {"suite": "lights", "ref_spp": 4096, "negative": {"beam": "12"}},
    "sphere_lights": {"suite": "lights", "ref_spp": 4096, "negative": {"radius": "0.36"}},
    "directional_light": {"suite": "lights", "ref_spp": 4096},
    "constant_env": {"suite": "lights", "ref_spp": 4096},
    "envmap_rotated": {"suite": "lights", "ref_spp": 4096, "negative": {"angle": "75"}},
    "emitter_value_forms": {"suite": "lights", "ref_spp": 4096},
    # spectra
    "spectrum_pairs": {"suite": "spectra", "ref_spp": 4096},
    "spectrum_spd_file": {"suite": "spectra", "ref_spp": 4096},
    "blackbody_point": {
        "suite": "spectra", "ref_spp": 4096, "negative": {"temperature": "2200"}},
    # textures
    "bitmap_srgb": {"suite": "textures", "ref_spp": 4096},
    "bitmap_nearest_mirror": {"suite": "textures", "ref_spp": 4096},
    "bitmap_raw_clamp": {"suite": "textures", "ref_spp": 4096},
    "checkerboard": {"suite": "textures", "ref_spp": 4096, "negative": {"uv_scale": "3.5"}},
    # shapes
    "shapes_transforms": {"suite": "shapes", "ref_spp": 4096},
    "obj_normals": {"suite": "shapes", "ref_spp": 4096},
    "ply_teapot": {"suite": "shapes", "ref_spp": 4096},
    "serialized_teapot": {"suite": "shapes", "ref_spp": 4096},
    "shape_cylinder": {"suite": "shapes", "ref_spp": 4096, "negative": {"r": "0.3"}},
    "instances": {"suite": "shapes", "ref_spp": 4096, "negative": {"angle": "40"}},
    # camera and film
    "camera_fov_axis_y": {"suite": "camera", "ref_spp": 4096, "negative": {"fov": "32"}},
    "camera_focal_length": {"suite": "camera", "ref_spp": 4096},
    "camera_thinlens": {"suite": "camera", "ref_spp": 4096, "negative": {"focus": "2.0"}},
    "camera_orthographic": {
        "suite": "camera", "ref_spp": 4096, "negative": {"scale": "1.1"}},
    "camera_clip_shift": {"suite": "camera", "ref_spp": 4096, "negative": {"near": "0.01"}},
    "filter_box": {"suite": "camera", "ref_spp": 4096},
    "filter_tent": {"suite": "camera", "ref_spp": 4096},
    "filter_gaussian": {"suite": "camera", "ref_spp": 4096, "negative": {"stddev": "0.5"}},
    # The cubic and Lanczos filters' differences stay within a pixel or two
    # of an edge, below the block comparison's resolution: their negative
    # controls are in cli/tests/mitsuba_conformance.rs's edge-profile test.
    "filter_mitchell": {"suite": "camera", "ref_spp": 4096},
    "filter_catmullrom": {"suite": "camera", "ref_spp": 4096},
    "filter_lanczos": {"suite": "camera", "ref_spp": 4096},
    "crop_window": {"suite": "camera", "ref_spp": 4096},
    # integrators
    "direct": {"suite": "integrators", "ref_spp": 4096},
    "path_max_depth_3": {
        "suite": "integrators", "ref_spp": 4096, "negative": {"max_depth": "4"}},
    "hide_emitters": {"suite": "integrators", "ref_spp": 4096},
    # format
    "defaults_params": {"suite": "format", "ref_spp": 4096, "negative": {"alpha": "0.4"}},
    "include": {"suite": "format", "ref_spp": 4096},
}


# ----------------------------------------------------------------- assets

def png_bytes(width, height, channels, rows):
    """An 8-bit PNG (colour type 0 grey or 2 RGB), no ancillary chunks."""

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    colour_type = {1: 0, 3: 2}[channels]
    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    raw = b"".join(b"\x00" + bytes(row) for row in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


#: The 4 x 4 texels of colours.png, sRGB bytes, top row first: no two
#: alike and no symmetry, so a flipped, mirrored or shifted lookup shows.
COLOURS = [
    [(230, 25, 30), (245, 130, 35), (250, 220, 40), (120, 200, 50)],
    [(30, 160, 70), (40, 200, 190), (30, 120, 220), (70, 50, 180)],
    [(150, 40, 190), (230, 60, 160), (250, 250, 250), (130, 130, 130)],
    [(20, 20, 20), (160, 110, 60), (250, 190, 170), (170, 220, 250)],
]
#: The 4 x 4 texels of grey.png (one channel), top row first.
GREYS = [
    [230, 40, 180, 90],
    [20, 140, 60, 250],
    [120, 200, 10, 160],
    [70, 100, 220, 30],
]


def led_spd():
    """A white-LED-like radiance: a blue emitter line (450 nm, 12 nm
    standard deviation) and a broad phosphor band (570 nm, 55 nm), 0 at
    380 and 780 nm, sampled every 10 nm; about as bright as the stage's
    RGB light."""
    lines = ["# White-LED-like radiance for the conformance scene spectrum_spd_file.",
             "# Written by tools/mitsuba_conformance.py: wavelength (nm), value."]
    for wavelength in range(380, 781, 10):
        blue = 3.0 * math.exp(-0.5 * ((wavelength - 450) / 12.0) ** 2)
        phosphor = 1.95 * math.exp(-0.5 * ((wavelength - 570) / 55.0) ** 2)
        edge = 0.0 if wavelength in (380, 780) else 1.0
        lines.append(f"{wavelength} {edge * (blue + phosphor):.4f}")
    return "\n".join(lines) + "\n"


def ball_obj(longitudes=12, latitudes=8, radius=0.6):
    """A UV sphere without normals or texture coordinates: shared vertices
    (one per pole), triangles wound counter-clockwise seen from outside."""
    lines = [f"# A {longitudes} x {latitudes} UV sphere of radius {radius}, no normals.",
             "# Written by tools/mitsuba_conformance.py."]
    lines.append(f"v 0 {radius} 0")
    for i in range(1, latitudes):
        theta = math.pi * i / latitudes
        for j in range(longitudes):
            phi = 2 * math.pi * j / longitudes
            x = radius * math.sin(theta) * math.cos(phi)
            y = radius * math.cos(theta)
            z = -radius * math.sin(theta) * math.sin(phi)
            lines.append(f"v {x:.6f} {y:.6f} {z:.6f}")
    lines.append(f"v 0 {-radius} 0")
    bottom = 2 + (latitudes - 1) * longitudes

    def ring(i, j):
        return 2 + (i - 1) * longitudes + j % longitudes

    for j in range(longitudes):
        lines.append(f"f 1 {ring(1, j)} {ring(1, j + 1)}")
    for i in range(1, latitudes - 1):
        for j in range(longitudes):
            a, b = ring(i, j), ring(i, j + 1)
            c, d = ring(i + 1, j + 1), ring(i + 1, j)
            lines.append(f"f {a} {d} {c}")
            lines.append(f"f {a} {c} {b}")
    for j in range(longitudes):
        lines.append(f"f {ring(latitudes - 1, j)} {bottom} {ring(latitudes - 1, j + 1)}")
    return "\n".join(lines) + "\n"


#: normal_bumps.png: texels per side, domes per side, and the domes'
#: height over their radius (the steepest tilt, at a dome's rim, is
#: atan(2 * BUMP_HEIGHT) = 50 degrees).
NORMAL_MAP_TEXELS = 16
NORMAL_MAP_DOMES = 2
BUMP_HEIGHT = 0.6


def cell_coordinates(i, j):
    """Texel (i, j)'s centre in its dome cell, x and y in [-1, 1]. Rows go
    down the image, as Mitsuba's v does (v = 0 is the top row), and the
    frame's t axis follows v."""
    cell = NORMAL_MAP_TEXELS // NORMAL_MAP_DOMES
    return (2.0 * ((i % cell) + 0.5) / cell - 1.0,
            2.0 * ((j % cell) + 0.5) / cell - 1.0)


def on_dome(x, y):
    """Whether (x, y) lies on its cell's dome: inside the unit circle and
    short of the cut on the +u side."""
    return x * x + y * y < 1.0 and x < 0.5


def normal_bumps_rows():
    """A tangent-space normal map of NORMAL_MAP_DOMES x NORMAL_MAP_DOMES
    paraboloid domes, h = BUMP_HEIGHT (1 - r^2) inside each cell's circle
    of radius 1 (r in cell units) and flat outside, as 8-bit (n + 1) / 2
    rows, top row first. The domes are cut off on the cell's +u side (a
    step in h there is left out: the texels beyond x > 0.5 are flat), so
    that a map whose u and v axes were swapped or mirrored shades
    differently."""
    rows = []
    for j in range(NORMAL_MAP_TEXELS):
        row = []
        for i in range(NORMAL_MAP_TEXELS):
            x, y = cell_coordinates(i, j)
            if on_dome(x, y):
                nx, ny = 2.0 * BUMP_HEIGHT * x, 2.0 * BUMP_HEIGHT * y
            else:
                nx, ny = 0.0, 0.0
            length = math.sqrt(nx * nx + ny * ny + 1.0)
            n = (nx / length, ny / length, 1.0 / length)
            row.extend(round(255 * (c + 1.0) / 2.0) for c in n)
        rows.append(row)
    return rows


def bump_heights_rows():
    """heights.png: NORMAL_MAP_TEXELS x NORMAL_MAP_TEXELS grey bytes, top
    row first, of the domes of normal_bumps.png as heights (1 - r^2 inside
    each cell's circle, 0 outside; cut off on the +u side, so that swapped
    or mirrored axes shade differently) over a slope along v (a tenth of
    the range across a cell)."""
    rows = []
    for j in range(NORMAL_MAP_TEXELS):
        row = []
        for i in range(NORMAL_MAP_TEXELS):
            x, y = cell_coordinates(i, j)
            dome = 1.0 - x * x - y * y if on_dome(x, y) else 0.0
            slope = 0.1 * (y + 1.0) / 2.0
            row.append(round(255 * (0.9 * dome + slope)))
        rows.append(row)
    return rows


def write_assets():
    (SCENE_DIR / "textures").mkdir(exist_ok=True)
    (SCENE_DIR / "spectra").mkdir(exist_ok=True)
    (SCENE_DIR / "meshes").mkdir(exist_ok=True)
    rgb_rows = [[c for texel in row for c in texel] for row in COLOURS]
    (SCENE_DIR / "textures" / "colours.png").write_bytes(png_bytes(4, 4, 3, rgb_rows))
    (SCENE_DIR / "textures" / "grey.png").write_bytes(png_bytes(4, 4, 1, GREYS))
    (SCENE_DIR / "textures" / "normal_bumps.png").write_bytes(
        png_bytes(NORMAL_MAP_TEXELS, NORMAL_MAP_TEXELS, 3, normal_bumps_rows()))
    (SCENE_DIR / "textures" / "heights.png").write_bytes(
        png_bytes(NORMAL_MAP_TEXELS, NORMAL_MAP_TEXELS, 1, bump_heights_rows()))
    (SCENE_DIR / "spectra" / "led.spd").write_text(led_spd())
    (SCENE_DIR / "meshes" / "ball.obj").write_text(ball_obj())


# ----------------------------------------------------------------- metrics
# The same comparison as cli/tests/mitsuba_conformance.rs: image-mean
# channel ratios, and CIEDE2000 of 8 x 8-pixel block means of the image as
# displayed (each channel clamped to [0, DISPLAY_WHITE]) in CIELAB with the
# white of linear sRGB (1, 1, 1), i.e. D65 with Y = 1.

#: Linear sRGB value shown as white (the clamp of the ΔE comparison).
DISPLAY_WHITE = 1.0

LINEAR_SRGB_TO_XYZ = np.array([
    [0.4123908, 0.3575843, 0.1804808],
    [0.2126390, 0.7151687, 0.0721923],
    [0.0193308, 0.1191948, 0.9505322],
])


def lab(rgb):
    xyz = rgb @ LINEAR_SRGB_TO_XYZ.T
    white = LINEAR_SRGB_TO_XYZ @ np.ones(3)
    t = xyz / white
    delta = 6.0 / 29.0
    f = np.where(t > delta ** 3, np.cbrt(t), t / (3 * delta ** 2) + 4.0 / 29.0)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]),
                     200 * (f[..., 1] - f[..., 2])], axis=-1)


def delta_e2000(lab1, lab2):
    """CIEDE2000 (Sharma, Wu and Dalal 2005), k_L = k_C = k_H = 1."""
    l1, a1, b1 = lab1[..., 0], lab1[..., 1], lab1[..., 2]
    l2, a2, b2 = lab2[..., 0], lab2[..., 1], lab2[..., 2]
    c_bar = 0.5 * (np.hypot(a1, b1) + np.hypot(a2, b2))
    g = 0.5 * (1 - np.sqrt(c_bar ** 7 / (c_bar ** 7 + 25.0 ** 7)))
    a1p, a2p = (1 + g) * a1, (1 + g) * a2
    c1p, c2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.degrees(np.arctan2(b1, a1p)) % 360
    h2p = np.degrees(np.arctan2(b2, a2p)) % 360
    dl = l2 - l1
    dc = c2p - c1p
    dh = h2p - h1p
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(c1p * c2p == 0, 0, dh)
    dhh = 2 * np.sqrt(c1p * c2p) * np.sin(np.radians(dh) / 2)
    l_bar = 0.5 * (l1 + l2)
    c_bar_p = 0.5 * (c1p + c2p)
    h_sum = h1p + h2p
    h_bar = np.where(np.abs(h1p - h2p) > 180,
                     np.where(h_sum < 360, h_sum + 360, h_sum - 360), h_sum) / 2
    h_bar = np.where(c1p * c2p == 0, h_sum, h_bar)
    t = (1 - 0.17 * np.cos(np.radians(h_bar - 30)) + 0.24 * np.cos(np.radians(2 * h_bar))
         + 0.32 * np.cos(np.radians(3 * h_bar + 6)) - 0.20 * np.cos(np.radians(4 * h_bar - 63)))
    d_theta = 30 * np.exp(-(((h_bar - 275) / 25) ** 2))
    r_c = 2 * np.sqrt(c_bar_p ** 7 / (c_bar_p ** 7 + 25.0 ** 7))
    s_l = 1 + 0.015 * (l_bar - 50) ** 2 / np.sqrt(20 + (l_bar - 50) ** 2)
    s_c = 1 + 0.045 * c_bar_p
    s_h = 1 + 0.015 * c_bar_p * t
    r_t = -np.sin(np.radians(2 * d_theta)) * r_c
    return np.sqrt((dl / s_l) ** 2 + (dc / s_c) ** 2 + (dhh / s_h) ** 2
                   + r_t * (dc / s_c) * (dhh / s_h))


def check_delta_e2000():
    # Pairs 1, 7 and 17 of Sharma et al.'s test data, with their ΔE00.
    pairs = [((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
             ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
             ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492)]
    for a, b, expected in pairs:
        got = float(delta_e2000(np.array(a), np.array(b)))
        if abs(got - expected) > 1e-4:
            raise AssertionError(f"ΔE2000 {a} {b}: {got}, expected {expected}")


def block_means(image):
    h, w, _ = image.shape
    return image.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, 3).mean(axis=(1, 3))


def metrics(image, reference):
    """Image-mean channel ratios and the mean and largest block ΔE2000."""
    ratios = image.reshape(-1, 3).mean(0) / reference.reshape(-1, 3).mean(0)
    displayed = [np.clip(x, 0.0, DISPLAY_WHITE) for x in (image, reference)]
    de = delta_e2000(lab(block_means(displayed[0])), lab(block_means(displayed[1])))
    return {"ratios": [float(r) for r in ratios], "mean_de": float(de.mean()),
            "max_de": float(de.max())}


def summary(samples):
    """Mean and (sample) standard deviation over seeds of each metric."""
    ratios = np.array([s["ratios"] for s in samples])
    mean_de = np.array([s["mean_de"] for s in samples])
    max_de = np.array([s["max_de"] for s in samples])
    return {
        "ratio_mean": [float(x) for x in ratios.mean(0)],
        "ratio_sigma": [float(x) for x in ratios.std(0, ddof=1)],
        "mean_de_mean": float(mean_de.mean()), "mean_de_sigma": float(mean_de.std(ddof=1)),
        "max_de_mean": float(max_de.mean()), "max_de_sigma": float(max_de.std(ddof=1)),
    }


# ----------------------------------------------------------------- rendering

def render(mi, scene, spp, seed):
    import drjit as dr
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    return np.array(image, dtype=np.float64)


# Scenes whose reference is Mitsuba's render of the whole film, cropped to
# the scene's crop window. Mitsuba renders a crop as a film of its own: a
# pixel within the filter radius of the crop's edge averages only samples
# inside the crop (measured on crop_window: the row beside the light is
# 1.47x brighter in the cropped full render than in Mitsuba's crop). fspec's
# crop gives exactly the full render's pixels (so that a frame split into
# windows reassembles bit for bit); the comparison is against those pixels.
FULL_FILM_CROPS = {"crop_window": {"x": 20, "y": 12, "width": 32, "height": 24}}


def full_film_scene(mi, name):
    """The scene file without its crop properties, loaded from beside it."""
    import re
    text = (SCENE_DIR / f"{name}.xml").read_text()
    text = re.sub(r'\s*<integer name="crop_[a-z_]+" value="[^"]*"/>', "", text)
    path = SCENE_DIR / f".{name}-full-film.xml"
    path.write_text(text)
    try:
        return mi.load_file(str(path))
    finally:
        path.unlink()


def reference_image(mi, name, spp):
    crop = FULL_FILM_CROPS.get(name)
    if crop is None:
        scene = mi.load_file(str(SCENE_DIR / f"{name}.xml"))
    else:
        scene = full_film_scene(mi, name)
    passes = max(1, spp // PASS_SPP)
    start = time.perf_counter()
    total = None
    for k in range(passes):
        image = render(mi, scene, spp // passes, REFERENCE_SEED + k)
        total = image if total is None else total + image
    seconds = time.perf_counter() - start
    if crop is not None:
        x, y = crop["x"], crop["y"]
        total = total[y:y + crop["height"], x:x + crop["width"]]
    return total / passes, seconds


def timing(mi, name):
    start = time.perf_counter()
    scene = mi.load_file(str(SCENE_DIR / f"{name}.xml"))
    load = time.perf_counter() - start
    start = time.perf_counter()
    render(mi, scene, TIMING_SPP, 1)
    cold = time.perf_counter() - start
    start = time.perf_counter()
    render(mi, scene, TIMING_SPP, 2)
    warm = time.perf_counter() - start
    return {"spp": TIMING_SPP, "load_seconds": load, "first_render_seconds": cold,
            "render_seconds": warm, "load_average": os.getloadavg()[0]}


def write_exr(mi, path, image):
    bitmap = mi.Bitmap(image.astype(np.float32), mi.Bitmap.PixelFormat.RGB)
    bitmap = bitmap.convert(component_format=mi.Struct.Type.Float16)
    bitmap.write(str(path))


def read_exr(mi, path):
    return np.array(mi.Bitmap(str(path)), dtype=np.float64)[:, :, :3]


def load_manifest():
    if MANIFEST.exists():
        return json.loads(MANIFEST.read_text())
    return {"scenes": {}}


def print_table(names):
    """The rows of `conformance!` in cli/tests/mitsuba_conformance.rs."""
    scenes = load_manifest()["scenes"]
    for name in names:
        noise = scenes[name]["noise"]
        negative = SCENES[name].get("negative")
        sigma = ", ".join(f"{s:.4f}" for s in noise["ratio_sigma"])
        row = (f"    {name + ':':<32}[{sigma}], "
               f"{noise['mean_de_mean']:.3f} ({noise['mean_de_sigma']:.3f}), "
               f"{noise['max_de_mean']:.3f} ({noise['max_de_sigma']:.3f})")
        if negative:
            (param, value), = negative.items()
            row += f'; "{param}" = "{value}"'
        print(row + ";")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only",
                        choices=["assets", "reference", "timing", "calibrate", "table"])
    parser.add_argument("--scenes", nargs="*", help="names (default: all)")
    args = parser.parse_args()
    names = args.scenes or list(SCENES)
    for name in names:
        if name not in SCENES:
            parser.error(f"unknown scene {name}")
    listed = {p.stem for p in SCENE_DIR.glob("*.xml")}
    if listed != set(SCENES):
        raise SystemExit(f"scenes on disk and in SCENES differ: {sorted(listed ^ set(SCENES))}")

    if args.only in (None, "assets"):
        write_assets()
    if args.only == "assets":
        return
    if args.only == "table":
        print_table(names)
        return
    check_delta_e2000()

    import drjit as dr
    import mitsuba as mi
    mi.set_variant(VARIANT)
    REFERENCE_DIR.mkdir(exist_ok=True)
    manifest = load_manifest()
    manifest.update({
        "mitsuba_version": mi.__version__, "drjit_version": dr.__version__,
        "variant": VARIANT, "test_spp": TEST_SPP, "pass_spp": PASS_SPP,
        "reference_seeds": f"{REFERENCE_SEED} + pass", "block_px": BLOCK,
        "calibration_seeds": list(range(1, CALIBRATION_SEEDS + 1)),
        "machine": f"{platform.machine()}, {os.cpu_count()} logical cores",
        "exr": "linear sRGB, RGB, half float",
    })
    for name in names:
        entry = manifest["scenes"].setdefault(name, {})
        entry["suite"] = SCENES[name]["suite"]
        path = REFERENCE_DIR / f"{name}.exr"
        if args.only in (None, "reference"):
            spp = SCENES[name]["ref_spp"]
            image, seconds = reference_image(mi, name, spp)
            write_exr(mi, path, image)
            h, w, _ = image.shape
            entry.update({"width": w, "height": h, "reference_spp": spp,
                          "reference_seconds": round(seconds, 2),
                          "mean_rgb": [round(float(x), 6) for x in image.reshape(-1, 3).mean(0)]})
            print(f"{name}: {spp} spp in {seconds:.1f} s, mean {entry['mean_rgb']}", flush=True)
        if args.only in (None, "reference", "timing"):
            entry["timing"] = {k: (round(v, 3) if isinstance(v, float) else v)
                               for k, v in timing(mi, name).items()}
            print(f"{name}: {entry['timing']}", flush=True)
        if args.only in (None, "calibrate"):
            reference = read_exr(mi, path)
            scene = mi.load_file(str(SCENE_DIR / f"{name}.xml"))
            samples = [metrics(render(mi, scene, TEST_SPP, seed), reference)
                       for seed in range(1, CALIBRATION_SEEDS + 1)]
            entry["noise"] = summary(samples)
            negative = SCENES[name].get("negative")
            if negative:
                wrong = mi.load_file(str(SCENE_DIR / f"{name}.xml"), **negative)
                entry["negative"] = {"override": negative,
                                     **metrics(render(mi, wrong, TEST_SPP, 1), reference)}
            noise = entry["noise"]
            print(f"{name}: noise at {TEST_SPP} spp: ratio σ "
                  f"{max(noise['ratio_sigma']):.4f}, mean ΔE {noise['mean_de_mean']:.3f} "
                  f"± {noise['mean_de_sigma']:.3f}, max ΔE {noise['max_de_mean']:.3f} "
                  f"± {noise['max_de_sigma']:.3f}"
                  + (f"; negative {entry['negative']}" if negative else ""), flush=True)
        MANIFEST.write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    if args.only in (None, "calibrate"):
        # For the harness's test that its comparison is this one.
        image, reference = METRIC_CHECK
        manifest["metric_check"] = {
            "image": image, "reference": reference,
            **metrics(read_exr(mi, REFERENCE_DIR / f"{image}.exr"),
                      read_exr(mi, REFERENCE_DIR / f"{reference}.exr"))}
        MANIFEST.write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
