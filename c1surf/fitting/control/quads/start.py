"""The simplification's start: the scan as a pure-quad mesh with exactly its topology.

Tarini et al. 2010 start from the triangle mesh turned into quads. Here the triangles are paired into quads where
the pair makes a good quad (``decimated_quads.pair_triangles``: corner angles within 85 degrees of 90, never an
interior vertex left with two edges), and every face, paired quad or lone triangle, is split at its centroid and
edge midpoints (``decimated_quads.split_faces``): about two quads a triangle, every one a quad, the same surface
cut finer, so components, Euler characteristic and rims are the scan's by construction. A scan of many more
triangles than the simplification needs is first decimated with its topology kept (quadric error collapses that
respect the link condition, ``decimated_quads.decimate_scan``, checked; the scan itself when the counts differ).
"""
from __future__ import annotations

import numpy as np

from ..decimated_quads import decimate_scan, mesh_topology, pair_triangles, split_faces
from .quad_mesh import QuadMesh

__all__ = ["quads_from_triangles", "start_mesh", "START_TRIANGLES_PER_FACE"]

START_TRIANGLES_PER_FACE = 4.0  # a scan of more triangles than this many per face wanted is decimated first
START_TRIANGLES = 20_000  # ... to this many at least


def quads_from_triangles(points: np.ndarray, triangles: np.ndarray):
    """(quads (q, 4) int64, points (V', 3) float64): a consistently oriented manifold triangle mesh (t, 3) as pure
    quads of the same topology (module docstring)."""
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    quads, lone = pair_triangles(triangles, points)
    sizes = np.concatenate([np.full(quads.shape[0], 4), np.full(lone.shape[0], 3)])
    vertices = np.concatenate([quads.ravel(), lone.ravel()])
    return split_faces(sizes, vertices, points)


def start_mesh(points: np.ndarray, triangles: np.ndarray, faces: int | None = None):
    """(QuadMesh, triangles used): the scan as quads (module docstring); decimated first to about
    ``START_TRIANGLES_PER_FACE * faces`` triangles (``START_TRIANGLES`` at least) when it has more and the decimation keeps its counts."""
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    wanted = max(START_TRIANGLES, int(START_TRIANGLES_PER_FACE * (faces or 0)))
    if faces is not None and triangles.shape[0] > 1.5 * wanted:
        want = mesh_topology(np.full(triangles.shape[0], 3), triangles.ravel(), points.shape[0])
        for keep_rims in (False, True):
            less = decimate_scan(points, triangles, wanted, keep_rims=keep_rims)
            if mesh_topology(np.full(less[1].shape[0], 3), less[1].ravel(), less[0].shape[0]) == want:
                points, triangles = less
                break
    quads, quad_points = quads_from_triangles(points, triangles)
    return QuadMesh.from_quads(quads, quad_points), triangles.shape[0]
