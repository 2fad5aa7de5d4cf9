#!/usr/bin/env python3
"""Generate the large benchmark scenes of docs/performance.md ("fspec and
Mitsuba 3 on large scenes"): Mitsuba 3 scene files that both `fspec render`
and Mitsuba's own `mitsuba` command read unchanged, so that whole-process
time, peak memory and loading time compare the two renderers on the same
input.

Scenes (each `NAME/scene.xml` under the output folder, with its meshes):

* `cornell`: Mitsuba's built-in Cornell box (`mi.cornell_box()`: five
  rectangles, two cubes, a rectangular area light), 36 triangles.
* `icospheres`: the Cornell room and light with a 4 x 4 field of level-6
  icospheres on its floor instead of the two boxes: 1 310 720 triangles in
  ONE OBJ file of about 50 MB, positions and faces only (no vertex normals:
  both renderers then compute smooth vertex normals).
* `bunnies`: the Stanford bunny (`scenes/assets/bunny.ply`, 69 451
  triangles) as one `shapegroup`, instanced 36 times (2.5 M instanced
  triangles) on a floor, lit by `scenes/assets/envmap2.exr` only.
* `plyfield`: 400 binary PLY meshes of varied sizes (displaced icospheres,
  tori, capped cylinders; every other one with vertex normals) on a
  20 x 20 grid on a floor, eight materials, an area light and the
  environment map.

Every scene uses a 512 x 512 `hdrfilm` with Mitsuba's default Gaussian
filter, the independent sampler at 64 spp and the path tracer at
max_depth 5; `spp` and `res` are `<default>`s, so `-D spp=1 -D res=8`
turns a scene into a loading test. The output is deterministic (seeded
numpy generator, fixed float formatting). `scenes.json` lists each scene's
file and triangle counts for tools/big_scene_bench.py.

Needs Python 3 and numpy only. Run from the repository root:
    python3 tools/bench_scenes.py                 # into target/bench-scenes/
    python3 tools/bench_scenes.py --out /tmp/bs   # elsewhere
"""

import argparse
import json
import math
import os
import shutil

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASSETS = os.path.join(REPO, "scenes", "assets")
BUNNY_PLY = os.path.join(ASSETS, "bunny.ply")
ENVMAP_EXR = os.path.join(ASSETS, "envmap2.exr")

SEED = 22  # the number: any fixed seed makes the scenes reproducible

# Render settings shared by all scenes (the benchmark's setting).
RESOLUTION = 512
SPP = 64
MAX_DEPTH = 5

# Mitsuba's built-in Cornell box (mitsuba/python/mitsuba/__init__.py,
# cornell_box()); the room spans [-1, 1]^3, the camera looks down -z.
CORNELL_FOV_DEG = 39.3077
CORNELL_EYE_Z = 3.9
CORNELL_WHITE = (0.885809, 0.698859, 0.666422)
CORNELL_GREEN = (0.105421, 0.37798, 0.076425)
CORNELL_RED = (0.570068, 0.0430135, 0.0443706)
CORNELL_LIGHT_RADIANCE = (18.387, 13.9873, 6.75357)
TRIANGLES_PER_RECTANGLE = 2
TRIANGLES_PER_CUBE = 12

# The icosphere field: 16 spheres of subdivision level 6 (81 920 triangles
# each), 1.31 M triangles, the size of the earlier one-OBJ measurement.
ICO_GRID = 4
ICO_LEVEL = 6
ICO_RADIUS = 0.18
ICO_SPACING = 0.45
ICO_RADIUS_JITTER = 0.15  # relative
ICO_SPHERE_RGB = (0.35, 0.55, 0.8)

# The bunny field: 6 x 6 instances of 69 451 triangles = 2.5 M.
BUNNY_GRID = 6
BUNNY_SPACING = 0.2
BUNNY_SCALE_RANGE = (0.8, 1.2)
BUNNY_RGB = (0.75, 0.6, 0.45)
# camera above the front edge, looking at the field's centre; in field extents
BUNNY_EYE = (0.0, 0.75, 1.4)
BUNNY_FOV_DEG = 40.0
FLOOR_RGB = (0.5, 0.5, 0.5)

