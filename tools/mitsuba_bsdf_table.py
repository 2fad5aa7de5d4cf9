#!/usr/bin/env python3
"""Tabulates Mitsuba 3.9.1's own BSDF evaluations for a few plastic,
rough plastic, rough conductor and rough dielectric configurations, so
that `simd-tracer/tests/mitsuba_bsdf.rs` can compare ours with them point
by point.

Every reflectance is a grey constant (and every index a constant), so the
colour pipeline plays no part: variant `scalar_rgb`, and the three channels
of each value are equal (the script checks that).

Directions are in the local shading frame (normal +z). The camera
direction (Mitsuba's `si.wi`, our `wo`) lies in the xz-plane at polar
angle `theta_camera_deg` (on the -z side for a camera inside a
dielectric); the light direction (Mitsuba's `wo`, our `wi`) has polar angle
`theta_light_deg` and azimuth `phi_deg` from the camera's half plane.

Outputs (into --out, default simd-tracer/tests/data):

* `mitsuba_bsdf_configs.csv`: one row per configuration (the Mitsuba
  plugin and its parameters);
* `mitsuba_bsdf_eval.csv`: per configuration and direction pair,
  `value` = `bsdf.eval` (f times the light's |cos|, Radiance mode),
  `pdf` = `bsdf.pdf`, and for the plastics `diffuse` = `bsdf.eval` with
  only the diffuse component enabled;
* `mitsuba_bsdf_delta.csv`: the smooth plastics' delta lobe per camera
  angle: `reflectance` (the sampled weight times the lobe probability, i.e.
  the specular reflectance times F) and `probability` (Mitsuba's chance of
  sampling the delta lobe);
Anisotropic configurations (`ALPHA_V`) give `alpha_u` (along the frame's
`s`, +x, as `Frame3f((0, 0, 1))` builds it) and `alpha_v`. Tinted rough
dielectrics (`TRANSMITTANCE`) give `specular` as their
`specular_reflectance` and `transmittance` as their
`specular_transmittance`.

* `mitsuba_principled_configs.csv` and `mitsuba_principled_eval.csv`: the
  same for the `principled` BSDF (grey `base_color` 0.5, whose luminance in
  `scalar_rgb` is 0.5, so the tints are white), `value` and `pdf` per
  direction pair.

    pip install mitsuba==3.9.1
    python3 tools/mitsuba_bsdf_table.py
"""

import argparse
import csv
import math
import pathlib

import mitsuba as mi

mi.set_variant("scalar_rgb")

# Polar angles of both directions (degrees) and light azimuths.
THETAS_DEG = [0.0, 20.0, 40.0, 60.0, 75.0, 85.0]
PHIS_DEG = [0.0, 45.0, 90.0, 135.0, 180.0]

GREY = 0.5
IOR = 1.5
CONDUCTOR_ETA, CONDUCTOR_K = 0.2, 3.0

# name, plugin, distribution, alpha, diffuse, specular, nonlinear,
# camera side, light side (+1 above the surface, -1 below).
CONFIGS = [
    ("plastic_linear", "plastic", "", 0.0, GREY, 1.0, False, 1, 1),
    ("plastic_nonlinear", "plastic", "", 0.0, 0.8, 1.0, True, 1, 1),
    ("plastic_specular_0.6", "plastic", "", 0.0, GREY, 0.6, False, 1, 1),
    ("roughplastic_ggx_0.1", "roughplastic", "ggx", 0.1, GREY, 1.0, False, 1, 1),
    ("roughplastic_ggx_0.3", "roughplastic", "ggx", 0.3, GREY, 1.0, False, 1, 1),
    ("roughplastic_beckmann_0.1", "roughplastic", "beckmann", 0.1, GREY, 1.0, False, 1, 1),
    ("roughplastic_beckmann_0.3", "roughplastic", "beckmann", 0.3, GREY, 1.0, False, 1, 1),
    ("roughplastic_beckmann_0.3_nonlinear_specular_0.6", "roughplastic", "beckmann", 0.3,
     0.8, 0.6, True, 1, 1),
    ("roughconductor_ggx_0.1", "roughconductor", "ggx", 0.1, 0.0, 1.0, False, 1, 1),
    ("roughconductor_ggx_0.3", "roughconductor", "ggx", 0.3, 0.0, 1.0, False, 1, 1),
    ("roughconductor_beckmann_0.1", "roughconductor", "beckmann", 0.1, 0.0, 1.0, False, 1, 1),
    ("roughconductor_beckmann_0.3", "roughconductor", "beckmann", 0.3, 0.0, 1.0, False, 1, 1),
]
for distribution in ("ggx", "beckmann"):
    for camera, light, what in ((1, 1, "reflect_outside"), (1, -1, "transmit_outside"),
                                (-1, -1, "reflect_inside"), (-1, 1, "transmit_inside")):
        CONFIGS.append((f"roughdielectric_{distribution}_0.3_{what}", "roughdielectric",
                        distribution, 0.3, 0.0, 1.0, False, camera, light))
