"""`--tolerance T` against uniform `--resolution N`: triangles for the same measured chordal error.

For every mesh and tolerance: the tolerance tessellation's triangles and measured chordal error
(``evaluation.tolerance.chordal``: the exact patch against each triangle at its centroid and edge
midpoints, over the output's bounding-box diagonal); the smallest uniform N whose measured error
is at most that (by bisection over N, measuring each candidate the same way) and its triangles;
and the uniform N that the bound of ``evaluation.tolerance.resolution`` needs to *guarantee* T on
every patch (the same guarantee --tolerance gives) and its triangles.

    .venv/bin/python bench/tolerance.py                      # sample meshes and spot, T = 1e-3 and 1e-4
    .venv/bin/python bench/tolerance.py --tolerance 1e-3 sample_meshes/twisted.obj

Prints a Markdown table (docs/tessellation.md's).
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from c1surf.api import surface_from_file
from c1surf.evaluation.adjacency import patch_adjacency
from c1surf.evaluation.tessellate import tessellate_patches
from c1surf.evaluation.tolerance import measured_chordal_error, plan_tolerance, tessellate_plan
from c1surf.evaluation.tolerance.resolution import bound, second_derivative_bounds

ROOT = Path(__file__).resolve().parents[1]
SPOT = ROOT.parent / "shared" / "meshes" / "spot" / "spot_quadrangulated.obj"


def uniform_error(groups, adjacency, weights, n: int, cache: dict) -> tuple:
    """(measured error, triangles) of the uniform tessellation at resolution n."""
    if n not in cache:
        tess = tessellate_patches(groups, adjacency, n, weights)
        cache[n] = (measured_chordal_error(groups, tess, weights), len(tess.triangles))
    return cache[n]


def smallest_uniform(groups, adjacency, weights, target: float, cache: dict) -> int:
    """The smallest N whose measured error is at most ``target``: doubling N - 1 upwards, then bisection."""
    hi = 2
    while uniform_error(groups, adjacency, weights, hi, cache)[0] > target:
        hi = 2 * hi - 1
    lo = max(1, (hi + 1) // 2)  # measured above target (or no mesh at 1)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if uniform_error(groups, adjacency, weights, mid, cache)[0] <= target:
            hi = mid
        else:
            lo = mid
    return hi


def guaranteed_uniform(groups, weights, tau: float) -> int:
    """The smallest uniform N whose bound is at most tau on every patch."""
    bounds = np.concatenate([second_derivative_bounds(g, None if weights is None else weights[k])
                             for k, g in enumerate(groups)])
    m = 1
    while np.any(bound(bounds, np.full((len(bounds), 2), m)) > tau):
        m = max(m + 1, int(m * 1.05))
    while m > 1 and not np.any(bound(bounds, np.full((len(bounds), 2), m - 1)) > tau):
        m -= 1
    return m + 1


def rows(path: Path, tolerances) -> list:
    surface = surface_from_file(str(path))[0]
    groups, weights = [surface.biquadratic, surface.bicubic], surface.patch_weights
    adjacency = patch_adjacency(surface.refined, surface.frames)
    cache: dict = {}
    out = []
    for tolerance in tolerances:
        start = time.perf_counter()
        plan = plan_tolerance(groups, adjacency, tolerance, weights)
        tess = tessellate_plan(groups, plan, weights)
        seconds = time.perf_counter() - start
        error = measured_chordal_error(groups, tess, weights)
        n = smallest_uniform(groups, adjacency, weights, error, cache)
        n_error, n_triangles = uniform_error(groups, adjacency, weights, n, cache)
        g = guaranteed_uniform(groups, weights, tolerance * plan.diagonal)
        out.append(f"| {path.name} | {surface.n_patches} | {tolerance:g} | {len(tess.triangles):,} | {error:.2g} | "
                   f"{n} | {n_triangles:,} | {n_error:.2g} | {n_triangles / len(tess.triangles):.2f} | {g} | "
                   f"{2 * (g - 1) ** 2 * surface.n_patches:,} | {seconds:.2f} |")
        print(out[-1], flush=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("meshes", nargs="*", type=Path)
    parser.add_argument("--tolerance", type=float, action="append")
    args = parser.parse_args()
    meshes = args.meshes or sorted((ROOT / "sample_meshes").glob("*.obj")) + ([SPOT] if SPOT.exists() else [])
    print("| mesh | patches | T | triangles (--tolerance) | measured error | uniform N, same error | its triangles | "
          "its error | ratio | uniform N guaranteeing T | its triangles | seconds (--tolerance) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for path in meshes:
        rows(path, args.tolerance or [1e-3, 1e-4])


if __name__ == "__main__":
    main()
