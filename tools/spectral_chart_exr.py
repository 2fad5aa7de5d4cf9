#!/usr/bin/env python3
"""Writes a reflective spectral OpenEXR of the ColorChecker for measuring
`fspec texture` (docs/performance.md, "Spectral images in").

    python3 tools/spectral_chart_exr.py OUT.exr [SIZE]

The image is SIZE x SIZE texels (default 512) with 31 channels
`T.<λ>nm`, 400-700 nm every 10 nm (the band layout of measured reflectance
images such as the CAVE set), in the layout of Fichet et al. 2021. The 24
ColorChecker reflectances of data/colorchecker_iso17321.csv (Ohta 1997,
5 nm) fill a 6 x 4 grid of patches, each texel's spectrum scaled by a
smooth shading factor between 0.5 and 1 (so no two rows are equal) and
bilinearly mixed with its neighbour patch across a soft edge. The file is
an uncompressed single-part scan-line OpenEXR of float32 channels (OpenEXR
file layout, openexr.com "OpenEXR File Layout"), written with numpy only.
"""

import struct
import sys
from pathlib import Path

import numpy as np

# Band layout: 31 bands, 400-700 nm every 10 nm.
FIRST_NM, STEP_NM, BANDS = 400.0, 10.0, 31
# The chart's 6 columns and 4 rows of patches.
COLUMNS, ROWS = 6, 4
# Width of the soft edge between patches, in patch widths.
EDGE = 0.1
# The shading factor ranges over [1 - SHADING, 1].
SHADING = 0.5
# OpenEXR: magic number 20000630 and version 2 (single-part scan lines).
MAGIC, VERSION = 20000630, 2
FLOAT = 2  # pixel type FLOAT


def chart(data: Path) -> tuple[np.ndarray, np.ndarray]:
    """Wavelengths (nm) and the 24 reflectances, shape (24, wavelengths)."""
    rows = [
        line.split(",")
        for line in data.read_text().splitlines()
        if line and not line.startswith("#") and not line.startswith("wavelength")
    ]
    table = np.array(rows, dtype=float)
    return table[:, 0], table[:, 1:].T


def image(size: int, data: Path) -> tuple[np.ndarray, np.ndarray]:
    """The band wavelengths and the texels, shape (size, size, BANDS)."""
    lambda_nm, patches = chart(data)
    bands = FIRST_NM + STEP_NM * np.arange(BANDS)
    spectra = np.array([np.interp(bands, lambda_nm, p) for p in patches])
    centre = (np.arange(size) + 0.5) / size
    x = centre * COLUMNS
    y = centre * ROWS
    column = np.minimum(x.astype(int), COLUMNS - 1)
    row = np.minimum(y.astype(int), ROWS - 1)
    # Mix towards the next patch over the last EDGE of each patch.
    mix_x = np.clip((x - column - (1 - EDGE)) / EDGE, 0, 1)
    next_column = np.minimum(column + 1, COLUMNS - 1)
    texels = np.empty((size, size, BANDS))
    for j in range(size):
        here = spectra[row[j] * COLUMNS + column]
        there = spectra[row[j] * COLUMNS + next_column]
        mixed = (1 - mix_x)[:, None] * here + mix_x[:, None] * there
        shading = 1 - SHADING * 0.5 * (1 + np.sin(2 * np.pi * (centre[j] + centre)))
        texels[j] = mixed * shading[:, None]
    return bands, texels.astype(np.float32)


def attribute(name: str, kind: str, value: bytes) -> bytes:
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def write_exr(path: Path, bands: np.ndarray, texels: np.ndarray) -> None:
    height, width, _ = texels.shape
    names = ["T." + ("%.6f" % l).replace(".", ",") + "nm" for l in bands]
    order = sorted(range(len(names)), key=lambda k: names[k].encode())
    channels = b"".join(
        names[k].encode() + b"\0" + struct.pack("<iB3xii", FLOAT, 0, 1, 1) for k in order
    ) + b"\0"
    window = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = b"".join(
        [
            attribute("channels", "chlist", channels),
            attribute("compression", "compression", b"\0"),
            attribute("dataWindow", "box2i", window),
            attribute("displayWindow", "box2i", window),
            attribute("lineOrder", "lineOrder", b"\0"),
            attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
            attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
            attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
            attribute("spectralLayoutVersion", "string", b"1.0"),
        ]
    ) + b"\0"
    start = struct.pack("<ii", MAGIC, VERSION) + header
    line_bytes = 4 * width * len(names)
    first = len(start) + 8 * height
    offsets = struct.pack("<%dQ" % height, *(first + y * (8 + line_bytes) for y in range(height)))
    with path.open("wb") as out:
        out.write(start)
        out.write(offsets)
        for y in range(height):
            out.write(struct.pack("<ii", y, line_bytes))
            for k in order:
                out.write(texels[y, :, k].astype("<f4").tobytes())


def main() -> None:
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    size = int(sys.argv[2]) if len(sys.argv) == 3 else 512
    data = Path(__file__).resolve().parent.parent / "data" / "colorchecker_iso17321.csv"
    bands, texels = image(size, data)
    write_exr(Path(sys.argv[1]), bands, texels)


if __name__ == "__main__":
    main()
