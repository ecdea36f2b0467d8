"""Numerical check of the dart's hole (construction.stencils.holes.dart) on cells built by hand.

Run from the repository root: ``python docs/research/c0_dart_hole.py``. For n = 3..8 it builds the refined
mesh around an n-sided cell (``tests/construction/dart_cell.py``: n sectors of 5 x 5 points on the valley
z = |y| with noise 0.05, a 90-degree dihedral angle along the positive x axis), the biquadratic patches of
every refined point whose neighbourhood is there (those beside the crease read their own side's mirrors
across it), and the dart's hole. Every pair of patch sides with the same end and middle points is measured
(21 samples): gaps, normal jumps; the crease pieces (one patch on each side of the crease line) apart.
It also prints the twist condition's residual on the crease spoke, P_22,n-1 + P_22,0 - 2 E_n-1 = 2 sigma
(sigma = sum_j (-1)^j E_j, zero for odd n by the least-squares choice, the vertex-enclosure sum for even n).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "construction"))

from dart_cell import crease_pair, dart_cell, measure_pairs, shared_sides, side_samples  # noqa: E402


def main() -> None:
    t = np.linspace(0.0, 1.0, 11)
    print("| n | side pairs | crease pieces | largest gap (of the size) | largest normal jump elsewhere (rad) |"
          " crease spoke's jump at M, middle, S (rad) | residual 2 sigma on the crease spoke |")
    print("|---|---|---|---|---|---|---|")
    for n in range(3, 9):
        cell = dart_cell(n, noise=0.05, seed=n)
        patches = cell["patches"]
        pairs = shared_sides(patches, 1e-9 * cell["size"])
        gaps, jumps = measure_pairs(patches, pairs)
        crease = np.array([crease_pair(p, cell) for p in pairs])
        _, before = side_samples(patches[n - 1], 1, t)
        _, after = side_samples(patches[0], 2, t)
        spoke = np.arctan2(np.linalg.norm(np.cross(before, after), axis=1), np.einsum("md,md->m", before, after))
        c = np.cos(2 * np.pi / n)
        E = (1 - 2 * c / 3) * patches[n - 1][3, 2] + 2 * c / 3 * patches[n - 1][3, 1]
        residual = np.linalg.norm(patches[n - 1][2, 2] + patches[0][2, 2] - 2 * E)
        print(f"| {n} | {len(pairs)} | {crease.sum()} | {gaps.max() / cell['size']:.1e} | {jumps[~crease].max():.1e} |"
              f" {spoke[0]:.2f}, {spoke[5]:.2f}, {spoke[-1]:.0e} | {residual:.1e} |")


if __name__ == "__main__":
    main()
