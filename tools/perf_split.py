#!/usr/bin/env python3
"""Split a `perf record` profile of `fspec` into the renderer's parts.

Each sample is counted in the innermost function of this project
(simd-tracer, spectral-core, cli) along the inline chain of its address, as
`addr2line -i` reads it from the binary's line tables (the release profile
keeps `debug = "line-tables-only"`), and the function's source file names
its part. Counting by symbol instead would charge everything inlined into
`trace_group` to the integrator, and counting by innermost source file would
charge the SIMD wrappers of `wide` and `core::arch`.

    cargo build --release -p cli
    perf record -F 4000 -o perf.data target/release/fspec render \\
        --width 512 --height 512 --spp 64 --max-depth 5 --threads 1 --out /tmp/p.png
    python3 tools/perf_split.py target/release/fspec perf.data
"""

import collections
import re
import subprocess
import sys

# Source files (relative to the workspace root) by part; the first match wins.
PARTS = [
    ("traversal", ["simd-tracer/src/accel/"]),
    ("ray compaction", ["simd-tracer/src/integrator/compaction.rs"]),
    (
        "spectral algebra",
        [
            "spectral-core/src/lane.rs",
            "spectral-core/src/fourier.rs",
            "simd-tracer/src/transport/",
            "spectral-core/src/color.rs",
            "spectral-core/src/xyz.rs",
            "spectral-core/src/sampling.rs",
            "spectral-core/src/control_variate.rs",
            "simd-tracer/src/spectra/mod.rs",
        ],
    ),
    (
        "integrator glue, shading, light sampling",
        [
            "simd-tracer/src/integrator/",
            "simd-tracer/src/shading/",
            # The environment map's light-sampling tables (not random numbers).
            "simd-tracer/src/sampling/distribution.rs",
            "simd-tracer/src/spectra/",
            "simd-tracer/src/simd/",
            "simd-tracer/src/packet.rs",
        ],
    ),
    ("random numbers", ["simd-tracer/src/sampling/"]),
    (
        "film, camera, filter, tiles",
        [
            "simd-tracer/src/render/",
            "simd-tracer/src/film/",
            "simd-tracer/src/scene/camera.rs",
        ],
    ),
    ("command line and output", ["cli/src"]),
]
PROJECT = ("simd-tracer/src/", "spectral-core/src/", "cli/src/")


def symbol_addresses(exe):
    out = subprocess.run(
        ["nm", "--defined-only", exe], capture_output=True, text=True, check=True
    ).stdout
    table = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3:
            table.setdefault(parts[2], int(parts[0], 16))
    return table


def sample_addresses(exe, data, symbols):
    """Counts of binary addresses of the samples in `exe`, and the number of
    all samples."""
    out = subprocess.run(
        ["perf", "script", "-i", data, "--no-demangle", "-F", "ip,sym,symoff,dso"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    counts = collections.Counter()
    total = 0
    name = exe.rsplit("/", 1)[-1]
    for line in out.splitlines():
        line = line.strip()
        if not line:
            continue
        total += 1
        m = re.match(r"[0-9a-f]+ (\S+)\+0x([0-9a-f]+) \((.*)\)", line)
        if m and m.group(3).endswith(name) and m.group(1) in symbols:
            counts[symbols[m.group(1)] + int(m.group(2), 16)] += 1
    return counts, total


def inline_chains(exe, addresses):
    """The inline chain (innermost first) of (function, file) per address."""
    out = subprocess.run(
        ["addr2line", "-a", "-i", "-f", "-C", "-e", exe] + [hex(a) for a in addresses],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.splitlines()
    chains, current, i = {}, None, 0
    while i < len(out):
        line = out[i]
        if line.startswith("0x") and (i + 1 >= len(out) or not out[i + 1].startswith("0x")):
            current = int(line, 16)
            chains[current] = []
            i += 1
            continue
        if current is not None and i + 1 < len(out):
            chains[current].append((line, out[i + 1].rsplit(":", 1)[0]))
        i += 2
    return chains


def project_frame(chain):
    for function, path in chain:
        for root in PROJECT:
            k = path.find(root)
            if k >= 0:
                return function, path[k:]
    return None


def main():
    exe, data = sys.argv[1], sys.argv[2]
    counts, total = sample_addresses(exe, data, symbol_addresses(exe))
    chains = inline_chains(exe, list(counts))
    parts = collections.Counter()
    functions = collections.Counter()
    for address, n in counts.items():
        frame = project_frame(chains.get(address, []))
        if frame is None:
            parts["outside the project (std, libraries)"] += n
            continue
        function, path = frame
        part = next(
            (name for name, prefixes in PARTS if any(path.startswith(p) for p in prefixes)),
            "other project code",
        )
        parts[part] += n
        functions[f"{re.sub(r'<.*>', '<>', function)[:70]}  ({path})"] += n
    parts["outside the binary (kernel, libc)"] = total - sum(counts.values())
    print(f"{total} samples")
    for name, n in parts.most_common():
        print(f"{100 * n / total:6.2f} %  {name}")
    print("hottest project functions:")
    for name, n in functions.most_common(25):
        print(f"{100 * n / total:6.2f} %  {name}")


if __name__ == "__main__":
    main()
