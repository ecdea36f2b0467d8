"""Maximal B-rep edges: runs of patch sides between the same faces joined into one C1 B-spline edge each.

``topology.brep_topology`` makes every patch side on a face border an edge.
Along the border between two merged pieces that gives one edge per span, and
vertices where nothing but those two edges meet; a CAD system reads a solid
with five times fewer edges and vertices faster (Open CASCADE's fixing passes
cost per edge) and the file is smaller. Here such runs become one edge each:

- A vertex is **dissolved** when exactly two edges meet there, every loop
  that passes it goes straight on in its face's parameter domain (the two
  spans lie on one side of the face's rectangle), both edges are degree 2
  (sides of merged pieces) and the curve is C1 there with the uniform
  parametrization of the pieces: the vertex is the midpoint of its two
  neighbouring control points (to 1e-12 of the size; homogeneous
  coordinates for rational surfaces). Domain corners are never dissolved.
- A **run** is a chain of edges through dissolved vertices; its curve is the
  clamped quadratic B-spline with knots ``0 0 0 1 ... k-1 k k k`` whose
  control points are the first side's start, every side's middle point and
  the last side's end: the same curve as its k Bezier sides, parameter k
  spanning side k. A run that closes on itself (a torus's seam) is one
  closed edge with one vertex.
- A loop entry per run use: its pcurve is the straight segment from the
  first side's start to the last side's end, over [0, k], so it stays
  same-parameter with the curve.

Patch faces (one span a side) and the corners of pieces keep their vertices,
so a set without merged pieces is unchanged.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .topology import BRepTopology

__all__ = ["EdgeRuns", "edge_runs"]


@dataclass(frozen=True)
class EdgeRuns:
    """The B-rep with maximal edges, and each edge's curve.

    topology : BRepTopology whose edges are the runs (``edge_patch_side`` and ``edge_reversed`` of
        each run's first side; ``loop_uv`` the runs' whole segments)
    spans : (E,) int64, patch sides in each run (its curve's and pcurves' parameter range is [0, spans])
    curves : list of (runs (n,) int64, degree d, spans k, points (n, k + d, 3) float, weights (n, k + d)
        float or None), one per (degree, spans) present: every run's B-spline control points
    """

    topology: BRepTopology
    spans: np.ndarray
    curves: list


def _loop_neighbours(topology: BRepTopology):
    """(next, previous) loop entry of every entry, cyclically within its face's loop: (L,) int64 each."""
    n = topology.loop_edge.size
    nxt, prev = np.arange(1, n + 1), np.arange(-1, n - 1)
    nxt[topology.loop_start[1:] - 1] = topology.loop_start[:-1]
    prev[topology.loop_start[:-1]] = topology.loop_start[1:] - 1
    return nxt, prev


def _padded(n_edges: int, polygons: list):
    """Every edge's polygon in one array: degree (E,) int64, points (E, 4, 3) float, weights (E, 4) float or None."""
    degree = np.zeros(n_edges, np.int64)
    points = np.zeros((n_edges, 4, 3))
    weights = None if not polygons or polygons[0][2] is None else np.ones((n_edges, 4))
    for edges, net, w in polygons:
        d = net.shape[1] - 1
        degree[edges], points[edges, : d + 1] = d, net
        if weights is not None:
            weights[edges, : d + 1] = w
    return degree, points, weights


def _oriented(points: np.ndarray, weights, d: int, edges: np.ndarray, forward: np.ndarray):
    """Degree-``d`` polygons (..., d + 1, 3) of ``edges`` run in loop direction, and weights (..., d + 1) or None."""
    net = points[edges, : d + 1]
    net = np.where(forward[..., None, None], net, net[..., ::-1, :])
    if weights is None:
        return net, None
    w = weights[edges, : d + 1]
    return net, np.where(forward[..., None], w, w[..., ::-1])


def _homogeneous(net: np.ndarray, w) -> np.ndarray:
    """(w x, w) of rational polygons, the points themselves of polynomial ones."""
    return net if w is None else np.concatenate([net * w[..., None], w[..., None]], axis=-1)


def _dissolved(topology: BRepTopology, degree: np.ndarray, points: np.ndarray, weights) -> np.ndarray:
    """(V,) bool: the vertices joined away (module docstring), from the loops' straightness and C1 at the vertex."""
    nxt, _ = _loop_neighbours(topology)
    ev, edge, forward = topology.edge_vertices, topology.loop_edge, topology.loop_forward
    end = np.where(forward, ev[edge, 1], ev[edge, 0])  # the vertex between entry k and entry nxt[k]
    step = topology.loop_uv[:, 1] - topology.loop_uv[:, 0]
    keep = np.zeros(len(topology.vertex_points), dtype=bool)
    keep[end[~np.all(step == step[nxt], axis=1)]] = True  # the loop turns (or moves to another side)
    keep[end[(degree[edge] != 2) | (degree[edge[nxt]] != 2)]] = True
    keep |= np.bincount(ev.ravel(), minlength=keep.size) != 2
    candidate = np.flatnonzero(~keep[end])
    if candidate.size:  # C1 with uniform parameters: the vertex halves its two neighbouring control points
        this = _homogeneous(*_oriented(points, weights, 2, edge[candidate], forward[candidate]))
        after = _homogeneous(*_oriented(points, weights, 2, edge[nxt[candidate]], forward[nxt[candidate]]))
        size = float(np.ptp(topology.vertex_points, axis=0).max()) if len(topology.vertex_points) else 1.0
        kink = np.abs(this[:, 2] - 0.5 * (this[:, 1] + after[:, 1])).max(axis=1) > 1e-12 * max(size, 1.0)
        keep[end[candidate[kink]]] = True
    return ~keep


