"""Chains of B-rep edges: the patch sides between the same faces, joined into one edge each.

``topology.brep_topology`` has one edge per patch side on a face border, so a
merged piece's border is cut at every knot, with a vertex at each cut that
only two faces (or, on the surface's boundary, one) share. A CAD system wants
one edge there: Open CASCADE's STEP reader spends its time per edge (spot:
14,139 sides, 12 s to read; 2,720 chains, 4 s), and the files are smaller.

A vertex is *inner* to a chain when exactly two distinct edges end there and
every face loop that passes it goes straight on (the same unit step of its
domain before and after: not a corner of the face), and, on a strip one span
wide in u (the CAD faces, ``merged.cad_patch_set``), along u or on the side
u = 0: the sides across v at u = 1 stay one edge each, since Open CASCADE's
default mass properties integrate along each edge with one Gauss rule over
its whole parameter range, exact over one span only (docs/patch-format.md,
*CAD faces as strips*); along u the pcurves have dv = 0, and at u = 0 the
rule across u has length 0, so they add nothing. Around such a vertex the
two edges split the surface into the two faces on their sides (or one, on a
boundary), so joining the edges keeps the topology: every chain is used by
the same faces as each of its edges. Face corners and vertices where three or
more faces meet end the chains.

A chain runs in the direction of its lowest-numbered edge; its curve is the
edges' Bezier curves one after another (a B-spline with knots 0, 1, ..., k of
multiplicity d: :func:`chain_curve`), and each face's pcurve is the straight
segment of length k of its domain, so parameter t in [0, k] is the same point
on both.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .topology import FACE_PIECE, BRepTopology


@dataclass(frozen=True)
class EdgeChains:
    """C chains of the E topology edges, and each face's loop as M uses of chains.

    chain_start : (C + 1,) int64, chain c is edges chain_edges[chain_start[c]:chain_start[c + 1]]
    chain_edges : (E,) int64, the topology edges, chain by chain, in chain order
    chain_forward : (E,) bool, parallel to chain_edges: the edge runs along its chain
    chain_vertices : (C, 2) int64, start and end topology vertex of each chain
    loop_start : (F + 1,) int64, face f's loop is uses loop_start[f]:loop_start[f + 1]
    loop_chain : (M,) int64, the chain of each use, in loop order
    loop_forward : (M,) bool, the loop runs along the chain
    loop_uv : (M, 2, 2) float, start and end (u, v) of the use in its face's domain, in loop order
    """

    chain_start: np.ndarray
    chain_edges: np.ndarray
    chain_forward: np.ndarray
    chain_vertices: np.ndarray
    loop_start: np.ndarray
    loop_chain: np.ndarray
    loop_forward: np.ndarray
    loop_uv: np.ndarray

    @property
    def n_chains(self) -> int:
        return int(self.chain_vertices.shape[0])

    def edges(self, c: int) -> slice:
        return slice(int(self.chain_start[c]), int(self.chain_start[c + 1]))


def inner_vertices(topology: BRepTopology) -> np.ndarray:
    """(V,) bool: the vertices inside chains (two distinct edges end there, every loop through it goes straight on,
    along u or at u = 0 on a strip face)."""
    n = len(topology.vertex_points)
    ev = topology.edge_vertices
    ends = np.bincount(ev.ravel(), minlength=n)
    closed_edge = np.zeros(n, dtype=bool)
    closed_edge[ev[ev[:, 0] == ev[:, 1], 0]] = True
    step = topology.loop_uv[:, 1] - topology.loop_uv[:, 0]  # (L, 2)
    following = np.arange(len(step)) + 1  # the next entry of the same loop, cyclically
    following[topology.loop_start[1:] - 1] = topology.loop_start[:-1]
    face = np.repeat(np.arange(topology.n_faces), np.diff(topology.loop_start))
    strip = (topology.face_kind == FACE_PIECE) & (topology.face_size[:, 0] == 1)  # one span wide (CAD strips)
    right_side = (step[:, 1] != 0) & (topology.loop_uv[:, 0, 0] != 0)  # across v, not at u = 0 (that adds nothing)
    turning = np.any(step != step[following], axis=1) | (strip[face] & right_side)  # a corner, a strip's u = 1 side
    end = np.where(topology.loop_forward, ev[topology.loop_edge, 1], ev[topology.loop_edge, 0])
    turned = np.zeros(n, dtype=bool)
    turned[end[turning]] = True
    return (ends == 2) & ~closed_edge & ~turned


def edge_chains(topology: BRepTopology) -> EdgeChains:
    """The chains of ``topology``'s edges and the faces' loops over them (see the module docstring)."""
    inner = inner_vertices(topology)
    ev = topology.edge_vertices
    at_vertex = np.full((len(inner), 2), -1, np.int64)  # the two edges at each inner vertex
    for e, ends in enumerate(ev.tolist()):
        for v in ends:
            if inner[v]:
                at_vertex[v, int(at_vertex[v, 0] >= 0)] = e
    chain_of = np.full(topology.n_edges, -1, np.int64)
    starts, edges, forward = [0], [], []
    for e in range(topology.n_edges):
        if chain_of[e] < 0:
            run = _walk(e, ev, inner, at_vertex)
            chain_of[[edge for edge, _ in run]] = len(starts) - 1
            edges.extend(edge for edge, _ in run)
            forward.extend(along for _, along in run)
            starts.append(len(edges))
    chain_start, chain_edges, chain_forward = np.array(starts), np.array(edges, np.int64), np.array(forward, bool)
    first, last = chain_edges[chain_start[:-1]], chain_edges[chain_start[1:] - 1]
    chain_vertices = np.stack([np.where(chain_forward[chain_start[:-1]], ev[first, 0], ev[first, 1]),
                               np.where(chain_forward[chain_start[1:] - 1], ev[last, 1], ev[last, 0])], axis=1)
    along = np.empty(topology.n_edges, bool)
    along[chain_edges] = chain_forward
    inner[chain_vertices[:, 0]] = False  # where _walk cut a chain of inner vertices only (none on c1surf surfaces)
    return EdgeChains(chain_start, chain_edges, chain_forward, chain_vertices,
                      *_chain_loops(topology, inner, chain_of, along))


def _walk(e: int, ev: np.ndarray, inner: np.ndarray, at_vertex: np.ndarray) -> list:
    """The chain through edge ``e`` as [(edge, runs along the chain)], in the direction of ``e``.

    Walks back from ``e``'s start through inner vertices, then forward from
    there; a chain that closes on itself (every vertex inner) is cut at ``e``'s start.
    """
    def step(edge: int, along: bool, backwards: bool):
        v = int(ev[edge, 0] if along == backwards else ev[edge, 1])  # the end walked through
        if not inner[v]:
            return None
        other = int(at_vertex[v, 0] if at_vertex[v, 1] == edge else at_vertex[v, 1])
        other_along = bool(ev[other, 0] == v) != backwards
        return other, other_along

    first, first_along = e, True
    while (previous := step(first, first_along, True)) is not None and previous[0] != e:
        first, first_along = previous
    if previous is not None:  # a closed chain: start it at e
        first, first_along = e, True
    run = [(first, first_along)]
    while (following := step(*run[-1], False)) is not None and following[0] != first:
        run.append(following)
    return run


def _chain_loops(topology: BRepTopology, inner: np.ndarray, chain_of: np.ndarray, along: np.ndarray):
    """Each face's loop as uses of chains: consecutive loop entries through inner vertices become one use.

    Returns (loop_start (F + 1,), loop_chain (M,), loop_forward (M,), loop_uv (M, 2, 2)).
    """
    ev = topology.edge_vertices
    start = np.where(topology.loop_forward, ev[topology.loop_edge, 0], ev[topology.loop_edge, 1])
    first_of_face = np.zeros(len(start), dtype=bool)
    first_of_face[topology.loop_start[:-1][np.diff(topology.loop_start) > 0]] = True
    new_use = first_of_face | ~inner[start]  # a face's loop starts at a corner of its domain: never inner
    use_first = np.flatnonzero(new_use)
    use_last = np.r_[use_first[1:], len(start)] - 1
    loop_chain = chain_of[topology.loop_edge[use_first]]
    loop_forward = topology.loop_forward[use_first] == along[topology.loop_edge[use_first]]
    loop_uv = np.stack([topology.loop_uv[use_first, 0], topology.loop_uv[use_last, 1]], axis=1)
    face_of = np.repeat(np.arange(topology.n_faces), np.diff(topology.loop_start))
    counts = np.bincount(face_of[use_first], minlength=topology.n_faces)
    return np.r_[0, np.cumsum(counts)].astype(np.int64), loop_chain, loop_forward, loop_uv


def chain_curve(edges: np.ndarray, forward: np.ndarray, curves: list, weights: list | None):
    """The B-spline curve of one chain: its edges' Bezier curves one after the other.

    Parameters
    ----------
    edges, forward : (k,) int64 and (k,) bool, the chain's edges in order and whether each runs along it
    curves : list of E arrays (d_e + 1, 3), each edge's control polygon (``topology.edge_curves``)
    weights : None or list of E arrays (d_e + 1,)

    Returns
    -------
    degree : int, the largest of the edges' (lower ones raised, exactly)
    poles : (k d + 1, 3) float; pole_weights : (k d + 1,) float or None
    knots : (k + 1,) float, 0, 1, ..., k; multiplicities : (k + 1,) int, d + 1, d, ..., d, d + 1
    A rational chain's spans are rescaled (a rational Bezier curve does not change when
    its weights are) so that each starts with the weight the one before ends with.
    """
    k = len(edges)
    if k == 1 and weights is None:  # the common case, quickly
        degree = curves[edges[0]].shape[0] - 1
        poles = curves[edges[0]] if forward[0] else curves[edges[0]][::-1]
        return degree, poles, None, np.array([0.0, 1.0]), np.array([degree + 1, degree + 1])
    degree = max(curves[e].shape[0] - 1 for e in edges.tolist())
    spans = []
    for e, along in zip(edges.tolist(), forward.tolist()):
        w = np.ones(curves[e].shape[0]) if weights is None else weights[e]
        h = np.concatenate([curves[e] * w[:, None], w[:, None]], axis=1)  # homogeneous (d_e + 1, 4)
        h = h if along else h[::-1]
        while h.shape[0] - 1 < degree:
            h = _raise_degree(h)
        if spans:
            h = h * (spans[-1][-1, 3] / h[0, 3])
        spans.append(h)
    joined = np.concatenate([spans[0]] + [s[1:] for s in spans[1:]])
    multiplicities = np.full(k + 1, degree)
    multiplicities[[0, -1]] = degree + 1
    pole_weights = None if weights is None else joined[:, 3]
    return degree, joined[:, :3] / joined[:, 3:], pole_weights, np.arange(k + 1, dtype=np.float64), multiplicities


def _raise_degree(h: np.ndarray) -> np.ndarray:
    """One degree more for a Bezier polygon (d + 1, c) -> (d + 2, c): the same curve."""
    d = h.shape[0] - 1
    i = np.arange(1, d + 1)[:, None] / (d + 1)
    return np.concatenate([h[:1], i * h[:-1] + (1 - i) * h[1:], h[-1:]])


__all__ = ["EdgeChains", "edge_chains", "inner_vertices", "chain_curve"]
