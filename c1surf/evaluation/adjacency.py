"""Patch adjacency as plain arrays: which corners and which sides patches share.

Every patch has four corners and four sides, numbered in parameter space::

    corner 0: (u, v) = (0, 0)    side 0: v = 0, u from 0 to 1 (corner 0 -> corner 1)
    corner 1: (1, 0)             side 1: u = 1, v from 0 to 1 (corner 1 -> corner 2)
    corner 2: (1, 1)             side 2: v = 1, u from 0 to 1 (corner 3 -> corner 2)
    corner 3: (0, 1)             side 3: u = 0, v from 0 to 1 (corner 0 -> corner 3)

``corners[p, c]`` names the surface point at corner ``c`` of patch ``p`` (all
patches meeting there carry the same id), ``edges[p, s]`` the patch edge under
side ``s`` (the two patches sharing it carry the same id), and
``reversed[p, s]`` says that side ``s``, run in increasing parameter, goes
against the edge's own direction.

The numbering is canonical, so it can be derived from the construction's
bookkeeping (``patch_adjacency``) or from the patch geometry alone
(``adjacency_from_geometry``) with the same result: ids are numbered in order
of first appearance, scanning patches in file order and corners / sides 0..3
within a patch, and every edge runs in the direction of its first appearance.
The welded tessellation (``evaluation.tessellate.welded_grid_from_ids``) needs
nothing else, so a patch file that stores these arrays can be tessellated
exactly as ``convert`` does.

This numbering is the only one: the tessellation's side kernels
(``side_offsets``), the smoothness check and the renderer's hops across
patch sides use it, and ``match_patch_sides`` is the one geometric matcher
(the smoothness check, ``adjacency_from_geometry`` and the renderer, when a
patch file carries no adjacency, all use it).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ..mesh.halfedges import component_roots
from ..parallel import run_tasks
from .bezier import bernstein_basis
from .rational import dehomogenize, homogeneous
from .sides.matching import SIDE_CORNERS, SideMatching, match_sides


@dataclass(frozen=True)
class PatchAdjacency:
    """Shared corners and sides of P patches.

    corners : (P, 4) int (int32 from the construction while it fits), corner ids, dense 0..n_corners-1
    edges : (P, 4) int (as corners), edge ids, dense 0..n_edges-1
    reversed : (P, 4) bool
    (edges and reversed are None in the corners-only adjacency of a tessellation at resolution 2, which
    numbers no edge samples: ``adjacency_from_corner_labels``)
    """

    corners: np.ndarray
    edges: np.ndarray
    reversed: np.ndarray

    @property
    def n_patches(self) -> int:
        return int(self.corners.shape[0])

    @property
    def n_corners(self) -> int:
        return int(self.corners.max()) + 1 if self.corners.size else 0

    @property
    def n_edges(self) -> int:
        if self.edges is None:
            raise ValueError("internal: this adjacency was made with its corners only")
        return int(self.edges.max()) + 1 if self.edges.size else 0

    def neighbours(self) -> np.ndarray:
        """(P, 4, 2) int64: (patch, side) on the other side of each side; (-1, -1) on a boundary.

        An edge used by more than two sides (not a surface) gets no neighbours.
        """
        return neighbour_rows(self.partners())

    def partners(self) -> np.ndarray:
        """(4 P,) int (int32 below 2^31 sides, else int64): the flat side (patch * 4 + side) across each flat
        side, -1 on a boundary or on an edge of more than two sides; ``neighbour_rows`` turns it into
        ``neighbours()``, a block at a time if need be.

        Made by blocks of sides: besides the result, two (n_edges,) tables of its type and two of bool.
        """
        flat = self.edges.reshape(-1)
        sides = flat.size
        index = np.int32 if sides < 2**31 else np.int64
        out = np.full(sides, -1, dtype=index)
        if sides == 0:
            return out
        step = 4 * _ADJACENCY_BLOCK
        first = np.full(self.n_edges, sides, dtype=index)  # the lowest position of each edge (none: sides)
        last = np.full(self.n_edges, -1, dtype=index)  # the highest (none: -1)
        for z in range(sides, 0, -step):  # from the end, each block backwards: the lowest is written last
            a = max(0, z - step)
            first[flat[a:z][::-1]] = np.arange(z - 1, a - 1, -1, dtype=index)
        for a in range(0, sides, step):  # in order: the highest is written last
            last[flat[a : a + step]] = np.arange(a, min(a + step, sides), dtype=index)
        more = np.zeros(self.n_edges, dtype=bool)  # a side between the first and the last: more than two
        for a in range(0, sides, step):
            block, position = flat[a : a + step], np.arange(a, min(a + step, sides), dtype=index)
            more[block[(np.take(first, block) != position) & (np.take(last, block) != position)]] = True
        pair = (last > first) & ~more
        del more
        for a in range(0, self.n_edges, step):
            both = np.flatnonzero(pair[a : a + step]) + a
            out[first[both]] = last[both]
            out[last[both]] = first[both]
        return out

    def validate(self, n_patches: int | None = None) -> None:
        """ValueError unless the arrays have the documented shapes and dense ids."""
        for name in ("corners", "edges", "reversed"):
            a = getattr(self, name)
            if a.ndim != 2 or a.shape[1] != 4 or a.shape[0] != self.corners.shape[0]:
                raise ValueError(f"adjacency {name} must have shape (P, 4), got {a.shape}")
        if n_patches is not None and self.n_patches != n_patches:
            raise ValueError(f"adjacency describes {self.n_patches} patches, the file has {n_patches}")
        for name in ("corners", "edges"):
            a = getattr(self, name)
            if not a.size:
                continue
            if a.min() < 0 or a.max() >= a.size or not np.all(np.bincount(a.ravel()) > 0):  # dense: max < size
                raise ValueError(f"adjacency {name} must be numbered 0, 1, 2, ... without gaps")
            if name == "edges" and np.bincount(a.ravel()).max() > 2:
                raise ValueError("an edge is shared by more than two patch sides")

    def __eq__(self, other) -> bool:
        if not isinstance(other, PatchAdjacency):
            return NotImplemented
        return all(np.array_equal(getattr(self, k), getattr(other, k)) for k in ("corners", "edges", "reversed"))

    __hash__ = None



def neighbour_rows(partners: np.ndarray) -> np.ndarray:
    """(c, 4, 2) int64 (patch, side) rows of ``PatchAdjacency.neighbours()`` from (4 c,) of its ``partners()``."""
    partners = np.asarray(partners, dtype=np.int64)
    out = np.stack([partners >> 2, partners & 3], axis=1)
    out[partners < 0] = -1
    return out.reshape(-1, 4, 2)

def _first_appearance(labels: np.ndarray) -> np.ndarray:
    """Renumber arbitrary integer labels 0, 1, 2, ... in order of first appearance (row-major)."""
    return _first_appearances(labels)[0]


def _first_appearances(labels: np.ndarray):
    """(ids, first): labels renumbered 0, 1, 2, ... in order of first appearance (row-major), and
    first (k,) int64, the flat position where id i appears first (increasing)."""
    flat = labels.ravel()
    if flat.size == 0:
        return np.zeros(labels.shape, dtype=np.int64), np.zeros(0, dtype=np.int64)
    # int32 ids and positions when they fit: these arrays are 4 entries per patch
    index = np.int32 if flat.size < 2**31 else np.int64
    if flat.min() < 0 or flat.max() >= 4 * flat.size + 1024:  # sparse or negative labels: sort
        _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
        order = np.argsort(first, kind="stable")
        rank = np.empty(first.size, dtype=np.int64)
        rank[order] = np.arange(first.size)
        return rank[inverse.ravel()].reshape(labels.shape), first[order]
    # dense labels: a reverse scatter finds each label's first position; those positions, in
    # order, name the new ids (a scatter and gather of k labels instead of a cumsum over all)
    first_at = np.full(int(flat.max()) + 1, flat.size, dtype=index)
    first_at[flat[::-1]] = np.arange(flat.size, dtype=index)[::-1]
    is_first = np.zeros(flat.size + 1, dtype=bool)
    is_first[first_at] = True
    first = np.flatnonzero(is_first[:-1])
    new_id = first_at  # reused: only entries of labels that occur are read back
    new_id[np.take(flat, first)] = np.arange(first.size, dtype=index)
    return np.take(new_id, flat).reshape(labels.shape), first


def _edge_ids(edge_labels: np.ndarray, forward_key: np.ndarray):
    """(edges, reversed): canonical edge ids and directions (see ``_canonical``)."""
    edges, first = _first_appearances(edge_labels)
    key = forward_key.ravel()
    # a side is reversed when its key differs from that of the edge's first side
    reversed_ = (key != np.take(np.take(key, first), edges.ravel())).reshape(edges.shape)
    return edges, reversed_


def _canonical(corner_labels: np.ndarray, edge_labels: np.ndarray, forward_key: np.ndarray) -> PatchAdjacency:
    """Canonical adjacency from arbitrary labels.

    forward_key : (P, 4) int; two sides of one edge run the same way iff their keys are equal.
    """
    corners, (edges, reversed_) = run_tasks([lambda: _first_appearance(corner_labels),
                                             lambda: _edge_ids(edge_labels, forward_key)])
    return PatchAdjacency(corners, edges, reversed_)


# Patches per block of ``patch_adjacency``'s gathers: block-sized temporaries instead of (P, 4) ones.
_ADJACENCY_BLOCK = 1 << 16


def patch_adjacency(refined, frames) -> PatchAdjacency:
    """Adjacency of the patches of a construction, from its refined mesh.

    Patches are dual to the refined mesh: a patch sits at a 4-valent refined vertex with outgoing half-edges
    e0..e3 (counter-clockwise), its corners are the refined faces around the vertex and its sides cross e0..e3.

    Parameters
    ----------
    refined : HalfEdgeMesh, the twice-refined mesh (its ``face`` and ``twin`` are read)
    frames : (P, 4) int, half-edges e0..e3 of each patch, in patch order; or a sequence of (p_k, 4) int
        arrays standing for their concatenation (``(quad_frames, cubic_frames)``: no (P, 4) copy made)

    Returns
    -------
    PatchAdjacency (canonical numbering, see the module docstring)

    Corners and sides are independent: a task each on the thread pool (their gathers and scatters run without
    the GIL). Memory: the result ((P, 4) int32 corners and edges, (P, 4) bool) and one int32 table per label
    range (refined faces, refined half-edges; both at once) besides blocks of ``_ADJACENCY_BLOCK`` patches: the
    labels are gathered by blocks (``corner_labels``, ``side_labels``) straight into the arrays that become the
    ids (``adjacency_from_labels`` renumbers them in place). A caller that owns the refined mesh's arrays can
    call the three itself and let each input go once read (``evaluation.stream.StreamedSurface``).
    """
    corners, (edges, forward) = run_tasks([lambda: adjacency_from_corner_labels(corner_labels(refined.face, frames)).corners,
                                           lambda: _sides_renumbered(*side_labels(refined.twin, frames))])
    return PatchAdjacency(corners, edges, forward)


def _frame_parts(frames) -> list:
    """(p_k, 4) int arrays of ``patch_adjacency``'s ``frames``: the array, or each of a sequence."""
    return [np.asarray(f).reshape(-1, 4) for f in (frames if isinstance(frames, (list, tuple)) else [frames])]