# The PLY field: 20 x 20 meshes, one per 1 x 1 cell.
PLY_GRID = 20
PLY_CELL = 1.0
PLY_JITTER = 0.15  # of a cell, each axis
PLY_SIZE_RANGE = (0.28, 0.42)  # half-extent of a mesh in scene units
PLY_EYE = (0.0, 0.45, 0.85)  # in field extents, like the target
PLY_TARGET = (0.0, 0.0, -0.05)
PLY_FOV_DEG = 45.0
ROCK_LEVELS = (1, 2, 3, 4, 5)
ROCK_LEVEL_WEIGHTS = (0.15, 0.25, 0.3, 0.2, 0.1)
ROCK_BUMPS = 6  # sinusoidal bumps summed over the sphere
ROCK_BUMP_AMPLITUDE = 0.08
ROCK_BUMP_FREQUENCY = (1.0, 4.0)  # radians per unit of the direction cosine
ROCK_STRETCH = (0.7, 1.3)  # per-axis scale of a rock
TORUS_MAJOR_SEGMENTS = (16, 160)
TORUS_MINOR_SEGMENTS = (8, 48)
TORUS_MINOR_RADIUS = (0.2, 0.4)  # relative to the major radius 1
CYLINDER_SEGMENTS = (8, 256)
CYLINDER_RINGS = (1, 8)
AREA_LIGHT_HEIGHT = 12.0
AREA_LIGHT_HALF_SIZE = 3.0
AREA_LIGHT_RADIANCE = 4.0  # times D65 (Mitsuba's meaning of a float radiance)
ENVMAP_SCALE_PLYFIELD = 0.5


# ---------------------------------------------------------------- meshes


