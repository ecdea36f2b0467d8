"""Tangential smoothing projected onto the scan: the quads even out, the control points stay on the scan.

Tarini et al. 2010 interleave their operations with smoothing in tangent space; it is what makes the next
operations' choices (the shortest diagonal, the strips to collapse) meaningful. One step: every interior vertex
moves halfway to the mean of its edge neighbours, along the mesh's tangent plane there; a rim vertex to the mean
of its two rim neighbours; then interior vertices go onto the tangent plane of their nearest scan vertex (the exact closest point
of the scan's triangles, ``deviation.closest_on_triangles``, once at the end: ``ScanTarget.onto_surface``) and rim vertices to the closest point of the scan's rims, so rims stay rims.
A vertex whose move folds a face (its normal turned by more than 90 degrees) stays where it was. Vectorized over
the live faces; the topology is not touched.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ...deviation import closest_on_triangles
from .quad_mesh import QuadMesh

__all__ = ["ScanTarget", "smooth"]

STEP = 0.5  # the share of the way to the neighbours' mean a step moves
RIM_CANDIDATES = 8  # the rim segments tried for each rim vertex (nearest midpoints)


class ScanTarget:
    """The scan's triangles and rim segments, for projecting control points back onto them."""

    def __init__(self, points: np.ndarray, triangles: np.ndarray, rim: np.ndarray):
        from ...system import vertex_normals

        self.points, self.triangles = points, triangles
        self.tree, self.normals = cKDTree(points), vertex_normals(points, triangles)
        self.rim_start, self.rim_end = points[rim[:, 0]], points[rim[:, 1]]
        self.rim_tree = cKDTree(0.5 * (self.rim_start + self.rim_end)) if rim.size else None

    def onto_surface(self, query: np.ndarray) -> np.ndarray:
        """(n, 3): the closest points of the scan's triangles (exact; ``deviation.closest_on_triangles``)."""
        return closest_on_triangles(query, self.points, self.triangles)[1] if query.size else query

    def onto_tangent(self, query: np.ndarray) -> np.ndarray:
        """(n, 3): the points moved onto the tangent plane of their nearest scan vertex (a first-order projection,
        a KD-tree query: what each smoothing step uses; ``onto_surface`` once at the end)."""
        if not query.size:
            return query
        _, near = self.tree.query(query)
        n = self.normals[near]
        return query - np.einsum("ij,ij->i", query - self.points[near], n)[:, None] * n

    def onto_rims(self, query: np.ndarray) -> np.ndarray:
        """(n, 3): the closest points of the scan's rims (the query itself when the scan has none)."""
        if self.rim_tree is None or not query.size:
            return query
        k = min(RIM_CANDIDATES, self.rim_start.shape[0])
        _, near = self.rim_tree.query(query, k=k)
        near = near.reshape(query.shape[0], k)
        a, b = self.rim_start[near], self.rim_end[near]
        ab = b - a
        t = np.einsum("ijk,ijk->ij", query[:, None] - a, ab) / np.maximum(np.einsum("ijk,ijk->ij", ab, ab), 1e-300)
        closest = a + np.clip(t, 0, 1)[..., None] * ab
        best = np.argmin(np.linalg.norm(closest - query[:, None], axis=2), axis=1)
        return closest[np.arange(query.shape[0]), best]


def _neighbour_means(quads: np.ndarray, points: np.ndarray):
    """(mean of edge neighbours (V, 3), mean of rim neighbours (V, 3), on_rim (V,) bool, normals (V, 3))."""
    n = points.shape[0]
    a, b = quads.ravel(), np.roll(quads, -1, axis=1).ravel()
    directed = a * n + b
    twin = np.isin(b * n + a, directed)
    lone = ~twin
    on_rim = np.zeros(n, dtype=bool)
    on_rim[a[lone]] = True
    ends = np.r_[a, b]
    others = np.r_[b, a]
    weight = np.r_[np.where(twin, 0.5, 1.0), np.where(twin, 0.5, 1.0)]  # an interior edge appears twice
    mean = _average(ends, others, weight, points)
    rim_mean = _average(np.r_[a[lone], b[lone]], np.r_[b[lone], a[lone]], np.ones(2 * lone.sum()), points)
    face_normal = np.cross(points[quads[:, 2]] - points[quads[:, 0]], points[quads[:, 3]] - points[quads[:, 1]])
    normals = np.zeros((n, 3))
    np.add.at(normals, quads.ravel(), np.repeat(face_normal, 4, axis=0))
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    return mean, rim_mean, on_rim, normals


def _average(ends, others, weight, points):
    """(V, 3): the weighted mean of points[others] grouped by ends (zero where a vertex has none)."""
    total = np.bincount(ends, weights=weight, minlength=points.shape[0])
    mean = np.stack([np.bincount(ends, weights=weight * points[others, c], minlength=points.shape[0])
                     for c in range(3)], axis=1)
    return mean / np.maximum(total, 1e-300)[:, None]


def smooth(mesh: QuadMesh, target: ScanTarget, steps: int = 2, fixed: np.ndarray | None = None) -> None:
    """``steps`` steps of the module docstring's smoothing on ``mesh.points`` (in place); ``fixed`` (V,) bool:
    vertices that do not move."""
    quads = mesh.live_quads()
    used = np.unique(quads)
    for _ in range(steps):
        points = mesh.points
        mean, rim_mean, on_rim, normals = _neighbour_means(quads, points)
        move = mean - points
        move -= np.einsum("ij,ij->i", move, normals)[:, None] * normals
        new = points + STEP * move
        new[on_rim] = points[on_rim] + STEP * (rim_mean[on_rim] - points[on_rim])
        inside = used[~on_rim[used]]
        rims = used[on_rim[used]]
        new[inside] = target.onto_tangent(new[inside])
        new[rims] = target.onto_rims(new[rims])
        if fixed is not None:
            new[fixed] = points[fixed]
        mesh.points[:] = _unfolded(quads, points, new)


def _unfolded(quads, old, new, rounds: int = 4):
    """(V, 3): ``new``, except at the vertices of faces whose normal turned by more than 90 degrees (and again,
    up to ``rounds`` times, for the faces that reverting made fold)."""
    out = new.copy()
    before = np.cross(old[quads[:, 2]] - old[quads[:, 0]], old[quads[:, 3]] - old[quads[:, 1]])
    for _ in range(rounds):
        after = np.cross(out[quads[:, 2]] - out[quads[:, 0]], out[quads[:, 3]] - out[quads[:, 1]])
        folded = np.einsum("ij,ij->i", before, after) <= 0
        if not folded.any():
            break
        back = np.unique(quads[folded])
        out[back] = old[back]
    return out
