"""Tessellation to a chordal tolerance: per-patch resolutions, welded, without T-junctions.

``plan_tolerance`` picks the segments of every patch from the bound of
``resolution`` (absolute tolerance = T times the bounding-box diagonal of the
patch corners, a lower bound of the surface's and the output's diagonal, so the
error relative to either stays within T), gives every patch side the larger
count of the patches sharing it, and numbers the vertices as
``evaluation.tessellate.welded_grid_from_ids`` does: corners first (by corner
id), then the inner samples of every edge (by edge id, in the edge's own
direction, so both sides of an edge name the same vertices), then the interior
samples of every patch (patch by patch). ``tessellate_plan`` then applies one
``triangulate.Template`` per distinct (m_u, m_v, s_0..s_3) to all its patches at
once (``np.unique`` over the tuples, index arithmetic per template, no loop over
patches) and evaluates every vertex once, from the last patch that has it, with
the Bernstein bases of ``evaluation.bezier`` at scattered samples. Normals are
the exact patch normals, as in the uniform tessellation.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..adjacency import PatchAdjacency
from ..bezier import patch_columns, sample_derivatives, unit_normals
from ..rational import euclidean_derivatives, homogeneous
from ..tessellate import defined_normals
from .resolution import MAX_SEGMENTS, bound, least_triangles, patch_segments, second_derivative_bounds
from .triangulate import template

_CHUNK = 1 << 15  # samples evaluated at once: bounded work arrays (some 50 doubles a sample)


@dataclass(frozen=True)
class TolerancePlan:
    """Segment counts, templates and the welded numbering of a tessellation to a tolerance.

    tolerance : float, relative to ``diagonal``; diagonal : float, of the patch corners' bounding box
    segments : (P, 2) int64, (m_u, m_v) of each patch; sides : (P, 4) int64, segments of each side
    keys : (K, 6) int64, the distinct (m_u, m_v, s_0..s_3); template_of : (P,) int64 row of keys
    corners : (P, 4) int64 compact corner ids; edges : (P, 4) int64; reversed : (P, 4) bool
    edge_base : (n_edges,) int64, vertex of an edge's first inner sample
    interior_base : (P,) int64, vertex of a patch's first interior sample
    triangle_start : (P + 1,) int64, first triangle of each patch (patch order), then the count
    n_vertices : int
    """

    tolerance: float
    diagonal: float
    segments: np.ndarray
    sides: np.ndarray
    keys: np.ndarray
    template_of: np.ndarray
    corners: np.ndarray
    edges: np.ndarray
    reversed: np.ndarray
    edge_base: np.ndarray
    interior_base: np.ndarray
    triangle_start: np.ndarray
    n_vertices: int

    @property
    def n_patches(self) -> int:
        return int(self.segments.shape[0])

    @property
    def n_triangles(self) -> int:
        return int(self.triangle_start[-1])

    def blocks(self):
        """Yield (template, patches (n,) int64, vertex ids (n, L) int64) for every distinct tuple.

        Row r of the ids names the global vertex of each local sample of patch ``patches[r]``.
        """
        order = np.argsort(self.template_of, kind="stable")
        bounds = np.searchsorted(self.template_of[order], np.arange(len(self.keys) + 1))
        for t, key in enumerate(self.keys.tolist()):
            patches = order[bounds[t] : bounds[t + 1]]
            yield template(tuple(key)), patches, self.vertex_ids(template(tuple(key)), patches)

    def vertex_ids(self, tpl, patches: np.ndarray) -> np.ndarray:
        """(n, L) int64: global vertex of every local sample of ``tpl`` on ``patches`` (all of its tuple)."""
        ids = np.empty((patches.size, tpl.uv.shape[0]), dtype=np.int64)
        ids[:, :4] = self.corners[patches]
        for s, count in enumerate(tpl.key[2:]):
            k = np.arange(1, count)  # sample k of the side is sample k-1 of its edge, or count-1-k against it
            back = self.reversed[patches, s][:, None]
            start = self.edge_base[self.edges[patches, s]][:, None]
            ids[:, tpl.side_start[s] : tpl.side_start[s] + count - 1] = start + np.where(back, count - 1 - k, k - 1)
        ids[:, tpl.interior_start :] = self.interior_base[patches, None] + np.arange(tpl.n_interior)
        return ids


def corner_diagonal(groups) -> float:
    """Bounding-box diagonal of the patch corners (x, y, z): on the surface and vertices of every tessellation."""
    corners = [np.asarray(g)[:, [0, -1, -1, 0], [0, 0, -1, -1], :3].reshape(-1, 3) for g in groups if len(g)]
    if not corners:
        return 0.0
    points = np.concatenate(corners)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def plan_tolerance(groups, adjacency: PatchAdjacency, tolerance: float, weights=None, budget=None) -> TolerancePlan:
    """Segments, side counts, templates and vertex numbering for a relative ``tolerance``.

    Parameters
    ----------
    groups : list of (p_k, d_k+1, d_k+1, dim) float, patches in adjacency order
    adjacency : PatchAdjacency of the sum p_k patches
    tolerance : float > 0, chordal error relative to the bounding-box diagonal
    weights : None or a list parallel to ``groups`` of (p_k, d_k+1, d_k+1) float (rational, A2a)
    budget : None or a callable given a lower bound of the vertex count (the cells of the fewest segments each
        patch needs) before the costly steps (side counts, templates), which may raise to refuse: a memory guard

    Returns
    -------
    TolerancePlan; a ValueError when some patch would need more than MAX_SEGMENTS segments a side
    """
    tolerance = float(tolerance)
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"the tolerance must be a positive finite number, got {tolerance}")
    diagonal = corner_diagonal(groups)
    bounds = np.concatenate([second_derivative_bounds(g, None if weights is None else weights[k])
                             for k, g in enumerate(groups)] or [np.zeros((0, 3))])
    tau = tolerance * diagonal if diagonal > 0 else tolerance
    corners, edges = _compact(adjacency.corners), _compact(adjacency.edges)
    with np.errstate(over="ignore", divide="ignore"):  # a tau near 0 asks for more segments than exist: refused below
        fewest = patch_segments(bounds, tau)
        if budget is not None:  # least_triangles only raises counts: at least one vertex per cell of these
            budget(int(np.prod(fewest, axis=1).sum()))
        segments, sides, per_edge = least_triangles(fewest, bounds, tau, edges)
    if np.any(bound(bounds, segments) > tau * (1 + 1e-12)):
        raise ValueError(f"a chordal error of {tolerance:g} of the diagonal needs more than {MAX_SEGMENTS} segments on "
                         "a patch side: give a larger tolerance")
    keys, template_of = np.unique(np.concatenate([segments, sides], axis=1), axis=0, return_inverse=True)
    template_of = template_of.reshape(-1)
    tpls = [template(tuple(k)) for k in keys.tolist()]
    n_corners = int(corners.max()) + 1 if corners.size else 0
    edge_base = n_corners + np.concatenate([[0], np.cumsum(np.maximum(per_edge - 1, 0))]).astype(np.int64)
    interior = np.array([t.n_interior for t in tpls], dtype=np.int64)[template_of]
    interior_base = edge_base[-1] + np.concatenate([[0], np.cumsum(interior)]).astype(np.int64)
    triangles = np.array([t.triangles.shape[0] for t in tpls], dtype=np.int64)[template_of]
    triangle_start = np.concatenate([[0], np.cumsum(triangles)]).astype(np.int64)
    return TolerancePlan(tolerance, diagonal, segments, sides, keys.astype(np.int64), template_of.astype(np.int64),
                         corners, edges, np.asarray(adjacency.reversed, dtype=bool), edge_base[:-1],
                         interior_base[:-1], triangle_start, int(interior_base[-1]))


def _compact(ids) -> np.ndarray:
    """(P, 4) int64 ids renumbered 0, 1, ... without unused ones (a no-op for the dense ids of c1surf)."""
    ids = np.asarray(ids, dtype=np.int64)
    if ids.size == 0 or np.all(np.bincount(ids.ravel()) > 0):
        return ids
    return np.unique(ids, return_inverse=True)[1].reshape(ids.shape)


@dataclass(frozen=True)
class ToleranceTessellation:
    """A triangle mesh sampled from the patches at per-patch resolutions.

    points : (V, dim) float; normals : (V, 3) float (exact); triangles : (T, 3) int, counter-clockwise
    from outside, patch by patch (int32 below 2^31 vertices); plan : the TolerancePlan it follows
    """

    points: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    plan: TolerancePlan

    @property
    def triangle_patch(self) -> np.ndarray:
        """(T,) int64: patch index of each triangle."""
        return np.repeat(np.arange(self.plan.n_patches), np.diff(self.plan.triangle_start))

    def triangle_parameters(self) -> np.ndarray:
        """(T, 3, 2) float: (u, v) of each triangle corner in the triangle's patch."""
        out = np.empty((self.triangles.shape[0], 3, 2))
        for tpl, patches, _ in self.plan.blocks():
            rows = self.plan.triangle_start[patches, None] + np.arange(tpl.triangles.shape[0])
            out[rows] = tpl.uv[tpl.triangles]
        return out