def _label_type(parts, table: np.ndarray):
    """int32 labels and ids while they fit (these (P, 4) arrays are the largest of the adjacency), else int64."""
    return np.int32 if max(4 * sum(part.shape[0] for part in parts), table.size) < 2**31 else np.int64


def corner_labels(face: np.ndarray, frames) -> np.ndarray:
    """(P, 4) int: the refined face at each patch corner (``patch_adjacency``'s corner labels, before renumbering),
    by blocks of rows on the thread pool. face : (H,) int, the refined mesh's ``face``; frames : as ``patch_adjacency``'s"""
    face, parts = np.asarray(face), _frame_parts(frames)
    corners = np.empty((sum(part.shape[0] for part in parts), 4), dtype=_label_type(parts, face))

    def fill(a: int, block: np.ndarray) -> None:  # a task per block: its rows only
        gathered = np.take(face, block)  # face(e2), face(e3), face(e0), face(e1): one take, then two copies
        corners[a : a + block.shape[0], :2], corners[a : a + block.shape[0], 2:] = gathered[:, 2:], gathered[:, :2]
    run_tasks([partial(fill, a, block) for a, block in _row_blocks(parts)])
    return corners


def side_labels(twin: np.ndarray, frames):
    """(edges (P, 4) int, forward (P, 4) bool): the label of the refined edge under each patch side (the lower of
    its two half-edges) and whether the side runs from that half-edge's face (``patch_adjacency``'s, before
    renumbering).

    twin : (H,) int, the refined mesh's ``twin``; frames : as ``patch_adjacency``'s
    """
    twin, parts = np.asarray(twin), _frame_parts(frames)
    index = _label_type(parts, twin)
    p = sum(part.shape[0] for part in parts)
    edges, forward = np.empty((p, 4), dtype=index), np.empty((p, 4), dtype=bool)
    low = 0
    for a, block in _row_blocks(parts):
        z = a + block.shape[0]
        # side s, run in increasing parameter, goes from face(x) to face(twin x): x = twin e3, twin e0, e1, e2
        x = np.empty(block.shape, dtype=index)
        x[:, :2] = np.take(twin, block[:, [3, 0]])
        x[:, 2:] = block[:, 1:3]
        np.minimum(x, np.take(twin, x), out=edges[a:z])  # the edge's label: the lower of its two half-edges
        np.equal(x, edges[a:z], out=forward[a:z])  # x is the label or its twin: the side's direction
        low = min(low, int(edges[a:z].min()) if z > a else 0)
    if low < 0:  # x or twin x is -1
        raise ValueError("internal: a patch side crosses a boundary half-edge")
    return edges, forward


