#!/usr/bin/env python3
"""Time Mitsuba 3's built-in Cornell box in the setting of issue 4's anchor
timings, on the machine at hand, so that `fspec`'s benchmark
(`cargo bench -p simd-tracer --bench cornell`) is compared with Mitsuba on
the same cores.

Setting: `mi.cornell_box()` as it is (perspective camera, Gaussian filter of
standard deviation 0.5 px, diffuse RGB materials and area light upsampled by
the spectral variants), film 512 x 512, 64 spp, path tracer max_depth 5,
2 threads by default. Each variant renders --repeats times; every render is
timed from the call of `mi.render` until its image is in memory
(`dr.eval` + `dr.sync_thread`), so a JIT variant's first render includes
tracing and compiling its kernel, later ones reuse Dr.Jit's kernel cache.
The median of the later renders is the steady-state figure.

Needs: pip install mitsuba==3.9.1; for llvm_ad_spectral Debian's libllvm19
(older libLLVM builds abort in instruction selection).
    python3 tools/mitsuba_bench.py --variant llvm_ad_spectral scalar_spectral
"""

import argparse
import statistics
import time

import drjit as dr
import mitsuba as mi


def time_variant(variant, width, height, spp, max_depth, threads, repeats):
    mi.set_variant(variant)
    dr.set_thread_count(threads)
    d = mi.cornell_box()
    d["sensor"]["film"]["width"] = width
    d["sensor"]["film"]["height"] = height
    d["sensor"]["sampler"]["sample_count"] = spp
    d["integrator"]["max_depth"] = max_depth
    scene = mi.load_dict(d)
    seconds = []
    mean = None
    for seed in range(repeats):
        start = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        seconds.append(time.perf_counter() - start)
        mean = dr.mean(img, axis=None)
    return seconds, mean


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--variant", nargs="+", default=["llvm_ad_spectral"])
    p.add_argument("--width", type=int, default=512)
    p.add_argument("--height", type=int, default=512)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--max-depth", type=int, default=5)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--repeats", type=int, default=6)
    a = p.parse_args()
    for variant in a.variant:
        seconds, mean = time_variant(
            variant, a.width, a.height, a.spp, a.max_depth, a.threads, a.repeats
        )
        later = seconds[1:] or seconds
        print(
            f"{variant}: first {seconds[0]:.2f} s, median of the later "
            f"{len(later)} {statistics.median(later):.2f} s "
            f"(min {min(later):.2f}, max {max(later):.2f}); mean {mean}"
        )


if __name__ == "__main__":
    main()
