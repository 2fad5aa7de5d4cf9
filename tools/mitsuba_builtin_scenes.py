#!/usr/bin/env python3
"""Mitsuba 3 XML equivalents of fspec's built-in scenes `colorchecker`,
`lamps` and `laser` (issue 27: "no built-in scene worse than Mitsuba at
equal time where Mitsuba can render it"), read by both renderers through
`tools/mitsuba_equal_time.py`.

What is written (OUT/SCENE.xml, its meshes in OUT/meshes-SCENE/): the
scene of `simd-tracer/src/scene/builtin.rs` at the harness's film
(`--size`, default 128 x 128, Gaussian filter of Mitsuba's default
sigma 0.5 px), path tracer with `--max-depth` (default 5), independent
sampler (the equal-time harness overrides the sample count and fspec's
sampler on the command line).

How the correspondence is exact:

* Geometry: every triangle of the built-in scene, in the builder's order
  and winding (`simd-tracer/src/scene/shapes.rs`: `add_quad_uv` splits
  a b c d into a b c and a c d; `add_box` its six faces; `add_sphere` the
  UV sphere of `rings x segments` quads whose pole quads are one triangle,
  its points computed in float32 as the builder does), one Wavefront OBJ
  file per object, loaded with `face_normals` (fspec's built-in triangles
  are flat: no vertex normals).
* Sides: built-in materials scatter from both faces (`Sides::Both`), so
  every BSDF is wrapped in `twosided`; emission is front-only in both
  renderers (Mitsuba's `area`, fspec's default `two_sided = false`).
* Spectra: the embedded tables of `spectral-core/src/data/tables.rs`
  (parsed from that file, so they are the renderer's very numbers), as
  `<spectrum value="lambda:v, ...">` with every native sample inside
  360-830 nm plus the values at 360 and 830 nm: fspec's tabulated
  built-ins are linear between samples and flat beyond the ends
  (`TabulatedSpectrum::value`), an XML `lambda:v` spectrum is zero beyond
  its samples in both renderers, so the written polyline equals fspec's
  spectrum over the whole range both render (360-830 nm, fspec's
  `SpectralRange::VISIBLE`, Mitsuba's `MI_CIE_MIN/MAX`).
* Light intensities: an emitter of luminance `Y` is its table times
  `Y / luminance(table)`, with `luminance` as `builtin.rs`: the 1 nm
  trapezoid over 360-830 nm of the spectrum (as float32) times the CIE 1931
  y-bar table, divided by the trapezoid integral of y-bar. Mitsuba's
  normalisation (`MI_CIE_Y_NORMALIZATION = 1 / integral of y-bar`) is the
  same, so both renderers see the same absolute radiance.
* Materials: `Material::lambert` is `diffuse` with the spectrum as
  `reflectance`; the lights' black Lambert base is `diffuse` of
  reflectance 0.

Scenes:

* `colorchecker`: the 24 ColorChecker patches (0.25 units, gap 0.03) and
  the black backdrop, under a `constant` environment of CIE D65 scaled to
  Y = 1 (the built-in's default illuminant); camera at (0, 0, 4), 22 deg.
* `lamps`: the room (five white quads of patch 20, half-size 1), three
  ceiling lights (half-size 0.18 at y = 0.995, x = -0.6, 0, 0.6) of CIE
  FL11, LED-B4 and A, each of luminance 8; the objects below. Camera of the
  Cornell box (0, 0, 3.9), 39.3077 deg.
* `laser`: the same room with three lights of half-size 0.12 emitting a
  triangular line (zero at centre +- 2 nm, 2 nm full width at half
  maximum: the three vertices are written exactly) at 450, 532 and 638 nm,
  each of luminance 6; the same objects.
* The objects of both rooms: red (patch 15) and blue (patch 13) diffuse
  boxes, a yellow (patch 16) diffuse sphere, and two coated spheres
  (patches 14 and 17 under a coat of index 1.5, GGX roughness 0.08 and
  smooth).

Deviations (Mitsuba has no exact equivalent; measured by the check of
`tools/mitsuba_equal_time.py --only builtin-check`):

* The two coated spheres are Mitsuba's `roughplastic` (GGX, alpha 0.08)
  and `plastic`, int_ior 1.5, ext_ior 1. fspec's built-in coat
  (`Bsdf::Coated` with `CoatParams::default()`) uses the flat coat
  transmittance 1 - F and the exact `F_dr` of the diffuse Fresnel
  integral; Mitsuba's (and fspec's import of it, `MitsubaPlastic`)
  tabulates the rough coat's transmittance and uses Mitsuba's fitted
  `F_dr`, with Mitsuba's separable GGX shadowing. The built-in's glossy
  spheres therefore differ from the XML's in both renderers: at the same
  seed fspec's two renders differ by up to 5 % in the 16 x 16-pixel
  blocks over the rough green sphere, by 0.1 % or less elsewhere.
* Nothing else: the camera, the filter and the depth are those of the
  harness, given to fspec's built-in renders on the command line. At the
  same seed fspec renders the built-in `colorchecker` and its XML alike to
  float rounding (largest block difference 1e-5 relative).

Not written: `materials` (its two thin films and the neural film have no
Mitsuba plugin; the rest, gold, copper, glass, a coated plastic and a
bilinearly filtered RGB checker under an RGB sky, is left for a later
pass: the checker's texels are interpolated in spectrum by the built-in
and in sigmoid coefficients by Mitsuba), `fluorescence` (Mitsuba renders
no fluorescence) and `prism` (Mitsuba's dielectrics are not dispersive).
`cornell` is written by `tools/mitsuba_equal_time.py` itself.

    python3 tools/mitsuba_builtin_scenes.py --out target/builtin-xml
    fspec render target/builtin-xml/lamps.xml --out lamps.exr
"""