def adjacency_from_labels(corners: np.ndarray, edges: np.ndarray, forward: np.ndarray) -> PatchAdjacency:
    """The PatchAdjacency of ``corner_labels`` and ``side_labels``' arrays, renumbered in place (they become its own)."""
    return PatchAdjacency(adjacency_from_corner_labels(corners).corners, *_sides_renumbered(edges, forward))


def _sides_renumbered(edges: np.ndarray, forward: np.ndarray):
    """(edges, reversed): ``side_labels``' arrays (P, 4) int and (P, 4) bool made edge ids and directions in place."""
    # a side is reversed when its direction differs from that of the edge's first side
    first_forward = np.take(forward.reshape(-1), _renumber(edges.reshape(-1)))
    flat_edges, flat_forward, step = edges.reshape(-1), forward.reshape(-1), 4 * _ADJACENCY_BLOCK
    for a, z in ((a, min(a + step, flat_edges.size)) for a in range(0, flat_edges.size, step)):
        np.not_equal(flat_forward[a:z], np.take(first_forward, flat_edges[a:z]), out=flat_forward[a:z])
    return edges, forward


def adjacency_from_corner_labels(corners: np.ndarray) -> PatchAdjacency:
    """The corners-only PatchAdjacency of ``corner_labels``' array, renumbered in place (edges and reversed None):
    what a tessellation at resolution 2 reads (its vertices are the corners), without the sides' labels."""
    _renumber(corners.reshape(-1))
    return PatchAdjacency(corners, None, None)