def icosphere(level):
    """Unit icosphere: (vertices float64 [n, 3], faces int64 [m, 3])."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = np.array(
        [
            [-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0],
            [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
            [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1],
        ],
        dtype=np.float64,
    )
    f = np.array(
        [
            [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
            [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
            [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
            [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
        ],
        dtype=np.int64,
    )
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(level):
        v, f = _subdivide(v, f)
    return v, f


def _subdivide(v, f):
    """Split every triangle into four at its edge midpoints (on the sphere)."""
    edges = np.stack([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]], axis=1)
    edges = np.sort(edges.reshape(-1, 2), axis=1)
    keys = edges[:, 0] * len(v) + edges[:, 1]
    unique_keys, inverse = np.unique(keys, return_inverse=True)
    a, b = np.divmod(unique_keys, len(v))
    mid = v[a] + v[b]
    mid /= np.linalg.norm(mid, axis=1, keepdims=True)
    m = inverse.reshape(-1, 3) + len(v)  # midpoints of edges 01, 12, 20
    c0, c1, c2 = f[:, 0], f[:, 1], f[:, 2]
    m01, m12, m20 = m[:, 0], m[:, 1], m[:, 2]
    faces = np.concatenate(
        [
            np.stack([c0, m01, m20], axis=1),
            np.stack([c1, m12, m01], axis=1),
            np.stack([c2, m20, m12], axis=1),
            np.stack([m01, m12, m20], axis=1),
        ]
    )
    return np.concatenate([v, mid]), faces


def vertex_normals(v, f):
    """Area-weighted vertex normals (unit length; zero-area fans give +y)."""
    n = np.zeros_like(v)
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    for corner in range(3):
        np.add.at(n, f[:, corner], face_n)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where(length > 0, n / np.maximum(length, 1e-30), [0.0, 1.0, 0.0])
    return n


def rock(rng):
    """A displaced icosphere of a random level; radius about 1."""
    level = int(rng.choice(ROCK_LEVELS, p=ROCK_LEVEL_WEIGHTS))
    v, f = icosphere(level)
    directions = rng.normal(size=(ROCK_BUMPS, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    frequencies = rng.uniform(*ROCK_BUMP_FREQUENCY, size=ROCK_BUMPS)
    phases = rng.uniform(0.0, 2.0 * math.pi, size=ROCK_BUMPS)
    bumps = np.sin((v @ directions.T) * frequencies + phases).sum(axis=1)
    radius = 1.0 + ROCK_BUMP_AMPLITUDE * bumps
    stretch = rng.uniform(*ROCK_STRETCH, size=3)
    v = v * radius[:, None] * stretch
    return v, f, None


def torus(rng):
    """A torus of major radius 1, tilted about x; analytic normals."""
    nu = int(rng.integers(*TORUS_MAJOR_SEGMENTS, endpoint=True))
    nv = int(rng.integers(*TORUS_MINOR_SEGMENTS, endpoint=True))
    r = rng.uniform(*TORUS_MINOR_RADIUS)
    u = np.arange(nu) * (2.0 * math.pi / nu)
    w = np.arange(nv) * (2.0 * math.pi / nv)
    uu, ww = np.meshgrid(u, w, indexing="ij")
    normal = np.stack(
        [np.cos(ww) * np.cos(uu), np.sin(ww), np.cos(ww) * np.sin(uu)], axis=-1
    )
    centre = np.stack([np.cos(uu), np.zeros_like(uu), np.sin(uu)], axis=-1)
    v = (centre + r * normal).reshape(-1, 3)
    n = normal.reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a = i * nv + j
    b = ((i + 1) % nu) * nv + j
    c = ((i + 1) % nu) * nv + (j + 1) % nv
    d = i * nv + (j + 1) % nv
    f = np.concatenate(
        [np.stack([a, d, c], -1).reshape(-1, 3), np.stack([a, c, b], -1).reshape(-1, 3)]
    )
    tilt = rng.uniform(0.0, math.pi / 2.0)
    rot = np.array(
        [[1, 0, 0], [0, math.cos(tilt), -math.sin(tilt)], [0, math.sin(tilt), math.cos(tilt)]]
    )
    return v @ rot.T, f, n @ rot.T


def cylinder(rng):
    """A capped cylinder of radius 1, height 2, with side rings; y is up."""
    segments = int(rng.integers(*CYLINDER_SEGMENTS, endpoint=True))
    rings = int(rng.integers(*CYLINDER_RINGS, endpoint=True))
    angle = np.arange(segments) * (2.0 * math.pi / segments)
    heights = np.linspace(-1.0, 1.0, rings + 1)
    hh, aa = np.meshgrid(heights, angle, indexing="ij")
    side = np.stack([np.cos(aa), hh, np.sin(aa)], axis=-1).reshape(-1, 3)
    k, s = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = k * segments + s
    b = k * segments + (s + 1) % segments
    c = (k + 1) * segments + (s + 1) % segments
    d = (k + 1) * segments + s
    faces = [np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    # caps: a centre vertex each, fans over the bottom and top rings
    bottom_centre = len(side)
    top_centre = bottom_centre + 1
    v = np.concatenate([side, [[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]])
    s = np.arange(segments)
    top_ring = rings * segments
    faces.append(np.stack([np.full(segments, bottom_centre), s, (s + 1) % segments], -1))
    faces.append(
        np.stack([np.full(segments, top_centre), top_ring + (s + 1) % segments, top_ring + s], -1)
    )
    return v, np.concatenate(faces), None


MESH_KINDS = (rock, torus, cylinder)


# ---------------------------------------------------------------- writers


def write_obj(path, objects):
    """One OBJ: positions and triangles of every (vertices, faces) pair."""
    offset = 1  # OBJ indices start at 1
    with open(path, "w", encoding="ascii") as out:
        out.write("# written by tools/bench_scenes.py\n")
        for number, (v, f) in enumerate(objects):
            out.write(f"o sphere{number}\n")
            np.savetxt(out, v, fmt="v %.6f %.6f %.6f")
            np.savetxt(out, f + offset, fmt="f %d %d %d")
            offset += len(v)


def write_ply(path, v, f, normals=None):
    """Binary little-endian PLY: float xyz (+ nx ny nz), uchar/int faces."""
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    if normals is not None:
        fields += [("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4")]
    vertices = np.empty(len(v), dtype=fields)
    vertices["x"], vertices["y"], vertices["z"] = v.T
    if normals is not None:
        vertices["nx"], vertices["ny"], vertices["nz"] = normals.T
    faces = np.empty(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"] = 3
    faces["i"] = f
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(v)}"]
    header += [f"property float {name}" for name, _ in fields]
    header += [f"element face {len(f)}", "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as out:
        out.write(("\n".join(header) + "\n").encode("ascii"))
        out.write(vertices.tobytes())
        out.write(faces.tobytes())


# ---------------------------------------------------------------- XML


def rgb(name, value):
    return f'<rgb name="{name}" value="{value[0]:g}, {value[1]:g}, {value[2]:g}"/>'


def header(eye, target, fov_deg):
    """Scene opening: defaults, integrator and sensor (fov on the smaller axis)."""
    return f"""<scene version="3.0.0">
    <default name="spp" value="{SPP}"/>
    <default name="res" value="{RESOLUTION}"/>
    <default name="max_depth" value="{MAX_DEPTH}"/>

    <integrator type="path">
        <integer name="max_depth" value="$max_depth"/>
    </integrator>

    <sensor type="perspective">
        <string name="fov_axis" value="smaller"/>
        <float name="fov" value="{fov_deg:g}"/>
        <transform name="to_world">
            <lookat origin="{eye[0]:g}, {eye[1]:g}, {eye[2]:g}"
                    target="{target[0]:g}, {target[1]:g}, {target[2]:g}"
                    up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="gaussian"/>
        </film>
    </sensor>
