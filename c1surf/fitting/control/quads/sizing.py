"""The control edge the fit wants at each scan vertex: short where the scan bends or is thin, long where flat.

A quadratic spline over control edges of length h misses a curve of curvature k by about k h^2 / 8 (the sagitta),
so an error e wants h = sqrt(8 e / k) (``curvature_edge``); k is the largest of the scan's normal-variation
curvature (|n_i - n_j| / |p_i - p_j| over the edges at a vertex, averaged) and, on a rim, the rim's own turning
(the outline a flat open scan needs its faces along). Flat parts take at most ``FLAT_EDGE`` of the diagonal.
The thickness guard: a limb of diameter d keeps control edges below ``THIN_EDGE`` d (``control.decimated_quads``'
inward-ray thickness), so it keeps about five faces around.
"""
from __future__ import annotations

import numpy as np

from ..cleanup import edge_keys
from ..decimated_quads import THIN_EDGE, thickness
from ...system import vertex_normals

__all__ = ["edge_sizing", "rim_edges", "FLAT_EDGE"]

FLAT_EDGE = 0.25  # the longest control edge wanted on a flat part, a fraction of the diagonal
SMOOTHING = 2  # averaging passes over the curvature estimate


def rim_edges(triangles: np.ndarray, n_vertices: int) -> np.ndarray:
    """(r, 2) int: the directed boundary edges of a triangle mesh (edges in one triangle)."""
    a, b, key, _ = edge_keys(np.full(triangles.shape[0], 3), triangles.ravel(), n_vertices)
    _, inverse, count = np.unique(key, return_inverse=True, return_counts=True)
    lone = count[inverse] == 1
    return np.stack([a[lone], b[lone]], axis=1)


def _curvature(points, triangles) -> np.ndarray:
    """(m,) float: the normal-variation curvature at each scan vertex, with the rims' turning (module docstring)."""
    n = points.shape[0]
    normals = vertex_normals(points, triangles)
    a, b, key, _ = edge_keys(np.full(triangles.shape[0], 3), triangles.ravel(), n)
    _, first = np.unique(key, return_index=True)
    a, b = a[first], b[first]
    length = np.maximum(np.linalg.norm(points[a] - points[b], axis=1), 1e-300)
    k_edge = np.linalg.norm(normals[a] - normals[b], axis=1) / length
    degree = np.maximum(np.bincount(np.r_[a, b], minlength=n), 1)
    k = np.bincount(np.r_[a, b], weights=np.r_[k_edge, k_edge], minlength=n) / degree
    for _ in range(SMOOTHING):
        k = 0.5 * k + 0.5 * np.bincount(np.r_[a, b], weights=np.r_[k[b], k[a]], minlength=n) / degree
    rim = rim_edges(triangles, n)
    if rim.size:
        after = np.full(n, -1)
        after[rim[:, 0]] = rim[:, 1]
        before = np.full(n, -1)
        before[rim[:, 1]] = rim[:, 0]
        v = rim[:, 0]
        u, w = points[v] - points[before[v]], points[after[v]] - points[v]
        lu, lw = np.linalg.norm(u, axis=1), np.linalg.norm(w, axis=1)
        cos = np.einsum("ij,ij->i", u, w) / np.maximum(lu * lw, 1e-300)
        turning = np.arccos(np.clip(cos, -1, 1)) / np.maximum(0.5 * (lu + lw), 1e-300)
        k[v] = np.maximum(k[v], turning)
    return k


def edge_sizing(points: np.ndarray, triangles: np.ndarray, error: float, thin_edge: float = THIN_EDGE):
    """(curvature_edge (m,), thin_limit (m,)) float: the control edge wanted at each scan vertex for a sagitta of
    ``error`` (an absolute length), at most ``FLAT_EDGE`` of the diagonal, and ``thin_edge`` times the thickness."""
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    k = _curvature(points, triangles)
    curvature_edge = np.minimum(np.sqrt(8.0 * error / np.maximum(k, 1e-300)), FLAT_EDGE * diagonal)
    return curvature_edge, thin_edge * thickness(points, triangles)