import argparse
import pathlib
import re
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
#: The embedded tables fspec renders with (generated from data/*.csv).
TABLES_RS = ROOT / "spectral-core" / "src" / "data" / "tables.rs"
#: The range both renderers sample, nm (fspec's SpectralRange::VISIBLE,
#: Mitsuba's MI_CIE_MIN / MI_CIE_MAX).
RANGE_NM = (360.0, 830.0)
#: Step of the luminance integral, nm (builtin.rs `luminance`: 1 nm).
LUMINANCE_STEP_NM = 1.0
#: Film side, pixels, and longest path (the equal-time harness's).
SIZE_PX = 128
MAX_DEPTH = 5

# builtin.rs, `room` / `ceiling_light` / `objects` / `lamps` / `laser`.
#: Field of view of the Cornell box camera, degrees (CORNELL_FOV_DEG).
CORNELL_FOV_DEG = 39.3077
#: Camera of the rooms: position, target, up.
ROOM_CAMERA = ((0.0, 0.0, 3.9), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
#: ColorChecker patch of the room's walls.
ROOM_WHITE_PATCH = 20
#: Height of the ceiling lights' quads (just below the ceiling at y = 1).
CEILING_LIGHT_Y = 0.995
#: `lamps`: (built-in illuminant, table name in tables.rs, x of the light).
LAMPS = (("fl11", "ILLUMINANT_FL11", -0.6), ("led-b4", "ILLUMINANT_LED_B4", 0.0),
         ("a", "ILLUMINANT_A", 0.6))
#: `lamps`: half-size of each light and its luminance Y.
LAMP_HALF_SIZE = 0.18
LAMP_LUMINANCE = 8.0
#: `laser`: (line centre, nm; x of the light), half-size, luminance, and
#: the half base of each triangular line, nm (`laser_line`).
LASERS = ((450.0, -0.6), (532.0, 0.0), (638.0, 0.6))
LASER_HALF_SIZE = 0.12
LASER_LUMINANCE = 6.0
LASER_HALF_BASE_NM = 2.0
#: Diffuse boxes: (patch, min corner, max corner).
BOXES = ((15, (-0.75, -1.0, -0.6), (-0.25, -0.2, -0.1)),
         (13, (0.3, -1.0, -0.7), (0.75, -0.55, -0.25)))
#: Sphere tessellation of the objects (rings, segments).
SPHERE_RINGS, SPHERE_SEGMENTS = 24, 48
#: Spheres: (name, patch, coat roughness or None for diffuse, centre, radius).
SPHERES = (("yellow", 16, None, (0.5, -0.3, -0.45), 0.25),
           ("glossy-green", 14, 0.08, (-0.45, -0.7, 0.35), 0.3),
           ("glossy-magenta", 17, 0.0, (0.35, -0.78, 0.4), 0.22))
#: Index of the coats (`coated`: ior 1.5, outside 1).
COAT_IOR = 1.5

# builtin.rs, `colorchecker`.
#: Camera: position, target, up, field of view (degrees).
CHECKER_CAMERA = ((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
CHECKER_FOV_DEG = 22.0
#: The environment: CIE D65 (the default illuminant) scaled to Y = 1.
CHECKER_ILLUMINANT = "ILLUMINANT_D65"
CHECKER_LUMINANCE = 1.0
#: Backdrop quad corners (x, y) at z = -0.01.
BACKDROP_HALF = (2.0, 1.5)
BACKDROP_Z = -0.01
#: Patch side and gap, six patches a row, four rows.
PATCH_SIZE, PATCH_GAP = 0.25, 0.03
PATCH_COLUMNS, PATCH_COUNT = 6, 24

SCENES = ("colorchecker", "lamps", "laser")

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- {title}
     Written by tools/mitsuba_builtin_scenes.py from fspec's built-in scene
     `{name}` (simd-tracer/src/scene/builtin.rs and the tables of
     spectral-core/src/data/tables.rs); read by Mitsuba 3 and by fspec. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <integrator type="path">
        <integer name="max_depth" value="{max_depth}"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="{fov:g}"/>
        <string name="fov_axis" value="smaller"/>
        <transform name="to_world">
            <lookat origin="{origin}" target="{target}" up="{up}"/>
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
"""


def parse_tables(path=TABLES_RS):
    """The `pub static NAME: [f64; n]` arrays (and the ColorChecker's
    `[[f64; 81]; 24]`) of tables.rs, as numpy arrays."""
    text = path.read_text()
    tables = {}
    for m in re.finditer(r"pub static (\w+): \[(\[f64; \d+\]|f64); \d+\] = \[(.*?)\n\];", text,
                         re.S):
        name, kind, body = m.groups()
        body = re.sub(r"//[^\n]*", "", body)
        if kind == "f64":
            tables[name] = np.array([float(v) for v in body.replace("\n", " ").split(",")
                                     if v.strip()])
        else:
            rows = re.findall(r"\[(.*?)\]", body, re.S)
            tables[name] = np.array([[float(v) for v in r.split(",") if v.strip()]
                                     for r in rows])
    return tables


class Spectra:
    """fspec's built-in spectra as polylines (wavelengths, values)."""

    def __init__(self):
        self.t = parse_tables()
        self.cmf_nm = self.t["CIE1931_NM"]
        self.y_bar = self.t["CIE1931_Y_BAR"]
        step = self.cmf_nm[1] - self.cmf_nm[0]
        # cmf.rs `Y_BAR_INTEGRAL`: the trapezoid rule over the table.
        self.y_integral = (self.y_bar.sum() - 0.5 * (self.y_bar[0] + self.y_bar[-1])) * step

    def illuminant(self, table):
        return self.t[f"{table}_NM"], self.t[table]

    def patch(self, number):
        return self.t["COLORCHECKER_NM"], self.t["COLORCHECKER_REFLECTANCE"][number - 1]

    def luminance(self, lam, val):
        """builtin.rs `luminance`: 1 nm trapezoid of the float32 spectrum
        times y-bar (linear between its samples, zero outside), over
        `Y_BAR_INTEGRAL`."""
        steps = int(round((RANGE_NM[1] - RANGE_NM[0]) / LUMINANCE_STEP_NM))
        grid = RANGE_NM[0] + np.arange(steps + 1) * LUMINANCE_STEP_NM
        weights = np.ones(steps + 1)
        weights[[0, -1]] = 0.5
        values = np.interp(grid, lam, val).astype(np.float32).astype(np.float64)
        y = np.interp(grid, self.cmf_nm, self.y_bar, left=0.0, right=0.0)
        return (weights * values * y).sum() * LUMINANCE_STEP_NM / self.y_integral

    def with_luminance(self, lam, val, target):
        """builtin.rs `with_luminance`: the spectrum scaled to `target`."""
        return lam, val * (target / self.luminance(lam, val))


def clip_to_range(lam, val):
    """The polyline of a tabulated spectrum (linear inside, flat beyond its
    ends) restricted to RANGE_NM: the native samples inside plus the values
    at the range's ends."""
    lo, hi = RANGE_NM
    inside = (lam > lo) & (lam < hi)
    lam_out = np.concatenate([[lo], lam[inside], [hi]])
    return lam_out, np.interp(lam_out, lam, val)


def spectrum_xml(name, lam, val, clip=True):
    if clip:
        lam, val = clip_to_range(lam, val)
    pairs = ", ".join(f"{l:g}:{v:.9g}" for l, v in zip(lam, val))
    return f'<spectrum name="{name}" value="{pairs}"/>'


# --- geometry (shapes.rs), float32 as the builder computes it ------------

def quad(a, b, c, d):
    return [(a, b, c), (a, c, d)]


def box(lo, hi):
    def corner(x, y, z):
        return (hi[0] if x else lo[0], hi[1] if y else lo[1], hi[2] if z else lo[2])
    faces = [
        (corner(0, 0, 1), corner(1, 0, 1), corner(1, 1, 1), corner(0, 1, 1)),
        (corner(1, 0, 0), corner(0, 0, 0), corner(0, 1, 0), corner(1, 1, 0)),
        (corner(1, 0, 1), corner(1, 0, 0), corner(1, 1, 0), corner(1, 1, 1)),
        (corner(0, 0, 0), corner(0, 0, 1), corner(0, 1, 1), corner(0, 1, 0)),
        (corner(0, 1, 1), corner(1, 1, 1), corner(1, 1, 0), corner(0, 1, 0)),
        (corner(0, 0, 0), corner(1, 0, 0), corner(1, 0, 1), corner(0, 0, 1)),
    ]
    return [t for f in faces for t in quad(*f)]


def sphere(centre, radius, rings=SPHERE_RINGS, segments=SPHERE_SEGMENTS):
    f32 = np.float32
    centre = np.array(centre, dtype=f32)

    def point(ring, segment):
        theta = f32(np.pi) * f32(ring) / f32(rings)
        phi = f32(2.0 * np.pi) * f32(segment) / f32(segments)
        d = np.array([np.sin(theta) * np.cos(phi), np.cos(theta), -np.sin(theta) * np.sin(phi)],
                     dtype=f32)
        return tuple(centre + f32(radius) * d)

    tris = []
    for ring in range(rings):
        for segment in range(segments):
            p = [point(r, s) for r, s in ((ring, segment), (ring + 1, segment),
                                           (ring + 1, segment + 1), (ring, segment + 1))]
            if ring + 1 < rings:
                tris.append((p[0], p[1], p[2]))
            if ring > 0:
                tris.append((p[0], p[2], p[3]))
    return tris


def write_obj(path, triangles):
    """The triangles as an indexed OBJ (identical vertices shared)."""
    index, vertices, faces = {}, [], []
    for tri in triangles:
        face = []
        for v in tri:
            key = tuple(float(c) for c in v)
            if key not in index:
                index[key] = len(vertices) + 1
                vertices.append(key)
            face.append(index[key])
        faces.append(face)
    lines = [f"# {len(faces)} triangles, written by tools/mitsuba_builtin_scenes.py"]
    lines += ["v " + " ".join(f"{c:.9g}" for c in v) for v in vertices]
    lines += ["f " + " ".join(map(str, f)) for f in faces]
    path.write_text("\n".join(lines) + "\n")


def shape_xml(mesh, bsdf_id, emitter=None):
    inner = f'        <ref id="{bsdf_id}"/>'
    if emitter:
        inner += ('\n        <emitter type="area">\n            '
                  f'{emitter}\n        </emitter>')
    return (f'    <shape type="obj">\n        <string name="filename" value="{mesh}"/>\n'
            f'        <boolean name="face_normals" value="true"/>\n{inner}\n    </shape>')


def diffuse_xml(bsdf_id, reflectance):
    return (f'    <bsdf type="twosided" id="{bsdf_id}">\n        <bsdf type="diffuse">\n'
            f'            {reflectance}\n        </bsdf>\n    </bsdf>')


def plastic_xml(bsdf_id, reflectance, alpha):
    rough = alpha > 0.0
    extra = (f'\n            <string name="distribution" value="ggx"/>'
             f'\n            <float name="alpha" value="{alpha:g}"/>') if rough else ""
    return (f'    <bsdf type="twosided" id="{bsdf_id}">\n'
            f'        <bsdf type="{"roughplastic" if rough else "plastic"}">\n'
            f'            <float name="int_ior" value="{COAT_IOR:g}"/>\n'
            f'            <float name="ext_ior" value="1"/>{extra}\n'
            f'            {reflectance}\n        </bsdf>\n    </bsdf>')


class Writer:
    """One scene: BSDFs, shapes and meshes, then the file."""

    def __init__(self, out, name, stem):
        self.out, self.name, self.stem = out, name, stem
        self.mesh_dir = out / f"meshes-{stem}"
        self.mesh_dir.mkdir(parents=True, exist_ok=True)
        self.bsdfs, self.shapes = [], []

    def mesh(self, stem, triangles, bsdf_id, emitter=None):
        path = self.mesh_dir / f"{stem}.obj"
        write_obj(path, triangles)
        self.shapes.append(shape_xml(path.relative_to(self.out).as_posix(), bsdf_id, emitter))

    def write(self, title, camera, fov, extra="", size=SIZE_PX, max_depth=MAX_DEPTH):
        origin, target, up = (", ".join(f"{c:g}" for c in v) for v in camera)
        text = HEADER.format(title=title, name=self.name, max_depth=max_depth, fov=fov,
                             origin=origin, target=target, up=up, size=size)
        text += "\n".join(self.bsdfs) + "\n" + extra + "\n".join(self.shapes) + "\n</scene>\n"
        path = self.out / f"{self.stem}.xml"
        path.write_text(text)
        return path


def room(w, spectra):
    """builtin.rs `room` and `objects`."""
    w.bsdfs.append(diffuse_xml("room-white", spectrum_xml(
        "reflectance", *spectra.patch(ROOM_WHITE_PATCH))))
    w.bsdfs.append(diffuse_xml("black", '<rgb name="reflectance" value="0"/>'))
    v = lambda x, y, z: (x, y, z)  # noqa: E731
    walls = (
        quad(v(-1, -1, 1), v(1, -1, 1), v(1, -1, -1), v(-1, -1, -1))
        + quad(v(-1, 1, -1), v(1, 1, -1), v(1, 1, 1), v(-1, 1, 1))
        + quad(v(-1, -1, -1), v(1, -1, -1), v(1, 1, -1), v(-1, 1, -1))
        + quad(v(-1, -1, 1), v(-1, -1, -1), v(-1, 1, -1), v(-1, 1, 1))
        + quad(v(1, -1, -1), v(1, -1, 1), v(1, 1, 1), v(1, 1, -1))
    )
    w.mesh("room", walls, "room-white")
    for patch, lo, hi in BOXES:
        w.bsdfs.append(diffuse_xml(f"patch-{patch}", spectrum_xml(
            "reflectance", *spectra.patch(patch))))
        w.mesh(f"box-patch-{patch}", box(lo, hi), f"patch-{patch}")
    for name, patch, alpha, centre, radius in SPHERES:
        reflectance = spectra.patch(patch)
        if alpha is None:
            w.bsdfs.append(diffuse_xml(name, spectrum_xml("reflectance", *reflectance)))
        else:
            w.bsdfs.append(plastic_xml(name, spectrum_xml("diffuse_reflectance", *reflectance),
                                       alpha))
        w.mesh(f"sphere-{name}", sphere(centre, radius), name)


def ceiling_light(x, z, h):
    y = CEILING_LIGHT_Y
    return quad((x - h, y, z - h), (x + h, y, z - h), (x + h, y, z + h), (x - h, y, z + h))


def write_lamps(out, spectra, stem, **film):
    w = Writer(out, "lamps", stem)
    room(w, spectra)
    for name, table, x in LAMPS:
        lam, val = spectra.with_luminance(*spectra.illuminant(table), LAMP_LUMINANCE)
        w.mesh(f"light-{name}", ceiling_light(x, 0.0, LAMP_HALF_SIZE), "black",
               spectrum_xml("radiance", lam, val))
    return w.write("fspec's built-in `lamps`: the room under FL11, LED-B4 and A lamps "
                   f"(luminance {LAMP_LUMINANCE:g} each).", ROOM_CAMERA, CORNELL_FOV_DEG, **film)


def write_laser(out, spectra, stem, **film):
    w = Writer(out, "laser", stem)
    room(w, spectra)
    for centre, x in LASERS:
        line = (np.array([centre - LASER_HALF_BASE_NM, centre, centre + LASER_HALF_BASE_NM]),
                np.array([0.0, 1.0, 0.0]))
        lam, val = spectra.with_luminance(*line, LASER_LUMINANCE)
        # The triangle's three vertices exactly (zero beyond them in both).
        w.mesh(f"light-{centre:g}nm", ceiling_light(x, 0.0, LASER_HALF_SIZE), "black",
               spectrum_xml("radiance", lam, val, clip=False))
    return w.write("fspec's built-in `laser`: the room under 2 nm laser lines at 450, 532 and "
                   f"638 nm (luminance {LASER_LUMINANCE:g} each).", ROOM_CAMERA,
                   CORNELL_FOV_DEG, **film)


def write_colorchecker(out, spectra, stem, **film):
    w = Writer(out, "colorchecker", stem)
    w.bsdfs.append(diffuse_xml("black", '<rgb name="reflectance" value="0"/>'))
    bx, by = BACKDROP_HALF
    w.mesh("backdrop", quad((-bx, -by, BACKDROP_Z), (bx, -by, BACKDROP_Z), (bx, by, BACKDROP_Z),
                            (-bx, by, BACKDROP_Z)), "black")
    step = PATCH_SIZE + PATCH_GAP
    for index in range(PATCH_COUNT):
        row, column = divmod(index, PATCH_COLUMNS)
        x0 = np.float32((column - 3.0) * step + PATCH_GAP / 2.0)
        y0 = np.float32((1.0 - row) * step + PATCH_GAP / 2.0)
        x1, y1 = np.float32(x0 + np.float32(PATCH_SIZE)), np.float32(y0 + np.float32(PATCH_SIZE))
        w.bsdfs.append(diffuse_xml(f"patch-{index + 1}", spectrum_xml(
            "reflectance", *spectra.patch(index + 1))))
        w.mesh(f"patch-{index + 1}", quad((x0, y0, 0.0), (x1, y0, 0.0), (x1, y1, 0.0),
                                          (x0, y1, 0.0)), f"patch-{index + 1}")
    lam, val = spectra.with_luminance(*spectra.illuminant(CHECKER_ILLUMINANT), CHECKER_LUMINANCE)
    env = ('    <emitter type="constant">\n        '
           f'{spectrum_xml("radiance", lam, val)}\n    </emitter>\n')
    return w.write("fspec's built-in `colorchecker`: the 24 patches under a constant D65 "
                   "environment of Y = 1.", CHECKER_CAMERA, CHECKER_FOV_DEG, extra=env, **film)


WRITERS = {"colorchecker": write_colorchecker, "lamps": write_lamps, "laser": write_laser}


def write_scene(name, out, size=SIZE_PX, max_depth=MAX_DEPTH, stem=None):
    """Writes built-in scene `name` as OUT/STEM.xml (default STEM: the
    name) and its meshes as OUT/meshes-STEM/; returns the XML's path."""
    out.mkdir(parents=True, exist_ok=True)
    return WRITERS[name](out, Spectra(), stem or name, size=size, max_depth=max_depth)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "target" / "builtin-xml")
    p.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    p.add_argument("--size", type=int, default=SIZE_PX)
    p.add_argument("--max-depth", type=int, default=MAX_DEPTH)
    a = p.parse_args()
    for name in a.scenes:
        print(write_scene(name, a.out, a.size, a.max_depth))


if __name__ == "__main__":
    sys.exit(main())
