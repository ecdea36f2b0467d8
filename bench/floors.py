"""How close ``update_points`` is to what its output costs to write: the floor behind issue 15's 10x target.

On the 180,000-quad torus (2,880,000 biquadratic patches, 622 MB of float64
coefficients) this measures, in one process after a first call of each:

- the in-memory conversion (build + N = 2 tessellation, as ``make bench``'s worker) and ``update_points``
  with its stages (``Surface.timings``);
- two floors on the same thread pool, into memory already mapped: filling an array of the patches' size,
  and gathering each patch's 9 refined points straight into such an array with no arithmetic at all
  (what any A2 kernel must read and write), each added to the two Doo-Sabin steps' time;
- the ratio the target asks for (conversion / update_points, at least 10) and the best any kernel
  could give (conversion / floor).

    .venv/bin/python bench/floors.py [--grid 600 300] [--repeats 7]
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from harness.meshes import torus


def _median(run, repeats: int) -> float:
    run()  # first call: pages mapped, faster forms readied
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grid", type=int, nargs=2, default=(600, 300), help="quad torus of NU x NV faces")
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    from c1surf import memory as runtime

    runtime.tune_allocator()  # as the command line and the bench's workers
    from c1surf.api import tessellate_surface
    from c1surf.construction.surface import Surface
    from c1surf.parallel import for_each_range

    points, sizes, corners = torus(*args.grid)
    start = time.perf_counter()
    surface = Surface(sizes, corners, points)
    tessellate_surface(surface, 2)
    convert = time.perf_counter() - start
    rng = np.random.default_rng(1)
    moved = [points * (1.0 + 0.01 * rng.standard_normal((len(points), 1))) for _ in range(2)]
    update = _median(lambda: surface.update_points(moved[rng.integers(2)]), args.repeats)
    stages = {name: surface.timings[f"apply {name}"] for name in ("doo_sabin_1", "doo_sabin_2", "patches")}
    slots = np.ascontiguousarray(np.asarray(surface.stage("patches").parts[0].groups[0][0]).T, dtype=np.intp)
    refined = np.ascontiguousarray(surface.refined_points)
    out = np.empty((slots.shape[0], 9, refined.shape[1]))

    def gather(a: int, b: int) -> None:
        for lo in range(a, b, 1 << 14):  # blocks in cache, as the kernels work
            hi = min(b, lo + (1 << 14))
            np.take(refined, slots[lo:hi], axis=0, out=out[lo:hi], mode="clip")

    fill = _median(lambda: for_each_range(len(out), lambda a, b: out[a:b].fill(1.0), minimum=1), args.repeats)
    gathered = _median(lambda: for_each_range(len(out), gather, minimum=1), args.repeats)
    steps = stages["doo_sabin_1"] + stages["doo_sabin_2"]
    print(f"{len(out):,} biquadratic patches ({out.nbytes / 1e6:.0f} MB), {len(sizes):,} input faces")
    print(f"conversion in memory (build + N=2 tessellation, first call): {convert:.3f} s")
    print(f"update_points: {update:.3f} s (Doo-Sabin steps {steps:.3f} s, patches {stages['patches']:.3f} s): "
          f"{convert / update:.1f}x")
    for name, seconds in (("fill the output", fill), ("gather 9 points per patch into it", gathered)):
        print(f"floor, {name}: {seconds:.3f} s + steps = {seconds + steps:.3f} s: at most {convert / (seconds + steps):.1f}x")


if __name__ == "__main__":
    main()