"""


def cornell_room(with_boxes):
    """Mitsuba's cornell_box() shapes; the transforms in its order."""
    walls = [
        ("floor", "white", '<rotate x="1" angle="-90"/><translate y="-1"/>'),
        ("ceiling", "white", '<rotate x="1" angle="90"/><translate y="1"/>'),
        ("back", "white", '<translate z="-1"/>'),
        ("greenwall", "green", '<rotate y="1" angle="-90"/><translate x="1"/>'),
        ("redwall", "red", '<rotate y="1" angle="90"/><translate x="-1"/>'),
    ]
    lines = [
        f'    <bsdf type="diffuse" id="white">{rgb("reflectance", CORNELL_WHITE)}</bsdf>',
        f'    <bsdf type="diffuse" id="green">{rgb("reflectance", CORNELL_GREEN)}</bsdf>',
        f'    <bsdf type="diffuse" id="red">{rgb("reflectance", CORNELL_RED)}</bsdf>',
        '    <shape type="rectangle" id="light">',
        '        <transform name="to_world"><scale x="0.23" y="0.19" z="0.19"/>'
        '<rotate x="1" angle="90"/><translate x="0" y="0.99" z="0.01"/></transform>',
        '        <ref id="white"/>',
        f'        <emitter type="area">{rgb("radiance", CORNELL_LIGHT_RADIANCE)}</emitter>',
        "    </shape>",
    ]
    for name, bsdf, transform in walls:
        lines.append(
            f'    <shape type="rectangle" id="{name}"><transform name="to_world">'
            f'{transform}</transform><ref id="{bsdf}"/></shape>'
        )
    if with_boxes:
        lines.append(
            '    <shape type="cube" id="smallbox"><transform name="to_world">'
            '<scale value="0.3"/><rotate y="1" angle="-17"/>'
            '<translate x="0.335" y="-0.7" z="0.38"/></transform><ref id="white"/></shape>'
        )
        lines.append(
            '    <shape type="cube" id="largebox"><transform name="to_world">'
            '<scale x="0.3" y="0.61" z="0.3"/><rotate y="1" angle="18.25"/>'
            '<translate x="-0.33" y="-0.4" z="-0.28"/></transform><ref id="white"/></shape>'
        )
    return "\n".join(lines) + "\n"