def _row_blocks(parts):
    """Yield (first row, (b, 4) rows) of the concatenation of ``parts``, ``_ADJACENCY_BLOCK`` rows at most."""
    start = 0
    for part in parts:
        for a in range(0, part.shape[0], _ADJACENCY_BLOCK):
            yield start + a, part[a : a + _ADJACENCY_BLOCK]
        start += part.shape[0]


def _renumber(flat: np.ndarray) -> np.ndarray:
    """Renumber the labels ``flat`` (n,) int in place, 0, 1, 2, ... in order of first appearance (as
    ``_first_appearances``, which takes the labels that are not small non-negative integers); return first (k,)
    int (``flat``'s dtype), the increasing positions where each id appears first. Small labels: a (max label + 1,)
    table of ``flat``'s dtype and an (n + 1,) bool one, every pass by blocks (no temporary of n or k entries), the
    last pass on the thread pool."""
    n = flat.size
    if n == 0:
        return np.zeros(0, dtype=flat.dtype)
    if flat.min() < 0 or flat.max() >= 4 * n + 1024:
        ids, first = _first_appearances(flat)
        flat[:] = ids
        return first
    block = 4 * _ADJACENCY_BLOCK
    first_at = np.full(int(flat.max()) + 1, n, dtype=flat.dtype)
    for z in range(n, 0, -block):  # from the end, each block backwards: the lowest position is written last
        a = max(0, z - block)
        first_at[flat[a:z][::-1]] = np.arange(z - 1, a - 1, -1, dtype=flat.dtype)
    is_first = np.zeros(n + 1, dtype=bool)
    is_first[first_at] = True
    first = np.empty(int(np.count_nonzero(is_first[:n])), dtype=flat.dtype)
    at = 0
    for a in range(0, n, block):
        found = np.flatnonzero(is_first[a : min(a + block, n)])
        first[at : at + found.size] = found + a
        at += found.size
    del is_first
    new_id = first_at  # reused: only entries of labels that occur are read back
    for a in range(0, first.size, block):
        z = min(a + block, first.size)
        new_id[np.take(flat, first[a:z])] = np.arange(a, z, dtype=flat.dtype)

    def rename(a: int) -> None:  # a block of labels, a task of its own, replaced by their new ids
        flat[a : a + block] = np.take(new_id, flat[a : a + block])
    run_tasks([partial(rename, a) for a in range(0, n, block)])
    return first