def edge_runs(topology: BRepTopology, polygons: list) -> EdgeRuns:
    """Join ``topology``'s edges into maximal runs (module docstring).

    Parameters
    ----------
    topology : BRepTopology
    polygons : every edge's Bezier control polygon in its direction, by degree:
        ``iges_brep.edge_polygons`` (a list of (edges, points (n, d + 1, 3), weights (n, d + 1) or None))

    Returns
    -------
    EdgeRuns
    """
    degree, points, weights = _padded(topology.n_edges, polygons)
    dissolved = _dissolved(topology, degree, points, weights)
    if not dissolved.any():  # no merged pieces: every edge is a run of one side
        return EdgeRuns(topology, np.ones(topology.n_edges, np.int64),
                        [(e, int(degree[e[0]]), 1, net, w) for e, net, w in polygons])
    ev, edge, forward = topology.edge_vertices, topology.loop_edge, topology.loop_forward
    start = np.where(forward, ev[edge, 0], ev[edge, 1])
    end = np.where(forward, ev[edge, 1], ev[edge, 0])
    # the uses of runs: loop entries from one kept vertex to the next (a loop starts at a domain corner)
    first_of_use = ~dissolved[start]
    use_of_entry = np.cumsum(first_of_use) - 1
    first_entry = np.flatnonzero(first_of_use)
    entries = np.bincount(use_of_entry, minlength=first_entry.size)
    last_entry = first_entry + entries - 1
    # runs: edges linked through dissolved vertices, numbered by their first use (in loop order)
    linked = np.flatnonzero(~first_of_use)
    graph = coo_matrix((np.ones(linked.size), (edge[linked - 1], edge[linked])), shape=(topology.n_edges,) * 2)
    _, run_of_edge = connected_components(graph, directed=False)
    _, defining_use, run_index = np.unique(run_of_edge[edge[first_entry]], return_index=True, return_inverse=True)
    order = np.argsort(defining_use, kind="stable")
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    run_of_use, defining_use = rank[run_index.ravel()], defining_use[order]
    # a use runs with its run when its first side runs as that side does in the run's defining use
    defining = np.zeros(first_entry.size, dtype=bool)
    defining[defining_use] = True
    in_definition = defining[use_of_entry]
    flag_in_definition = np.zeros(topology.n_edges, dtype=bool)
    flag_in_definition[edge[in_definition]] = forward[in_definition]
    use_forward = forward[first_entry] == flag_in_definition[edge[first_entry]]
    kept = np.flatnonzero(~dissolved)
    renumber = np.full(dissolved.size, -1, dtype=np.int64)
    renumber[kept] = np.arange(kept.size)
    first_side = edge[first_entry[defining_use]]
    face_of_entry = np.repeat(np.arange(topology.n_faces), np.diff(topology.loop_start))
    loop_start = np.r_[0, np.cumsum(np.bincount(face_of_entry[first_entry], minlength=topology.n_faces))]
    coarse = BRepTopology(
        topology.face_kind, topology.face_index, topology.face_size, topology.vertex_points[kept],
        renumber[np.stack([start[first_entry[defining_use]], end[last_entry[defining_use]]], axis=1)],
        topology.edge_patch_side[first_side], topology.edge_reversed[first_side],
        np.bincount(run_of_use, minlength=defining_use.size), loop_start.astype(np.int64), run_of_use, use_forward,
        np.stack([topology.loop_uv[first_entry, 0], topology.loop_uv[last_entry, 1]], axis=1))
    spans = entries[defining_use].astype(np.int64)
    return EdgeRuns(coarse, spans, _run_curves(degree, points, weights, edge, forward, first_entry[defining_use], spans))


def _run_curves(degree: np.ndarray, points: np.ndarray, weights, edge: np.ndarray, forward: np.ndarray,
                first: np.ndarray, spans: np.ndarray) -> list:
    """``EdgeRuns.curves``: each run's control points from the sides of its defining use (entries first .. + k).

    A single side keeps its Bezier polygon; k > 1 quadratic sides give the k + 2 points of their
    C1 B-spline: the first start, every middle point, the last end (weights alike).
    """
    out = []
    run_degree = degree[edge[first]]
    for d, k in sorted(set(zip(run_degree.tolist(), spans.tolist()))):
        runs = np.flatnonzero((run_degree == d) & (spans == k))
        at = first[runs, None] + np.arange(k)  # (n, k) loop entries
        net, w = _oriented(points, weights, d, edge[at], forward[at])  # (n, k, d + 1, 3), (n, k, d + 1)
        take = (lambda x: x[:, 0]) if k == 1 else (lambda x: np.concatenate([x[:, :1, 0], x[:, :, 1], x[:, -1:, -1]], axis=1))
        out.append((runs, d, k, np.ascontiguousarray(take(net)), None if w is None else np.ascontiguousarray(take(w))))
    return out