def tessellate_to_tolerance(groups, adjacency: PatchAdjacency, tolerance: float, weights=None) -> ToleranceTessellation:
    """Welded tessellation whose chordal error is at most ``tolerance`` times the bounding-box diagonal.

    Parameters as ``plan_tolerance``; the result as ``tessellate_plan``.
    """
    return tessellate_plan(groups, plan_tolerance(groups, adjacency, tolerance, weights), weights)


def tessellate_plan(groups, plan: TolerancePlan, weights=None) -> ToleranceTessellation:
    """Triangles of every template block and every vertex evaluated once (points (V, dim), exact normals)."""
    groups = [np.asarray(g, dtype=np.float64) for g in groups]
    dtype = np.int32 if plan.n_vertices < 2**31 else np.int64
    triangles = np.empty((plan.n_triangles, 3), dtype=dtype)
    owner = np.empty(plan.n_vertices, dtype=np.int64)  # patch the vertex is evaluated from
    owner_uv = np.empty((plan.n_vertices, 2))
    for tpl, patches, ids in plan.blocks():
        rows = plan.triangle_start[patches, None] + np.arange(tpl.triangles.shape[0])
        triangles[rows.ravel()] = ids[:, tpl.triangles].reshape(-1, 3)
        flat = ids.ravel()  # in order: the last patch holding a vertex evaluates it
        owner[flat] = np.repeat(patches, tpl.uv.shape[0])
        owner_uv[flat] = np.tile(tpl.uv, (patches.size, 1))
    points, normals = evaluate_samples(groups, owner, owner_uv[:, 0], owner_uv[:, 1], weights)
    return ToleranceTessellation(points, defined_normals(points, normals, triangles), triangles, plan)


