"""The boundary representation of a patch set, from c1surf's own adjacency: CAD faces, edges, vertices.

STEP and IGES solids need what a generic sewing by tolerance would guess:
which face boundaries are one edge, and where the vertices are. c1surf knows
it: the patch adjacency (``evaluation.adjacency``: one id per shared patch
side and per shared corner) says it exactly, from the construction's
topology, or from the geometry for patch files that carry none.

A CAD face is a merged B-spline piece (``PatchSet.merged``, m x n patches in
the piece's own (u, v), knots 0 .. m and 0 .. n) or a single patch that no
piece covers (over [0, 1]^2), in the order the writers use: pieces first,
then the uncovered patches in file order (``merged.uncovered_groups``).

- **Edges** are the patch sides on the border of a CAD face (sides inside a
  piece are no edges). A side shared by two faces is one edge used twice; a
  side on the surface's boundary is used once. One face may use an edge twice
  (a piece that closes on itself, as around a torus): a seam.
- Each edge runs in its adjacency direction; its curve is the control polygon
  of the first patch side that names it (degree 2 or 3, with weights for
  rational surfaces). The other side's curve is the same to round-off (G0 of
  the construction), so both faces carry the same 3D curve.
- **Vertices** are the patch corners at edge ends, at the corner coefficient.
- **Loops**: one outer loop per face, counter-clockwise in its (u, v) (so the
  face normal is S_u x S_v): along v = 0 with increasing u, along u = max,
  back along v = max, down along u = 0. Each use of an edge records whether
  it runs with the edge, and its straight parameter-space segment (the pcurve)
  from start to end in loop direction.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ....evaluation.adjacency import SIDE_CORNERS, with_seams
from ....evaluation.patch_set import PatchSet

FACE_PIECE, FACE_PATCH = 0, 1


@dataclass(frozen=True)
class BRepTopology:
    """A patch set's B-rep: F faces, E edges, V vertices and L edge uses in the faces' loops.

    face_kind : (F,) int8, FACE_PIECE (a merged piece) or FACE_PATCH (one patch)
    face_index : (F,) int64, index into ``patch_set.merged`` or the patch number (file order)
    face_size : (F, 2) int64, the face's parameter extent (m, n): its domain is [0, m] x [0, n]
    vertex_points : (V, 3) float
    edge_vertices : (E, 2) int64, start and end vertex of each edge, in its direction
    edge_patch_side : (E, 2) int64, the (patch, side) whose side curve is the edge's curve
    edge_reversed : (E,) bool, that side runs (in increasing parameter) against the edge
    edge_uses : (E,) int64, how many loop entries use the edge (2 inside, 1 on a boundary)
    loop_start : (F + 1,) int64, face f's loop is entries loop_start[f]:loop_start[f + 1]
    loop_edge : (L,) int64, the edge of each loop entry, in loop order
    loop_forward : (L,) bool, the loop runs along the edge's direction
    loop_uv : (L, 2, 2) float, start and end (u, v) of the entry in its face's domain, in loop order
    """

    face_kind: np.ndarray
    face_index: np.ndarray
    face_size: np.ndarray
    vertex_points: np.ndarray
    edge_vertices: np.ndarray
    edge_patch_side: np.ndarray
    edge_reversed: np.ndarray
    edge_uses: np.ndarray
    loop_start: np.ndarray
    loop_edge: np.ndarray
    loop_forward: np.ndarray
    loop_uv: np.ndarray

    @property
    def n_faces(self) -> int:
        return int(self.face_kind.size)

    @property
    def n_edges(self) -> int:
        return int(self.edge_vertices.shape[0])

    @property
    def closed(self) -> bool:
        """Every edge is used twice: the faces bound a solid."""
        return bool(self.n_edges) and bool(np.all(self.edge_uses == 2))

    def loop(self, f: int) -> slice:
        return slice(int(self.loop_start[f]), int(self.loop_start[f + 1]))


# For a patch turned k quarter turns (np.rot90(net, k, axes=(0, 1)), as merge_biquadratic turns
# patches into a piece's frame): ROTATED_SIDE[k, s'] is the side of the original patch under side s'
# of the turned one, ROTATED_FLIP[k, s'] whether the two run in opposite parameter directions.
def _rotation_tables():
    net = np.arange(9).reshape(3, 3)
    sides = [lambda a: a[:, 0], lambda a: a[-1, :], lambda a: a[:, -1], lambda a: a[0, :]]
    side, flip = np.zeros((4, 4), np.int64), np.zeros((4, 4), bool)
    for k in range(4):
        turned = np.rot90(net, k=k, axes=(0, 1))
        for s_new in range(4):
            polygon = sides[s_new](turned).tolist()
            for s_old in range(4):
                old = sides[s_old](net).tolist()
                if polygon in (old, old[::-1]):
                    side[k, s_new], flip[k, s_new] = s_old, polygon != old
    return side, flip


ROTATED_SIDE, ROTATED_FLIP = _rotation_tables()
_LOOP_BACKWARD = np.array([False, False, True, True])  # sides 2 and 3 run against increasing parameter


def _border_cells(m: int, n: int):
    """The border spans of an m x n domain in loop order: (i, j, side) arrays and the uv segments.

    Returns
    -------
    i, j, side : (2 m + 2 n,) int64
    uv : (2 m + 2 n, 2, 2) float, start and end of each border span in loop direction
    """
    a, b = np.arange(m), np.arange(n)
    i = np.concatenate([a, np.full(n, m - 1), a[::-1], np.zeros(n, np.int64)])
    j = np.concatenate([np.zeros(m, np.int64), b, np.full(m, n - 1), b[::-1]])
    side = np.repeat([0, 1, 2, 3], [m, n, m, n])
    start = np.concatenate([np.stack([a, 0 * a], 1), np.stack([0 * b + m, b], 1),
                            np.stack([a[::-1] + 1, 0 * a + n], 1), np.stack([0 * b, b[::-1] + 1], 1)])
    step = np.repeat(np.array([[1, 0], [0, 1], [-1, 0], [0, -1]]), [m, n, m, n], axis=0)
    return i, j, side, np.stack([start, start + step], axis=1).astype(np.float64)


def _biquadratic_numbers(patch_set: PatchSet) -> np.ndarray:
    """(Nq,) int64: the file-order patch number of each biquadratic patch (pieces number those)."""
    out, first = [], 0
    for g in patch_set.groups:
        if g.shape[1:3] == (3, 3):
            out.append(np.arange(first, first + len(g)))
        first += len(g)
    return np.concatenate(out) if out else np.zeros(0, np.int64)


def _face_borders(patch_set: PatchSet):
    """Every face's border spans as original (patch, side) and loop data, faces in writer order.

    Returns (face_kind, face_index, face_size, face_of, patch, side, flip, uv): the last five per
    loop entry, ``flip`` meaning the loop's span runs against the patch side's increasing parameter.
    """
    number = _biquadratic_numbers(patch_set)
    kinds, indices, sizes, parts = [], [], [], []
    covered = np.zeros(patch_set.n_patches, dtype=bool)
    for k, piece in enumerate(patch_set.merged):
        m, n = piece.patches.shape
        i, j, side, uv = _border_cells(m, n)
        turns = np.asarray(piece.rotation)[i, j] % 4
        old_side = ROTATED_SIDE[turns, side]
        flip = ROTATED_FLIP[turns, side] ^ _LOOP_BACKWARD[side]
        parts.append((np.full(i.size, len(kinds)), number[np.asarray(piece.patches)[i, j]], old_side, flip, uv))
        covered[number[np.asarray(piece.patches).ravel()]] = True
        kinds.append(FACE_PIECE), indices.append(k), sizes.append((m, n))
    single = np.flatnonzero(~covered)
    i, j, side, uv = _border_cells(1, 1)
    f0 = len(kinds)
    faces = f0 + np.repeat(np.arange(single.size), 4)
    parts.append((faces, np.repeat(single, 4), np.tile(side, single.size), np.tile(_LOOP_BACKWARD, single.size),
                  np.tile(uv, (single.size, 1, 1))))
    face_kind = np.r_[np.array(kinds, np.int8), np.full(single.size, FACE_PATCH, np.int8)]
    face_index = np.r_[np.array(indices, np.int64), single.astype(np.int64)]
    face_size = np.concatenate([np.array(sizes, np.int64).reshape(-1, 2), np.ones((single.size, 2), np.int64)])
    face_of, patch, side, flip, uv = (np.concatenate(c) for c in zip(*parts))
    return face_kind, face_index, face_size, face_of, patch, side, flip, uv


def brep_topology(patch_set: PatchSet, tolerance: float = 1e-9) -> BRepTopology:
    """The B-rep of ``patch_set``: its CAD faces, their loops, shared edges and vertices.

    The adjacency is the patch set's own (the construction's, for a surface
    c1surf made) or, for a file that carries none, the one found from the
    geometry (``PatchSet.welding(tolerance)``, tolerance relative to the size).

    Parameters
    ----------
    patch_set : evaluation.patch_set.PatchSet
    tolerance : float, only for a patch set without adjacency

    Returns
    -------
    BRepTopology
    """
    adjacency = patch_set.welding(tolerance)
    seams = patch_set.crease_sides
    if seams is not None and len(seams):  # C0 creases: their two sides are one B-rep edge
        adjacency = with_seams(adjacency, seams, _same_direction(patch_set, seams))
    face_kind, face_index, face_size, face_of, patch, side, flip, uv = _face_borders(patch_set)
    side_edge = np.asarray(adjacency.edges)[patch, side].astype(np.int64)
    side_reversed = np.asarray(adjacency.reversed)[patch, side]
    forward = ~(flip ^ side_reversed)  # loop direction against the side's, the side's against the edge's

    # B-rep edges: the adjacency edges that lie on some face border, numbered by first use
    used, first_use, edge_of_entry = np.unique(side_edge, return_index=True, return_inverse=True)
    order = np.argsort(first_use, kind="stable")
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    loop_edge = rank[edge_of_entry.ravel()]
    first = first_use[order]  # the entry that defines each edge
    edge_patch_side = np.stack([patch[first], side[first]], axis=1)
    edge_reversed = side_reversed[first]
    edge_uses = np.bincount(loop_edge, minlength=order.size)

    # vertices: the corner ids at the edges' ends, numbered by first appearance
    ends = SIDE_CORNERS[edge_patch_side[:, 1]]  # (E, 2) corner numbers of the side, increasing parameter
    ends = np.where(edge_reversed[:, None], ends[:, ::-1], ends)
    corner_ids = np.asarray(adjacency.corners)[edge_patch_side[:, :1], ends].astype(np.int64)
    corner_of, vertex_first, vertex_of = np.unique(corner_ids.ravel(), return_index=True, return_inverse=True)
    order = np.argsort(vertex_first, kind="stable")
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    edge_vertices = rank[vertex_of.ravel()].reshape(-1, 2)
    vertex_points = _corner_positions(patch_set, np.repeat(edge_patch_side[:, 0], 2).reshape(-1, 2), ends)
    points = np.zeros((order.size, 3))
    points[edge_vertices.ravel()] = vertex_points.reshape(-1, 3)

    loop_start = np.r_[0, np.cumsum(np.bincount(face_of, minlength=face_kind.size))].astype(np.int64)
    return BRepTopology(face_kind, face_index, face_size, points, edge_vertices, edge_patch_side, edge_reversed,
                        edge_uses, loop_start, loop_edge, forward, uv)


def _same_direction(patch_set: PatchSet, seams: np.ndarray) -> np.ndarray:
    """(k,) bool: the two sides of each seam (curve ids) run the same way: the first one's start point is
    nearer the second one's start than its end (the two curves are equal, so this is never close)."""
    patch, side = np.divmod(seams, 4)
    corners = SIDE_CORNERS[side]  # (k, 2, 2): start and end corner of both sides
    start_a = _corner_positions(patch_set, patch[:, 0], corners[:, 0, 0])
    start_b = _corner_positions(patch_set, patch[:, 1], corners[:, 1, 0])
    end_b = _corner_positions(patch_set, patch[:, 1], corners[:, 1, 1])
    return np.linalg.norm(start_a - start_b, axis=-1) <= np.linalg.norm(start_a - end_b, axis=-1)