CORNELL_WALLS = 5
CORNELL_ROOM_TRIANGLES = (CORNELL_WALLS + 1) * TRIANGLES_PER_RECTANGLE  # + light


def cornell_header():
    return header((0.0, 0.0, CORNELL_EYE_Z), (0.0, 0.0, 0.0), CORNELL_FOV_DEG)


# ---------------------------------------------------------------- scenes


def scene_cornell(folder, _rng):
    xml = cornell_header() + cornell_room(with_boxes=True) + "</scene>\n"
    write_text(os.path.join(folder, "scene.xml"), xml)
    triangles = CORNELL_ROOM_TRIANGLES + 2 * TRIANGLES_PER_CUBE
    return {"triangles": triangles, "unique_triangles": triangles, "meshes": 0}


def scene_icospheres(folder, rng):
    sphere_v, sphere_f = icosphere(ICO_LEVEL)
    objects = []
    floor_y = -1.0
    first = -(ICO_GRID - 1) / 2.0 * ICO_SPACING
    for row in range(ICO_GRID):
        for column in range(ICO_GRID):
            radius = ICO_RADIUS * (1.0 + rng.uniform(-ICO_RADIUS_JITTER, ICO_RADIUS_JITTER))
            centre = np.array(
                [first + column * ICO_SPACING, floor_y + radius, first + row * ICO_SPACING]
            )
            objects.append((sphere_v * radius + centre, sphere_f))
    write_obj(os.path.join(folder, "icospheres.obj"), objects)
    xml = cornell_header() + cornell_room(with_boxes=False)
    xml += f'    <bsdf type="diffuse" id="spheres">{rgb("reflectance", ICO_SPHERE_RGB)}</bsdf>\n'
    xml += (
        '    <shape type="obj" id="icospheres">\n'
        '        <string name="filename" value="icospheres.obj"/>\n'
        '        <ref id="spheres"/>\n'
        "    </shape>\n</scene>\n"
    )
    write_text(os.path.join(folder, "scene.xml"), xml)
    triangles = CORNELL_ROOM_TRIANGLES + len(objects) * len(sphere_f)
    return {"triangles": triangles, "unique_triangles": triangles, "meshes": 1}


def ply_face_count(path):
    with open(path, "rb") as source:
        for line in source:
            if line.startswith(b"element face"):
                return int(line.split()[2])
            if line.startswith(b"end_header"):
                break
    raise ValueError(f"{path}: no face element")


def floor_xml(half_size, bsdf_id):
    return (
        f'    <shape type="rectangle" id="floor"><transform name="to_world">'
        f'<scale value="{half_size:g}"/><rotate x="1" angle="-90"/></transform>'
        f'<ref id="{bsdf_id}"/></shape>\n'
    )


def envmap_xml(scale):
    return (
        '    <emitter type="envmap">\n'
        '        <string name="filename" value="envmap2.exr"/>\n'
        f'        <float name="scale" value="{scale:g}"/>\n'
        "    </emitter>\n"
    )


# The bunny's lowest point (y of its bounding box; scenes/assets/bunny.ply).
BUNNY_MIN_Y = -0.0545676


