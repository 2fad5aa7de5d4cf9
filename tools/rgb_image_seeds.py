#!/usr/bin/env python3
"""Writes the seeds of the `rgb_image` fuzz target (fuzz/corpus/rgb_image).

The target reads arbitrary bytes as an environment map or bitmap file of
any of the four formats fspec reads (Radiance RGBE, OpenEXR, PNG, JPEG;
`cli/src/hdr_image.rs`). Seeds named `valid-*` load and `broken-*` are
refused with a message (`cli/tests/fuzz_corpus.rs` checks both).

Made here, with the standard library only (PNG is zlib and CRC-32):
PNGs of every colour type the loader expands (grey 16-bit, grey with
alpha, palette, RGBA), and broken files cut from the valid ones. Copied
from the repository: the two scene PNGs, the JPEG of the hdr_image tests,
an RGB and a grey OpenEXR of the coefficient_exr corpus, an RGBE file of
the rgbe corpus.

    python3 tools/rgb_image_seeds.py          # from the repository root
"""
import os
import shutil
import struct
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fuzz", "corpus", "rgb_image")

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def png(width, height, bit_depth, colour_type, rows, palette=None):
    """A PNG with filter type 0 on every row; `rows` are the raw row bytes."""
    header = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    data = b"".join(b"\x00" + row for row in rows)
    chunks = chunk(b"IHDR", header)
    if palette is not None:
        chunks += chunk(b"PLTE", bytes(c for rgb in palette for c in rgb))
    chunks += chunk(b"IDAT", zlib.compress(data)) + chunk(b"IEND", b"")
    return PNG_SIGNATURE + chunks


def write(name, data):
    with open(os.path.join(OUT, name), "wb") as out:
        out.write(data)


def main():
    os.makedirs(OUT, exist_ok=True)
    copies = {
        "valid-checker.png": "scenes/assets/checker.png",
        "valid-thickness.png": "scenes/assets/thickness.png",
        "valid-two-colours-8x8.jpg": "cli/tests/data/two-colours-8x8.jpg",
        "valid-rgb-3x2.exr": "fuzz/corpus/coefficient_exr/rgb-3x2",
        "valid-y-piz.exr": "fuzz/corpus/coefficient_exr/y-piz",
        "valid-flat-16x8.hdr": "fuzz/corpus/rgbe/valid-flat-16x8.hdr",
    }
    for name, source in copies.items():
        shutil.copyfile(os.path.join(ROOT, source), os.path.join(OUT, name))

    grey16 = [struct.pack(">HHH", 0, 32768, 65535), struct.pack(">HHH", 1, 2, 3)]
    write("valid-grey16-3x2.png", png(3, 2, 16, 0, grey16))
    write("valid-grey-alpha-2x2.png", png(2, 2, 8, 4, [bytes([10, 255, 200, 0])] * 2))
    palette = [(255, 0, 0), (0, 128, 255)]
    write("valid-palette-2x1.png", png(2, 1, 8, 3, [bytes([0, 1])], palette))
    rgba = [bytes([255, 0, 128, 7, 10, 200, 255, 255])]
    write("valid-rgba-2x1.png", png(2, 1, 8, 6, rgba))

    def cut(source, keep):
        with open(os.path.join(OUT, source), "rb") as f:
            return f.read()[:keep]

    write("broken-truncated.png", cut("valid-thickness.png", 200))
    write("broken-zero-width.png", png(0, 1, 8, 0, [b""]))
    write("broken-palette-index.png", png(2, 1, 8, 3, [bytes([0, 7])], palette))
    write("broken-truncated.jpg", cut("valid-two-colours-8x8.jpg", 300))
    write("broken-truncated.exr", cut("valid-rgb-3x2.exr", 400))
    write("broken-truncated.hdr", cut("valid-flat-16x8.hdr", 100))
    write("broken-unknown-format", b"P6\n2 1\n255\n\xff\x00\x00\x00\x00\xff")


if __name__ == "__main__":
    main()