def _corner_positions(patch_set: PatchSet, patch: np.ndarray, corner: np.ndarray) -> np.ndarray:
    """Positions (..., 3) of corner ``corner`` of patch ``patch`` (same shapes): the corner coefficients."""
    out = np.empty(patch.shape + (3,))
    first = 0
    for g in patch_set.groups:
        inside = (patch >= first) & (patch < first + len(g))
        if inside.any():
            d = g.shape[1] - 1
            local = patch[inside] - first
            c = corner[inside]
            iu = np.array([0, d, d, 0])[c]
            iv = np.array([0, 0, d, d])[c]
            out[inside] = np.asarray(g)[local, iu, iv, :3]
        first += len(g)
    return out


_SIDE_INDEX = {}  # degree -> (4, d + 1, 2) net indices (u, v) of each side's polygon, in increasing parameter


def _side_index(d: int) -> np.ndarray:
    if d not in _SIDE_INDEX:
        t = np.arange(d + 1)
        zero, full = np.zeros_like(t), np.full_like(t, d)
        _SIDE_INDEX[d] = np.stack([np.stack(p, axis=1) for p in ((t, zero), (full, t), (t, full), (zero, t))])
    return _SIDE_INDEX[d]


def edge_polygons(patch_set: PatchSet, topology: BRepTopology) -> list:
    """Every edge's Bezier control polygon in its direction, grouped by degree, gathered at once.

    Returns
    -------
    list of (edges (n,) int64, points (n, d + 1, 3) float, weights (n, d + 1) float or None), one per
    degree present, increasing; every edge in exactly one entry
    """
    patch, side = topology.edge_patch_side[:, 0], topology.edge_patch_side[:, 1]
    by_degree: dict = {}
    first = 0
    for k, g in enumerate(patch_set.groups):
        inside = np.flatnonzero((patch >= first) & (patch < first + len(g)))
        if inside.size:
            d = g.shape[1] - 1
            index = _side_index(d)[side[inside]]  # (n, d + 1, 2)
            index = np.where(topology.edge_reversed[inside, None, None], index[:, ::-1], index)
            local = (patch[inside] - first)[:, None]
            points = np.asarray(g)[local, index[..., 0], index[..., 1], :3]
            weights = None
            if patch_set.weights is not None:
                weights = np.asarray(patch_set.weights[k])[local, index[..., 0], index[..., 1]]
            by_degree.setdefault(d, []).append((inside, points, weights))
        first += len(g)
    out = []
    for d in sorted(by_degree):
        parts = by_degree[d]
        weights = None if parts[0][2] is None else np.concatenate([p[2] for p in parts])
        out.append((np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]).astype(np.float64),
                    weights))
    return out


def edge_curves(patch_set: PatchSet, topology: BRepTopology):
    """Each edge's Bezier control polygon, in the edge's direction, one array per edge (``edge_polygons`` by edge).

    Returns
    -------
    points : list of E arrays (d + 1, 3) float (d = 2 or 3)
    weights : list of E arrays (d + 1,) float, or None for a polynomial surface
    """
    points = [None] * topology.n_edges
    weights = [None] * topology.n_edges if patch_set.weights else None
    for edges, polygons, polygon_weights in edge_polygons(patch_set, topology):
        for e, polygon in zip(edges.tolist(), polygons):
            points[e] = polygon
        if weights is not None:
            for e, w in zip(edges.tolist(), polygon_weights):
                weights[e] = w
    return points, weights


__all__ = ["BRepTopology", "brep_topology", "edge_curves", "edge_polygons", "FACE_PIECE", "FACE_PATCH", "ROTATED_SIDE",
           "ROTATED_FLIP"]
