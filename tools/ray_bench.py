#!/usr/bin/env python3
"""Traversal alone, fspec against Mitsuba 3.9.1 (Embree), on the same rays.

The whole-process comparison (`tools/big_scene_bench.py`) times everything a
render does; this script isolates the ray queries, so that the time split of
a render can be set against what Mitsuba's ray tracer (Embree, through
Mitsuba's `llvm_ad_spectral` variant) needs for the same rays.

Rays: for each scene of `tools/bench_scenes.py`, Mitsuba shoots one camera
ray through the centre of each pixel of a W x W film (the scene's sensor);
at every hit it starts a *bounce ray*, cosine-distributed about the
geometric normal (flipped towards the camera), from the hit point offset
along that normal by 1e-4 of the scene's bounding-box diagonal. The
directions come from a fixed hash of the pixel index, so the rays are the
same on every run. They are written as little-endian `f32` records
(origin xyz, direction xyz) to `OUT/SCENE.rays`, which the Rust benchmark
`cargo bench -p cli --bench rays` reads.

Mitsuba's timings: `scene.ray_intersect_preliminary` (closest hit: distance
and primitive, no shading data) and `scene.ray_test` (any hit) on the whole
batch as one Dr.Jit array, evaluated and synchronised, after two warm-up
calls (the kernel compiled and cached); medians of --repeats, on 1 thread
(`dr.set_thread_count(1)`) and on the machine's cores. Results to
`OUT/mitsuba.json` and stdout as rays per second.

Needs: pip install mitsuba==3.9.1 numpy; Debian's libllvm19
(DRJIT_LIBLLVM_PATH is set to /usr/lib/x86_64-linux-gnu/libLLVM-19.so when
unset).
    python3 tools/bench_scenes.py
    python3 tools/ray_bench.py                      # writes target/ray-bench
    cargo bench -p cli --bench rays                 # fspec on the same rays
"""

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"

# The hash of the bounce directions: two 32-bit integer mixes (Wellons'
# "lowbias32") of the pixel index, as uniform numbers in [0, 1).
MASK32 = 0xFFFFFFFF


def lowbias32(x):
    import numpy as np

    x = x.astype(np.uint64) & MASK32
    x ^= x >> 16
    x = (x * 0x7FEB352D) & MASK32
    x ^= x >> 15
    x = (x * 0x846CA68B) & MASK32
    x ^= x >> 16
    return x


def uniforms(index, salt):
    import numpy as np

    return lowbias32(index * 2 + salt).astype(np.float64) / 2.0**32


def rays_of(scene, mi, dr, width):
    """Bounce rays from the camera hits of a width x width film."""
    import numpy as np

    sensor = scene.sensors()[0]
    n = width * width
    index = np.arange(n, dtype=np.uint64)
    x = (index % width + 0.5) / width
    y = (index // width + 0.5) / width
    position = mi.Point2f(x.astype(np.float32), y.astype(np.float32))
    ray, _ = sensor.sample_ray(0.0, 0.5, position, mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    valid = np.array(si.is_valid(), dtype=bool)
    p = np.stack([np.array(si.p[k], dtype=np.float64) for k in range(3)], axis=1)
    ng = np.stack([np.array(si.n[k], dtype=np.float64) for k in range(3)], axis=1)
    d_cam = np.stack([np.array(ray.d[k], dtype=np.float64) for k in range(3)], axis=1)
    p, ng, d_cam, index = p[valid], ng[valid], d_cam[valid], index[valid]
    # Normals towards the camera.
    flip = np.sum(ng * d_cam, axis=1) > 0
    ng[flip] = -ng[flip]
    # Cosine-distributed directions about the normal (Malley).
    u1, u2 = uniforms(index, 0), uniforms(index, 1)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0, 1 - u1))], axis=1)
    # An orthonormal frame about each normal (Duff et al. 2017).
    sign = np.where(ng[:, 2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + ng[:, 2])
    b = ng[:, 0] * ng[:, 1] * a
    s = np.stack([1 + sign * ng[:, 0] ** 2 * a, sign * b, -sign * ng[:, 0]], axis=1)
    t = np.stack([b, sign + ng[:, 1] ** 2 * a, -ng[:, 1]], axis=1)
    d = local[:, :1] * s + local[:, 1:2] * t + local[:, 2:3] * ng
    bbox = scene.bbox()
    diagonal = float(dr.norm(bbox.max - bbox.min))
    o = p + ng * (1e-4 * diagonal)
    return np.concatenate([o, d], axis=1).astype(np.float32)


def timed(fn, repeats):
    fn()
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), max(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes-dir", default="target/bench-scenes")
    parser.add_argument("--scenes", nargs="+", default=["bunnies", "icospheres", "plyfield"])
    parser.add_argument("--width", type=int, default=512, help="film width and height (rays = hits)")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--out", default="target/ray-bench")
    args = parser.parse_args()
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM)
    import drjit as dr
    import mitsuba as mi
    import numpy as np

    mi.set_variant("llvm_ad_spectral")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cores = os.cpu_count() or 1
    results = {}
    for name in args.scenes:
        path = Path(args.scenes_dir) / name / "scene.xml"
        if not path.is_file():
            sys.exit(f"{path}: missing (run python3 tools/bench_scenes.py first)")
        scene = mi.load_file(str(path))
        rays = rays_of(scene, mi, dr, args.width)
        (out / f"{name}.rays").write_bytes(rays.astype("<f4").tobytes())
        ray = mi.Ray3f(
            mi.Point3f(*(rays[:, k].copy() for k in range(3))),
            mi.Vector3f(*(rays[:, 3 + k].copy() for k in range(3))),
        )
        dr.eval(ray)

        def closest():
            pi = scene.ray_intersect_preliminary(ray, coherent=False)
            dr.eval(pi.t, pi.prim_index)
            dr.sync_thread()

        def shadow():
            blocked = scene.ray_test(ray, coherent=False)
            dr.eval(blocked)
            dr.sync_thread()

        row = {"rays": int(len(rays))}
        for threads in sorted({1, cores}):
            dr.set_thread_count(threads)
            for query, fn in (("closest", closest), ("shadow", shadow)):
                median, lo, hi = timed(fn, args.repeats)
                row[f"{query}_{threads}t_s"] = [median, lo, hi]
                print(
                    f"{name}: {len(rays)} rays, {query}, {threads} thread(s): "
                    f"{len(rays) / median / 1e6:.2f} M rays/s (median {median * 1e3:.1f} ms, "
                    f"{lo * 1e3:.1f}-{hi * 1e3:.1f})",
                    flush=True,
                )
        hits = scene.ray_intersect_preliminary(ray, coherent=False).is_valid()
        row["hit_fraction"] = float(np.mean(np.array(hits, dtype=bool)))
        results[name] = row
    (out / "mitsuba.json").write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