# -- sides and corners of patch arrays --------------------------------------------------


def corner_points(group: np.ndarray) -> np.ndarray:
    """Corner control points of a group of patches, corners 0..3.

    Parameters
    ----------
    group : (p, du+1, dv+1, d) float

    Returns
    -------
    (p, 4, d) float
    """
    return np.stack([group[:, 0, 0], group[:, -1, 0], group[:, -1, -1], group[:, 0, -1]], axis=1)


def side_polygons(group: np.ndarray) -> list:
    """Control polygons of sides 0..3 of a group of patches, in increasing parameter.

    Parameters
    ----------
    group : (p, du+1, dv+1, d) float

    Returns
    -------
    list of 4 arrays (p, du+1, d) (sides 0 and 2) or (p, dv+1, d) (sides 1 and 3)
    """
    return [group[:, :, 0], group[:, -1, :], group[:, :, -1], group[:, 0, :]]


def side_offsets(d: int) -> np.ndarray:
    """Where each side's control polygon and the row next to it lie in a flat patch.

    A patch of degree (d, d) flattened to (d+1)^2 control points has point (i, j)
    at offset i (d+1) + j. The row next to a side (inwards) gives the derivative
    across it.

    Returns
    -------
    (4, 2, d+1) int: [s, 0] the polygon of side s, [s, 1] the next row inwards,
    both in increasing parameter
    """
    i = np.arange(d + 1)
    return np.array([[i * (d + 1), i * (d + 1) + 1],  # side 0: v = 0, next v = 1/d
                     [d * (d + 1) + i, (d - 1) * (d + 1) + i],  # side 1: u = 1
                     [i * (d + 1) + d, i * (d + 1) + d - 1],  # side 2: v = 1
                     [i, d + 1 + i]])  # side 3: u = 0


# -- the geometric side matcher ---------------------------------------------------------

# Parameters of the points that tell sides apart: a side is one edge with another when their end
# corners and these points match, in one order or the other (``sides.matching``).
SIDE_SAMPLES = np.array([0.25, 0.5, 0.75])


def _side_points(patch_groups, weights=None):
    """Corners (P, 4, 3) and points of every side at ``SIDE_SAMPLES`` (P, 4, 3, 3), on the surface.

    Rational sides (``weights``: a list parallel to ``patch_groups``) are evaluated
    as such: the homogeneous polygon, then divided by w.
    """
    corners, samples = [], []
    for k, g in enumerate(patch_groups):
        if not len(g):
            continue
        g = np.asarray(g, dtype=np.float64)[..., :3]
        h = g if weights is None else homogeneous(g, weights[k])
        corners.append(corner_points(g))
        sides = np.stack([np.einsum("ti,pid->ptd", bernstein_basis(poly.shape[1] - 1, SIDE_SAMPLES), poly)
                          for poly in side_polygons(h)], axis=1)
        samples.append(sides if weights is None else dehomogenize(sides)[0])
    return np.concatenate(corners), np.concatenate(samples)


