#!/usr/bin/env python3
"""Writes an ASCII PLY mesh (x y z vertices, polygon faces) as a Mitsuba
`serialized` file (format version 4, one shape, single precision, no
normals, fan-triangulated), the layout of Mitsuba 3's serialized shape
plugin: u16 0x041C, u16 version, a zlib stream of (u32 flags, the shape
name NUL-terminated, u64 vertex count, u64 triangle count, positions,
u32 indices), then the u64 offset of each shape and the u32 shape count.

    python3 tools/ply_to_serialized.py scenes/assets/teapot.ply scenes/assets/teapot.serialized
"""
import struct
import sys
import zlib

SINGLE_PRECISION = 0x1000


def read_ascii_ply(path):
    with open(path) as f:
        lines = f.read().split("\n")
    vertices = faces = 0
    body = 0
    for i, line in enumerate(lines):
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            vertices = int(words[2])
        elif words[:2] == ["element", "face"]:
            faces = int(words[2])
        elif words == ["end_header"]:
            body = i + 1
            break
    positions = [tuple(map(float, lines[body + i].split()[:3])) for i in range(vertices)]
    triangles = []
    for i in range(faces):
        values = list(map(int, lines[body + vertices + i].split()))
        polygon = values[1 : 1 + values[0]]
        triangles += [(polygon[0], polygon[k], polygon[k + 1]) for k in range(1, len(polygon) - 1)]
    return positions, triangles


def main(source, target):
    positions, triangles = read_ascii_ply(source)
    payload = struct.pack("<I", SINGLE_PRECISION) + b"teapot\0"
    payload += struct.pack("<QQ", len(positions), len(triangles))
    payload += b"".join(struct.pack("<3f", *p) for p in positions)
    payload += b"".join(struct.pack("<3I", *t) for t in triangles)
    data = struct.pack("<HH", 0x041C, 4) + zlib.compress(payload, 9)
    data += struct.pack("<QI", 0, 1)
    with open(target, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main(*sys.argv[1:3])
