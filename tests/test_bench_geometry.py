"""The bench's yardstick of --tolerance (bench/harness/geometry.py): the largest distance to a mesh, exact.

``MeshDistance.max_distance`` searches few vertices first and redoes the largest
bounds with more: it must give exactly the maximum of the full search, which here is
checked against a brute-force minimum over every triangle.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from harness.geometry import MeshDistance, point_triangle_distance  # noqa: E402


def _plane_and_fin(rows: int = 8):
    """(points, triangles): one large flat triangle (its vertices 10 away) and, above it, a vertical fin of small
    triangles: for points just above the plane the nearest vertices are the fin's, the nearest triangle is not."""
    plane = np.array([[-10.0, -10.0, 0.0], [10.0, -10.0, 0.0], [0.0, 10.0, 0.0]])
    y, z = np.meshgrid(np.linspace(-1, 1, rows), np.linspace(0.2, 1.0, rows), indexing="ij")
    fin = np.stack([np.full(y.size, 0.3), y.ravel(), z.ravel()], axis=1)
    i, j = np.meshgrid(np.arange(rows - 1), np.arange(rows - 1), indexing="ij")
    a = (3 + i * rows + j).ravel()
    quads = np.stack([a, a + rows, a + rows + 1, a + 1], axis=1)
    triangles = np.concatenate([[[0, 1, 2]], quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return np.concatenate([plane, fin]), triangles


def _brute_force(points, triangles, queries):
    q = np.repeat(queries, len(triangles), axis=0)
    a, b, c = (np.tile(points[triangles[:, j]], (len(queries), 1)) for j in range(3))
    return point_triangle_distance(q, a, b, c).reshape(len(queries), -1).min(axis=1)


def test_max_distance_is_the_exact_maximum():
    points, triangles = _plane_and_fin()
    rng = np.random.default_rng(3)
    # near the surface, as chordal samples are: just above the plane, under and beside the fin
    queries = np.concatenate([rng.uniform(-1, 1, (400, 2)), rng.uniform(0.001, 0.01, (400, 1))], axis=1)
    exact = _brute_force(points, triangles, queries)
    few = MeshDistance(points, triangles, k=3)
    assert np.all(few(queries) >= exact - 1e-15)  # fewer vertices searched: an upper bound of each distance
    assert few(queries).max() > 10 * exact.max()  # and here a loose one (the bug this guards against)
    assert few.max_distance(queries, k=len(points)) == exact.max()
    assert few.max_distance(queries, k=16) == few(queries, 16).max()