def match_patch_sides(patch_groups, tolerance: float, weights=None) -> SideMatching:
    """Find which patch sides are one edge, from the geometry alone.

    Two sides are one edge when their end corners coincide (within ``tolerance``)
    and so do their quarter, mid and three-quarter points (in one order or the
    other); they run the same way when they start at the same corner
    (``sides.matching``).

    Parameters
    ----------
    patch_groups : list of (p_k, du+1, dv+1, d) float, patches in order (x, y, z first)
    tolerance : float, absolute distance below which two points are the same
    weights : None or a list parallel to ``patch_groups`` of (p_k, du+1, dv+1) float (rational, A2a)

    Returns
    -------
    SideMatching (all empty arrays when there are no patches)
    """
    if not any(len(g) for g in patch_groups):
        empty = np.zeros((0, 4), dtype=np.int64)
        return SideMatching(empty, empty, empty, np.zeros((0, 4), dtype=bool))
    return match_sides(*_side_points(patch_groups, weights), tolerance)


def adjacency_from_geometry(patch_groups, tolerance: float = 1e-9, weights=None) -> PatchAdjacency:
    """Adjacency found from the patch geometry alone (no bookkeeping).

    Sides are matched by ``match_patch_sides`` with ``tolerance`` relative to the
    bounding-box diagonal of the corners and side points; a side is reversed
    when its quarter point lies at the other end of the edge's first side. For
    a c1surf surface this gives exactly ``patch_adjacency``
    (tests/io/test_patch_exchange.py checks it).

    Parameters
    ----------
    patch_groups : list of (p_k, du+1, dv+1, d) float, in patch order (x, y, z first)
    tolerance : float, relative to the bounding-box diagonal
    weights : None or a list parallel to ``patch_groups`` of (p_k, du+1, dv+1) float (rational, A2a)

    Returns
    -------
    PatchAdjacency
    """
    if not any(len(g) for g in patch_groups):
        empty = np.zeros((0, 4), dtype=np.int64)
        return PatchAdjacency(empty, empty.copy(), np.zeros((0, 4), dtype=bool))
    corners, samples = _side_points(patch_groups, weights)
    everything = np.concatenate([corners.reshape(-1, 3), samples.reshape(-1, 3)])
    diagonal = float(np.linalg.norm(everything.max(axis=0) - everything.min(axis=0)))
    matching = match_sides(corners, samples, tolerance * diagonal if diagonal > 0 else tolerance)
    return _canonical(matching.corners, matching.edges, matching.forward)



def with_seams(adjacency: PatchAdjacency, seams: np.ndarray, same_direction: np.ndarray) -> PatchAdjacency:
    """``adjacency`` with each pair of sides in ``seams`` made one shared side (C0 creases: B-rep edges).

    Parameters
    ----------
    adjacency : PatchAdjacency in which the two sides of each seam are separate (boundary) sides
    seams : (k, 2) int, curve ids ``4 * patch + side`` of the two sides of each seam
    same_direction : (k,) bool, the two sides run the same way in increasing parameter

    Returns
    -------
    PatchAdjacency, canonical, with the seams' sides sharing an edge id and their end corners a corner id
    """
    seams = np.asarray(seams, dtype=np.int64).reshape(-1, 2)
    if seams.size == 0:
        return adjacency
    corners = np.asarray(adjacency.corners, dtype=np.int64)
    ends = lambda curve: corners.reshape(-1)[4 * (curve // 4)[:, None] + SIDE_CORNERS[curve % 4]]  # (k, 2) start, end
    a, b = ends(seams[:, 0]), ends(seams[:, 1])
    b = np.where(same_direction[:, None], b, b[:, ::-1])
    corner_labels = component_roots(adjacency.n_corners, a.ravel(), b.ravel())[corners]  # the seam ends made one
    edge_labels = np.asarray(adjacency.edges, dtype=np.int64).copy()
    flat = edge_labels.reshape(-1)
    flat[seams[:, 1]] = flat[seams[:, 0]]
    start = corner_labels.reshape(-1, 4)[:, SIDE_CORNERS[:, 0]]  # the corner each side starts at
    return _canonical(corner_labels, edge_labels, start)


__all__ = ["PatchAdjacency", "with_seams", "neighbour_rows", "patch_adjacency", "corner_labels", "side_labels", "adjacency_from_labels", "adjacency_from_geometry", "match_patch_sides", "SideMatching",
           "SIDE_CORNERS", "side_offsets", "side_polygons", "corner_points"]