# Anisotropic ones: `alpha` is then `alpha_u` (along the frame's s = +x) and
# ALPHA_V[name] is `alpha_v`.
ALPHA_V = {}
for distribution, alpha_u, alpha_v in (("ggx", 0.1, 0.4), ("beckmann", 0.4, 0.1)):
    name = f"roughconductor_{distribution}_{alpha_u}_{alpha_v}"
    CONFIGS.append((name, "roughconductor", distribution, alpha_u, 0.0, 1.0, False, 1, 1))
    ALPHA_V[name] = alpha_v
for camera, light, what in ((1, -1, "transmit_outside"), (-1, -1, "reflect_inside")):
    name = f"roughdielectric_ggx_0.1_0.35_{what}"
    CONFIGS.append((name, "roughdielectric", "ggx", 0.1, 0.0, 1.0, False, camera, light))
    ALPHA_V[name] = 0.35
# Tinted dielectrics: `specular` is then `specular_reflectance` and
# TRANSMITTANCE[name] is `specular_transmittance`.
TRANSMITTANCE = {}
for camera, light, what in ((1, 1, "reflect_outside"), (1, -1, "transmit_outside"),
                            (-1, -1, "reflect_inside"), (-1, 1, "transmit_inside")):
    name = f"roughdielectric_ggx_0.3_tinted_{what}"
    CONFIGS.append((name, "roughdielectric", "ggx", 0.3, 0.0, 0.6, False, camera, light))
    TRANSMITTANCE[name] = 0.3


# Principled: name, parameters (besides base_color 0.5), camera side, light
# side. The transmitting ones from all four sides.
PRINCIPLED_PARAMETERS = ["roughness", "metallic", "spec_trans", "spec_tint", "sheen",
                         "sheen_tint", "clearcoat", "clearcoat_gloss", "flatness", "anisotropic",
                         "eta"]
PRINCIPLED_CONFIGS = [
    ("principled_defaults", {}, 1, 1),
    ("principled_metal_tint", {"metallic": 0.7, "spec_tint": 0.6, "roughness": 0.3}, 1, 1),
    ("principled_sheen_clearcoat_flat", {"sheen": 0.8, "sheen_tint": 0.5, "clearcoat": 0.9,
                                         "clearcoat_gloss": 0.7, "flatness": 0.6,
                                         "roughness": 0.8}, 1, 1),
    ("principled_anisotropic_metal", {"metallic": 1.0, "roughness": 0.5, "anisotropic": 0.8},
     1, 1),
    ("principled_anisotropic_glass_transmit_outside",
     {"spec_trans": 1.0, "roughness": 0.5, "anisotropic": 0.6}, 1, -1),
]
for camera, light, what in ((1, 1, "reflect_outside"), (1, -1, "transmit_outside"),
                            (-1, -1, "reflect_inside"), (-1, 1, "transmit_inside")):
    PRINCIPLED_CONFIGS.append((f"principled_glass_{what}",
                               {"spec_trans": 1.0, "roughness": 0.4, "eta": 1.45}, camera, light))
    PRINCIPLED_CONFIGS.append((f"principled_mix_{what}",
                               {"spec_trans": 0.5, "metallic": 0.2, "clearcoat": 0.5,
                                "sheen": 0.5, "roughness": 0.5}, camera, light))
PRINCIPLED_DEFAULTS = {"roughness": 0.5, "eta": 1.5}