def scene_bunnies(folder, rng):
    shutil.copyfile(BUNNY_PLY, os.path.join(folder, "bunny.ply"))
    shutil.copyfile(ENVMAP_EXR, os.path.join(folder, "envmap2.exr"))
    extent = (BUNNY_GRID - 1) * BUNNY_SPACING
    eye = tuple(c * extent for c in BUNNY_EYE)
    xml = header(eye, (0.0, 0.0, 0.0), BUNNY_FOV_DEG)
    xml += f'    <bsdf type="diffuse" id="clay">{rgb("reflectance", BUNNY_RGB)}</bsdf>\n'
    xml += f'    <bsdf type="diffuse" id="grey">{rgb("reflectance", FLOOR_RGB)}</bsdf>\n'
    xml += envmap_xml(1.0)
    xml += floor_xml(extent, "grey")
    xml += (
        '    <shape type="shapegroup" id="bunny">\n'
        '        <shape type="ply">\n'
        '            <string name="filename" value="bunny.ply"/>\n'
        '            <ref id="clay"/>\n'
        "        </shape>\n"
        "    </shape>\n"
    )
    first = -extent / 2.0
    for row in range(BUNNY_GRID):
        for column in range(BUNNY_GRID):
            scale = rng.uniform(*BUNNY_SCALE_RANGE)
            angle = rng.uniform(0.0, 360.0)
            x = first + column * BUNNY_SPACING
            z = first + row * BUNNY_SPACING
            y = -BUNNY_MIN_Y * scale
            xml += (
                f'    <shape type="instance"><ref id="bunny"/><transform name="to_world">'
                f'<scale value="{scale:.4f}"/><rotate y="1" angle="{angle:.2f}"/>'
                f'<translate x="{x:.4f}" y="{y:.5f}" z="{z:.4f}"/></transform></shape>\n'
            )
    xml += "</scene>\n"
    write_text(os.path.join(folder, "scene.xml"), xml)
    bunny = ply_face_count(BUNNY_PLY)
    instances = BUNNY_GRID * BUNNY_GRID
    return {
        "triangles": instances * bunny + TRIANGLES_PER_RECTANGLE,
        "unique_triangles": bunny + TRIANGLES_PER_RECTANGLE,
        "meshes": 1,
    }


PLY_MATERIALS = [
    ("terracotta", '<bsdf type="diffuse" id="terracotta">'
     + rgb("reflectance", (0.7, 0.35, 0.2)) + "</bsdf>"),
    ("sage", '<bsdf type="diffuse" id="sage">' + rgb("reflectance", (0.4, 0.55, 0.35)) + "</bsdf>"),
    ("slate", '<bsdf type="diffuse" id="slate">' + rgb("reflectance", (0.3, 0.33, 0.4)) + "</bsdf>"),
    ("bone", '<bsdf type="diffuse" id="bone">' + rgb("reflectance", (0.85, 0.8, 0.7)) + "</bsdf>"),
    ("blueplastic", '<bsdf type="plastic" id="blueplastic">'
     + rgb("diffuse_reflectance", (0.1, 0.2, 0.6)) + "</bsdf>"),
    ("redplastic", '<bsdf type="roughplastic" id="redplastic">'
     + rgb("diffuse_reflectance", (0.6, 0.08, 0.06)) + '<float name="alpha" value="0.2"/></bsdf>'),
    ("gold", '<bsdf type="roughconductor" id="gold"><string name="material" value="Au"/>'
     '<float name="alpha" value="0.15"/></bsdf>'),
    ("copper", '<bsdf type="roughconductor" id="copper"><string name="material" value="Cu"/>'
     '<float name="alpha" value="0.3"/></bsdf>'),
]


