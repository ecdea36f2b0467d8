"""Meshes with darts (crease lines that end inside the surface), for tests/construction/test_darts.py.

- ``polar_dart``: a disk around a dart vertex v of valence n whose faces are triangles, quads or pentagons
  (``kinds``: the number of ring edges each face has, 1, 2 or 3), rings of quads outside; the crease runs
  from v along the positive x axis to the boundary. The points lie on the valley z = slope |y| (a 90-degree
  dihedral angle at slope 1) whose bottom line only half is tagged, plus noise.
- ``grid_dart``: a quad grid on the same valley with a crease along its middle row from the boundary to a
  dart, and optionally a crease across it (the dart's line then ends at a crossing of two creases).
"""
from __future__ import annotations

import numpy as np

from c1surf.construction.features import SharpFeatures

SHARP = 10.0


def polar_dart(kinds, rings: int = 3, slope: float = 1.0, noise: float = 0.02, seed: int = 0):
    """(points (V, 3), face sizes, face vertices, SharpFeatures, dart vertex)."""
    rng = np.random.default_rng(seed)
    m = int(sum(kinds))  # vertices per ring
    angle = 2 * np.pi * np.arange(m) / m
    points = [np.zeros(3)]
    for r in range(1, rings + 1):
        xy = np.stack([r * np.cos(angle), r * np.sin(angle)], axis=1)
        points += [np.r_[p, slope * abs(p[1])] for p in xy]
    points = np.array(points)
    points[1:] += noise * rng.standard_normal(points[1:].shape)
    ring = lambda r, k: 1 + (r - 1) * m + k % m
    faces, start = [], 0
    for k in kinds:  # the faces around v: (v, ring-1 vertices start .. start + k), counter-clockwise
        faces.append([0] + [ring(1, start + j) for j in range(k + 1)])
        start += k
    for r in range(1, rings):
        faces += [[ring(r, k), ring(r + 1, k), ring(r + 1, k + 1), ring(r, k + 1)] for k in range(m)]
    crease = np.array([[0, ring(1, 0)]] + [[ring(r, 0), ring(r + 1, 0)] for r in range(1, rings)])
    sizes = np.array([len(f) for f in faces])
    features = SharpFeatures(crease, np.full(len(crease), SHARP))
    return points, sizes, np.concatenate(faces), features, 0


def grid_dart(N: int = 8, length: int = 4, cross: bool = False, slope: float = 1.0, noise: float = 0.03, seed: int = 0):
    """(points, face sizes, face vertices, SharpFeatures, dart vertex): the crease along row N / 2 from x = 0
    to x = ``length``; ``cross``: and a crease along column x = 2 from boundary to boundary."""
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(N + 1), np.arange(N + 1), indexing="ij")
    at = lambda a, b: a * (N + 1) + b
    points = np.stack([i, j, slope * np.abs(j - N / 2)], -1).reshape(-1, 3).astype(float)
    points += noise * rng.standard_normal(points.shape)
    faces = [[at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)] for a in range(N) for b in range(N)]
    crease = [[at(a, N // 2), at(a + 1, N // 2)] for a in range(length)]
    if cross:
        crease += [[at(2, b), at(2, b + 1)] for b in range(N)]
    sizes = np.full(len(faces), 4)
    return points, sizes, np.concatenate(faces), SharpFeatures(np.array(crease), np.full(len(crease), SHARP)), at(length, N // 2)