def principled_table(out):
    """The principled BSDF's configurations and evaluations."""
    everything = mi.BSDFContext()
    rows = []
    with open(out / "mitsuba_principled_configs.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["name"] + PRINCIPLED_PARAMETERS + ["camera_side", "light_side"])
        for name, params, cs, ls in PRINCIPLED_CONFIGS:
            values = [params.get(p, PRINCIPLED_DEFAULTS.get(p, 0.0)) for p in PRINCIPLED_PARAMETERS]
            w.writerow([name] + values + [cs, ls])
    for name, params, cs, ls in PRINCIPLED_CONFIGS:
        d = {"type": "principled", "base_color": {"type": "rgb", "value": [GREY] * 3}}
        d.update(params)
        bsdf = mi.load_dict(d)
        for theta_camera, theta_light, phi, si, wo in direction_pairs(cs, ls):
            value = grey(bsdf.eval(everything, si, wo))
            pdf = float(bsdf.pdf(everything, si, wo))
            rows.append([name, theta_camera, theta_light, phi, f"{value:.9g}", f"{pdf:.9g}"])
    with open(out / "mitsuba_principled_eval.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["config", "theta_camera_deg", "theta_light_deg", "phi_deg", "value", "pdf"])
        w.writerows(rows)
    print(f"{len(PRINCIPLED_CONFIGS)} principled configurations, {len(rows)} evaluations")


def load(plugin, distribution, alpha, diffuse, specular, nonlinear, alpha_v, transmittance):
    d = {"type": plugin}
    if plugin in ("plastic", "roughplastic"):
        d.update(int_ior=IOR, ext_ior=1.0, nonlinear=nonlinear,
                 diffuse_reflectance={"type": "rgb", "value": [diffuse] * 3})
        if specular != 1.0:
            d["specular_reflectance"] = {"type": "rgb", "value": [specular] * 3}
    elif plugin == "roughconductor":
        d.update(eta=CONDUCTOR_ETA, k=CONDUCTOR_K)
    elif plugin == "roughdielectric":
        d.update(int_ior=IOR, ext_ior=1.0)
        if specular != 1.0 or transmittance != 1.0:
            d["specular_reflectance"] = {"type": "rgb", "value": [specular] * 3}
            d["specular_transmittance"] = {"type": "rgb", "value": [transmittance] * 3}
    if distribution and alpha_v != alpha:
        d.update(distribution=distribution, alpha_u=alpha, alpha_v=alpha_v)
    elif distribution:
        d.update(distribution=distribution, alpha=alpha)
    return mi.load_dict(d)


def direction(theta_deg, phi_deg, side):
    theta, phi = math.radians(theta_deg), math.radians(phi_deg)
    return mi.Vector3f(math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                       side * math.cos(theta))


def grey(value):
    channels = [float(value[i]) for i in range(3)]
    if max(channels) - min(channels) > 1e-6 * max(1.0, abs(channels[0])):
        raise ValueError(f"channels differ: {channels}")
    return channels[0]


def direction_pairs(camera_side, light_side):
    """Every (camera angle, light angle, azimuth, interaction, light
    direction) of the grid, in the tables' order."""
    for theta_camera in THETAS_DEG:
        si = interaction(direction(theta_camera, 0.0, camera_side))
        for theta_light in THETAS_DEG:
            for phi in PHIS_DEG:
                if theta_light == 0.0 and phi != 0.0:
                    continue
                yield theta_camera, theta_light, phi, si, direction(theta_light, phi, light_side)


def interaction(camera):
    si = mi.SurfaceInteraction3f()
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Normal3f(0, 0, 1)
    si.wi = camera
    return si


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    root = pathlib.Path(__file__).resolve().parent.parent
    parser.add_argument("--out", type=pathlib.Path, default=root / "simd-tracer/tests/data")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    everything = mi.BSDFContext()
    diffuse_only = mi.BSDFContext()
    diffuse_only.component = 1
    with open(args.out / "mitsuba_bsdf_configs.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["name", "plugin", "distribution", "alpha", "int_ior", "ext_ior", "diffuse",
                    "specular", "nonlinear", "eta", "k", "camera_side", "light_side",
                    "alpha_v", "transmittance"])
        for name, plugin, distribution, alpha, diffuse, specular, nonlinear, cs, ls in CONFIGS:
            w.writerow([name, plugin, distribution, alpha, IOR, 1.0, diffuse, specular,
                        int(nonlinear), CONDUCTOR_ETA, CONDUCTOR_K, cs, ls,
                        ALPHA_V.get(name, alpha), TRANSMITTANCE.get(name, 1.0)])
    rows, deltas = [], []
    for name, plugin, distribution, alpha, diffuse, specular, nonlinear, cs, ls in CONFIGS:
        bsdf = load(plugin, distribution, alpha, diffuse, specular, nonlinear,
                    ALPHA_V.get(name, alpha), TRANSMITTANCE.get(name, 1.0))
        plastic = plugin in ("plastic", "roughplastic")
        for theta_camera in THETAS_DEG:
            si = interaction(direction(theta_camera, 0.0, cs))
            if plugin == "plastic":
                # sample1 = 0 picks the delta lobe whenever it can be picked.
                bs, weight = bsdf.sample(everything, si, 0.0, mi.Point2f(0.5, 0.5))
                probability = float(bs.pdf)
                deltas.append([name, theta_camera, f"{grey(weight) * probability:.9g}",
                               f"{probability:.9g}"])
        for theta_camera, theta_light, phi, si, wo in direction_pairs(cs, ls):
            value = grey(bsdf.eval(everything, si, wo))
            pdf = float(bsdf.pdf(everything, si, wo))
            diff = grey(bsdf.eval(diffuse_only, si, wo)) if plastic else 0.0
            rows.append([name, theta_camera, theta_light, phi, f"{value:.9g}", f"{pdf:.9g}",
                         f"{diff:.9g}"])

    with open(args.out / "mitsuba_bsdf_eval.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["config", "theta_camera_deg", "theta_light_deg", "phi_deg", "value", "pdf",
                    "diffuse"])
        w.writerows(rows)
    with open(args.out / "mitsuba_bsdf_delta.csv", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["config", "theta_camera_deg", "reflectance", "probability"])
        w.writerows(deltas)
    print(f"{len(CONFIGS)} configurations, {len(rows)} evaluations, {len(deltas)} delta rows")
    principled_table(args.out)


if __name__ == "__main__":
    main()
