"""The edges of the IGES B-rep: ``edge_chains``' chains of patch sides, each with one B-spline curve.

The STEP and IGES B-reps share their edges: ``edge_chains`` joins the patch
sides between the same faces where nothing else meets them (the border
between two merged pieces is one edge, cut only where a third face meets it),
so both files hold the same faces, edges and vertices. This module makes of
the chains a ``BRepTopology`` (edges = chains, vertices = the chain ends, loop
entries = chain uses), which ``iges_brep`` numbers into entities, and gives
each chain its curve for an IGES entity 126:

- a chain of k > 1 quadratic sides that is C1 at every joint with the
  uniform parameters of the pieces (each joint the midpoint of its two
  neighbouring control points, to 1e-12 of the size; homogeneous coordinates
  for rational surfaces) is the clamped quadratic B-spline with knots
  ``0 0 0 1 ... k-1 k k k``: the first side's start, every side's middle
  point and the last side's end, its own points and weights: k + 2 control
  points instead of the 2 k + 1 of the sides one after the other, and the
  piece's own border curve. On c1surf surfaces every chain runs along a
  merged piece's side, which is C1, so this is the curve written;
- a single side keeps its Bezier polygon (knots ``0..0 1..1``);
- any other chain is ``edge_chains.chain_curve``'s exact form, the sides one
  after the other with knots 0, 1, ..., k of multiplicity d.

Its parameter t in [0, k] is side floor(t)'s parameter t - floor(t), as on
the pcurves of the loops (straight segments over [0, k]).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .edge_chains import EdgeChains, chain_curve, edge_chains, inner_vertices
from .topology import BRepTopology

__all__ = ["IgesEdges", "iges_edges"]


@dataclass(frozen=True)
class IgesEdges:
    """The chains as a B-rep, and their curves.

    topology : BRepTopology whose edges are the chains (``edge_patch_side`` of each chain's first side,
        ``edge_reversed``: that side runs against the chain), vertices the chain ends, loop entries the
        chain uses (``loop_uv``: each use's whole segment)
    spans : (E,) int64, sides in each chain: its curve's and pcurves' parameter range is [0, spans]
    curves : list of (chains (n,) int64, degree d, spans k, multiplicity m, points (n, c, 3) float,
        weights (n, c) float or None), one per curve layout: knots d + 1 times 0, m times each of
        1 .. k - 1, d + 1 times k; c = (k - 1) m + d + 1 control points
    """

    topology: BRepTopology
    spans: np.ndarray
    curves: list


def _single_sides(topology: BRepTopology) -> EdgeChains:
    """``edge_chains`` of a topology without inner vertices (no merged piece): every edge its own chain."""
    e = topology.n_edges
    return EdgeChains(np.arange(e + 1), np.arange(e), np.ones(e, dtype=bool), topology.edge_vertices,
                      topology.loop_start, topology.loop_edge, topology.loop_forward, topology.loop_uv)


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


def iges_edges(topology: BRepTopology, polygons: list) -> IgesEdges:
    """The chains of ``topology``'s edges with their curves (module docstring).

    Parameters
    ----------
    topology : BRepTopology (one edge per patch side on a face border)
    polygons : every edge's Bezier control polygon in its direction, by degree: ``iges_brep.edge_polygons``
        (a list of (edges (n,), points (n, d + 1, 3), weights (n, d + 1) or None))

    Returns
    -------
    IgesEdges
    """
    chains = edge_chains(topology) if inner_vertices(topology).any() else _single_sides(topology)
    kept, ends = np.unique(chains.chain_vertices, return_inverse=True)
    first = chains.chain_edges[chains.chain_start[:-1]]
    coarse = BRepTopology(
        topology.face_kind, topology.face_index, topology.face_size, topology.vertex_points[kept],
        ends.reshape(-1, 2).astype(np.int64), topology.edge_patch_side[first],
        topology.edge_reversed[first] ^ ~chains.chain_forward[chains.chain_start[:-1]],
        np.bincount(chains.loop_chain, minlength=chains.n_chains).astype(np.int64), chains.loop_start.astype(np.int64),
        chains.loop_chain.astype(np.int64), chains.loop_forward, chains.loop_uv)
    spans = np.diff(chains.chain_start).astype(np.int64)
    return IgesEdges(coarse, spans, _chain_curves(chains, spans, *_padded(topology.n_edges, polygons), polygons))


def _chain_curves(chains: EdgeChains, spans: np.ndarray, degree: np.ndarray, points: np.ndarray, weights,
                  polygons: list) -> list:
    """``IgesEdges.curves``: the chains grouped by layout, their control points gathered a group at once
    (the few chains that are not C1 quadratic go to ``chain_curve`` one by one)."""
    at = chains.chain_start[:-1]
    low = np.minimum.reduceat(degree[chains.chain_edges], at) if at.size else np.zeros(0, np.int64)
    high = np.maximum.reduceat(degree[chains.chain_edges], at) if at.size else np.zeros(0, np.int64)
    size = float(np.ptp(points[:, 0], axis=0).max()) if len(points) else 1.0
    out, general = [], []
    for d, k in sorted(set(zip(high.tolist(), spans.tolist()))):
        group = np.flatnonzero((high == d) & (spans == k) & (low == d))
        general.extend(np.flatnonzero((high == d) & (spans == k) & (low != d)).tolist())
        if not group.size:
            continue
        entries = at[group, None] + np.arange(k)  # (n, k) positions in chain_edges
        edges, forward = chains.chain_edges[entries], chains.chain_forward[entries]
        net = np.where(forward[..., None, None], points[edges, : d + 1], points[edges, d::-1])  # (n, k, d + 1, 3)
        w = None if weights is None else np.where(forward[..., None], weights[edges, : d + 1], weights[edges, d::-1])
        if k == 1:
            out.append((group, d, 1, d + 1, net[:, 0], None if w is None else w[:, 0]))
            continue
        h = net if w is None else np.concatenate([net * w[..., None], w[..., None]], axis=-1)
        smooth = np.all(np.abs(h[:, :-1, 2] - 0.5 * (h[:, :-1, 1] + h[:, 1:, 1])) <= 1e-12 * max(size, 1.0),
                        axis=(1, 2)) if d == 2 else np.zeros(group.size, dtype=bool)
        general.extend(group[~smooth].tolist())
        if smooth.any():
            take = lambda x: np.concatenate([x[smooth, :1, 0], x[smooth, :, 1], x[smooth, -1:, -1]], axis=1)  # noqa: E731
            out.append((group[smooth], 2, k, 1, take(net), None if w is None else take(w)))
    per_edge = _per_edge(polygons, len(degree)) if general else None
    for c in sorted(general):  # exact, knots of multiplicity d: the sides one after the other
        part = slice(int(chains.chain_start[c]), int(chains.chain_start[c + 1]))
        d, poles, pole_weights, _, _ = chain_curve(chains.chain_edges[part], chains.chain_forward[part], *per_edge)
        out.append((np.array([c]), d, int(spans[c]), d, poles[None], None if pole_weights is None else pole_weights[None]))
    return out


def _per_edge(polygons: list, n_edges: int):
    """``chain_curve``'s inputs: lists of E polygons (d + 1, 3) and weights (d + 1,) (or None), from the groups."""
    curves, weights = [None] * n_edges, (None if not polygons or polygons[0][2] is None else [None] * n_edges)
    for edges, net, w in polygons:
        for k, e in enumerate(edges.tolist()):
            curves[e] = net[k]
            if weights is not None:
                weights[e] = w[k]
    return curves, weights