def scene_plyfield(folder, rng):
    shutil.copyfile(ENVMAP_EXR, os.path.join(folder, "envmap2.exr"))
    os.makedirs(os.path.join(folder, "meshes"), exist_ok=True)
    extent = PLY_GRID * PLY_CELL
    eye = tuple(c * extent for c in PLY_EYE)
    target = tuple(c * extent for c in PLY_TARGET)
    xml = header(eye, target, PLY_FOV_DEG)
    for _, bsdf in PLY_MATERIALS:
        xml += f"    {bsdf}\n"
    xml += f'    <bsdf type="diffuse" id="grey">{rgb("reflectance", FLOOR_RGB)}</bsdf>\n'
    xml += envmap_xml(ENVMAP_SCALE_PLYFIELD)
    xml += (
        '    <shape type="rectangle" id="light">\n'
        f'        <transform name="to_world"><scale value="{AREA_LIGHT_HALF_SIZE:g}"/>'
        f'<rotate x="1" angle="90"/><translate y="{AREA_LIGHT_HEIGHT:g}"/></transform>\n'
        f'        <emitter type="area"><float name="radiance" value="{AREA_LIGHT_RADIANCE:g}"/>'
        "</emitter>\n    </shape>\n"
    )
    xml += floor_xml(extent / 2.0 + PLY_CELL, "grey")
    triangles = 2 * TRIANGLES_PER_RECTANGLE
    with_normals = 0
    first = -(PLY_GRID - 1) / 2.0 * PLY_CELL
    for index in range(PLY_GRID * PLY_GRID):
        kind = MESH_KINDS[int(rng.integers(len(MESH_KINDS)))]
        v, f, normals = kind(rng)
        if index % 2 == 0:
            if normals is None:
                normals = vertex_normals(v, f)
            with_normals += 1
        else:
            normals = None
        # fit the mesh into PLY_SIZE_RANGE: scale its largest half-extent
        half = (v.max(axis=0) - v.min(axis=0)).max() / 2.0
        scale = rng.uniform(*PLY_SIZE_RANGE) / half
        name = f"mesh{index:03d}.ply"
        write_ply(os.path.join(folder, "meshes", name), v, f, normals)
        row, column = divmod(index, PLY_GRID)
        x = first + column * PLY_CELL + rng.uniform(-PLY_JITTER, PLY_JITTER) * PLY_CELL
        z = first + row * PLY_CELL + rng.uniform(-PLY_JITTER, PLY_JITTER) * PLY_CELL
        y = -v[:, 1].min() * scale
        angle = rng.uniform(0.0, 360.0)
        material = PLY_MATERIALS[int(rng.integers(len(PLY_MATERIALS)))][0]
        xml += (
            f'    <shape type="ply"><string name="filename" value="meshes/{name}"/>'
            f'<transform name="to_world"><scale value="{scale:.5f}"/>'
            f'<rotate y="1" angle="{angle:.2f}"/>'
            f'<translate x="{x:.4f}" y="{y:.5f}" z="{z:.4f}"/></transform>'
            f'<ref id="{material}"/></shape>\n'
        )
        triangles += len(f)
    xml += "</scene>\n"
    write_text(os.path.join(folder, "scene.xml"), xml)
    count = PLY_GRID * PLY_GRID
    return {
        "triangles": triangles,
        "unique_triangles": triangles,
        "meshes": count,
        "meshes_with_normals": with_normals,
    }


SCENES = {
    "cornell": scene_cornell,
    "icospheres": scene_icospheres,
    "bunnies": scene_bunnies,
    "plyfield": scene_plyfield,
}


def write_text(path, text):
    with open(path, "w", encoding="utf-8") as out:
        out.write(text)


def folder_bytes(folder):
    return sum(
        os.path.getsize(os.path.join(root, name))
        for root, _, names in os.walk(folder)
        for name in names
    )


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.join(REPO, "target", "bench-scenes"))
    p.add_argument("--only", nargs="+", choices=sorted(SCENES), help="scenes to write")
    a = p.parse_args()
    manifest = {}
    for name, make in SCENES.items():
        if a.only and name not in a.only:
            continue
        folder = os.path.join(a.out, name)
        os.makedirs(folder, exist_ok=True)
        # each scene its own stream, so that --only writes the same files
        rng = np.random.default_rng([SEED, list(SCENES).index(name)])
        info = make(folder, rng)
        info["file"] = os.path.join(name, "scene.xml")
        info["bytes_on_disk"] = folder_bytes(folder)
        manifest[name] = info
        print(
            f"{name}: {info['triangles']:,} triangles "
            f"({info['unique_triangles']:,} stored), "
            f"{info['bytes_on_disk'] / 2**20:.1f} MiB on disk -> {folder}/scene.xml"
        )
    path = os.path.join(a.out, "scenes.json")
    if os.path.exists(path):  # keep the entries of scenes not rewritten now
        with open(path, encoding="utf-8") as source:
            manifest = {**json.load(source), **manifest}
    with open(path, "w", encoding="utf-8") as out:
        json.dump(manifest, out, indent=2, sort_keys=True)


if __name__ == "__main__":
    main()