def evaluate_samples(groups, patch: np.ndarray, u: np.ndarray, v: np.ndarray, weights=None):
    """Points (m, dim) and unit normals (m, 3) at samples (global patch index, u, v).

    Every column of the patches is evaluated (attribute columns ride along); rational
    patches in homogeneous coordinates and the quotient rule (``evaluation.rational``).
    Normals are NaN where x_u x x_v vanishes (``tessellate.defined_normals`` fills them).
    """
    dim = groups[0].shape[-1]
    points, normals = np.empty((patch.size, dim)), np.empty((patch.size, 3))
    start = 0
    for k, group in enumerate(groups):
        stop = start + len(group)
        which = np.flatnonzero((patch >= start) & (patch < stop))
        if which.size:
            h = group if weights is None else homogeneous(group, weights[k])
            columns = patch_columns(h)
            for lo in range(0, which.size, _CHUNK):
                rows = which[lo : lo + _CHUNK]
                d = sample_derivatives(columns, patch[rows] - start, u[rows], v[rows], ((0, 0), (1, 0), (0, 1)))
                if weights is not None:
                    d = euclidean_derivatives(d)
                points[rows] = d[(0, 0)]
                normals[rows] = unit_normals(d[(1, 0)][:, :3], d[(0, 1)][:, :3])
        start = stop
    return points, normals


__all__ = ["TolerancePlan", "ToleranceTessellation", "plan_tolerance", "tessellate_plan", "tessellate_to_tolerance",
           "evaluate_samples", "corner_diagonal"]
