"""Patch sides matched by their geometry alone: which sides are one edge (``check``, ``adjacency_from_geometry``).

Two sides are one edge when their end corners are the same points and their quarter, mid and
three-quarter points coincide within the tolerance (in one order or the other); they run the same
way when they start at the same corner. Only the corners are clustered (``mesh.points.clusters``,
four points a patch): the sides are grouped by their two end points, and the two sides of an end
pair are compared point by point. Where three or more sides share their end points (sheets of a
non-manifold edge, or different curves between two points), the side points of those sides only are
clustered, and sides whose mid and quarter points fall in one cluster each are one edge.

Clustering every side point as well (16 points a patch) gave the same edges; on a 1.49 M-patch
surface it took 10.8 s of ``check``'s 24.5 s.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ...mesh.points.clusters import cluster_points

# Corner (start, end) of each side, in increasing parameter (``evaluation.adjacency``'s numbering).
SIDE_CORNERS = np.array([[0, 1], [1, 2], [3, 2], [0, 3]])
_PAIRS = 1 << 20  # side pairs compared at a time (block-sized gathers)


@dataclass(frozen=True)
class SideMatching:
    """Patch sides matched by geometry; side s of patch p is the flat side ``4 p + s``.

    corners : (P, 4) int64, a label per corner point (equal labels: the same point)
    edges : (P, 4) int64, a label per side (equal labels: the same edge)
    forward : (P, 4) int64, a label per side, equal for two sides of one edge iff they run the same way
        (the label of the corner it starts at)
    degenerate : (P, 4) bool, the side's two end corners are one point
    """

    corners: np.ndarray
    edges: np.ndarray
    forward: np.ndarray
    degenerate: np.ndarray

    @cached_property
    def _counts(self):
        """(flat edge label, how many sides have it, usable: not degenerate) per flat side."""
        flat = self.edges.ravel()
        return flat, np.bincount(flat)[flat], ~self.degenerate.ravel()

    @cached_property
    def _shared(self) -> np.ndarray:
        """Sides of the edges found in exactly two sides, the two of each edge one after the other."""
        flat, count, usable = self._counts
        shared = np.flatnonzero((count == 2) & usable)
        return shared[np.argsort(flat[shared], kind="stable")]

    @property
    def first(self) -> np.ndarray:
        """(k,) int, one side of each edge found in exactly two sides (in order of edge label)."""
        return self._shared[0::2]

    @property
    def second(self) -> np.ndarray:
        """(k,) int, the other side of each edge of ``first``."""
        return self._shared[1::2]

    @property
    def reversed(self) -> np.ndarray:
        """(k,) bool, the two sides of an edge run in opposite directions."""
        forward = self.forward.ravel()
        return forward[self.first] != forward[self.second]

    @property
    def lone(self) -> np.ndarray:
        """(m,) int, sides found in one patch only (the surface's boundary)."""
        _, count, usable = self._counts
        return np.flatnonzero((count == 1) & usable)

    @property
    def overshared(self) -> int:
        """Edges found in more than two sides (not a surface there)."""
        flat, count, usable = self._counts
        return int(np.unique(flat[(count > 2) & usable]).size)

    @property
    def overshared_sides(self) -> np.ndarray:
        """(m,) int, the sides (``4 * patch + side``) of the edges found in more than two sides."""
        flat, count, usable = self._counts
        return np.flatnonzero((count > 2) & usable)


def matching_tolerance(corners: np.ndarray, tolerance: float, compiled: bool = False) -> float:
    """The absolute distance below which ``match_sides`` takes two points as one: ``tolerance``, or less where
    the patches are small beside it.

    A tolerance relative to the whole surface (``check``'s 1e-9 of the diagonal) is larger than the sides of
    the smallest patches when their sizes span many orders of magnitude (a cell of 10,000 sides bulges to
    about 1e5 units while its patches near the centre are 1e-4 long): their corners would fall into one
    point. So it is lowered to a thousandth of the shortest side where that is below a thousand tolerances,
    never below the coordinates' own resolution (2^-40 of the largest coordinate), so that rounding never
    splits a point. On every other surface it is ``tolerance`` unchanged.

    corners : (P, 4, 3) float, the patches' corner points; tolerance : float, absolute; compiled : bool, the
    shortest side found by ``evaluation.compiled.kernels.shortest_side`` (no (P, 4, 3) temporaries: 0.9 s -> 0.05 s on
    1.2 M patches), the same lengths to rounding
    """
    if corners.size == 0 or not tolerance > 0:
        return tolerance
    floor = float(np.abs(corners).max()) * 2.0**-40
    if compiled:
        from ..compiled import kernels  # numba: imported where the loops run

        shortest = float(kernels.shortest_side(np.ascontiguousarray(corners, dtype=np.float64), SIDE_CORNERS,
                                               8 * floor))
    else:
        chords = corners[:, SIDE_CORNERS[:, 1]] - corners[:, SIDE_CORNERS[:, 0]]  # (P, 4, 3)
        lengths = np.sqrt(np.einsum("psk,psk->ps", chords, chords)).ravel()
        shortest = float(lengths[lengths > 8 * floor].min(initial=np.inf))  # shorter: a collapsed side, to rounding
    if shortest >= 1e3 * tolerance:
        return tolerance
    return max(floor, min(tolerance, 1e-3 * shortest))


def match_sides(corners: np.ndarray, samples: np.ndarray, tolerance: float) -> SideMatching:
    """SideMatching of corner points (P, 4, 3) and side points (P, 4, 3, 3) (each side's points at
    ``adjacency.SIDE_SAMPLES``, in increasing parameter), ``tolerance`` an absolute distance (lowered where the
    patches are small beside it: ``matching_tolerance``)."""
    p, tolerance = corners.shape[0], matching_tolerance(corners, tolerance)
    return sides_of_corners(cluster_points(corners.reshape(-1, 3), tolerance).reshape(p, 4), samples, tolerance)


def sides_of_corners(corner_label: np.ndarray, samples: np.ndarray, tolerance: float,
                     compiled: bool = False) -> SideMatching:
    """SideMatching of the corners' labels (P, 4) (``mesh.points.clusters.cluster_points`` of the corner points)
    and the side points (P, 4, 3, 3) (see the module docstring).

    Edge labels are ranked by the sides' end labels (lowest first), then within one pair of ends by
    the sides' own order (two sides) or by their mid and quarter points' clusters (three or more).
    Labels and positions are int32 where they fit (a 1.5 M-patch check: 6 M sides).
    """
    p = corner_label.shape[0]
    small = np.int32 if 4 * p < 2**31 else np.int64
    ends = corner_label.astype(small, copy=False)[:, SIDE_CORNERS].reshape(-1, 2)  # (4P, 2) start, end
    low, high = ends.min(axis=1), ends.max(axis=1)
    degenerate = (low == high).reshape(p, 4)
    pair = low.astype(np.int64) * (int(high.max(initial=0)) + 1) + high
    del low, high
    order = np.argsort(pair, kind="stable").astype(small)
    pair = pair[order]
    first_of_group = np.ones(pair.size, dtype=bool)
    np.not_equal(pair[1:], pair[:-1], out=first_of_group[1:])
    del pair
    starts = np.flatnonzero(first_of_group)
    size = np.diff(np.r_[starts, order.size])
    within = np.zeros(order.size, dtype=small)  # the second key per sorted side: 0, or 1 for a second curve
    two = starts[size == 2]
    within[two + 1] = ~_same_curves(samples.reshape(-1, 3, 3), ends, order[two], order[two + 1], tolerance, compiled)
    many = np.flatnonzero(np.repeat(size >= 3, size))
    del starts, size, two
    if many.size:  # three or more sides between two points: their side points' clusters, sorted in the group
        labels = cluster_points(samples.reshape(-1, 3, 3)[order[many]].reshape(-1, 3), tolerance).reshape(-1, 3)
        key = labels[:, 1] * (int(labels.max()) + 1) + np.minimum(labels[:, 0], labels[:, 2])
        by = np.lexsort((key, np.cumsum(first_of_group)[many]))
        order[many], within[many] = order[many][by], np.unique(key, return_inverse=True)[1].reshape(-1)[by]
    # sorted by (end pair, within): a new edge where either changes
    new_edge = first_of_group
    new_edge[1:] |= within[1:] != within[:-1]
    del within
    edges = np.empty(order.size, dtype=np.int64)
    edges[order] = np.cumsum(new_edge) - 1
    return SideMatching(corner_label, edges.reshape(p, 4), ends[:, 0].reshape(p, 4).astype(np.int64), degenerate)


def _same_curves(points: np.ndarray, ends: np.ndarray, a: np.ndarray, b: np.ndarray, tolerance: float,
                 compiled: bool = False) -> np.ndarray:
    """(k,) bool: sides a and b (flat ids, with the same two end points) have their side points within
    ``tolerance`` of each other, b's taken backwards where it starts at a's end; by blocks of pairs, or pair by
    pair in ``evaluation.compiled.kernels.same_curves`` (``compiled``: no (2^20, 3, 3) copies, 216 MB of a large check)."""
    out = np.empty(a.size, dtype=bool)
    if compiled:
        from ..compiled import kernels  # numba: imported where the loops run

        kernels.same_curves(np.ascontiguousarray(points), np.ascontiguousarray(ends), np.ascontiguousarray(a),
                            np.ascontiguousarray(b), float(tolerance), out)
        return out
    for lo in range(0, a.size, _PAIRS):
        sa, sb = points[a[lo : lo + _PAIRS]], points[b[lo : lo + _PAIRS]]
        backwards = ends[a[lo : lo + _PAIRS], 0] != ends[b[lo : lo + _PAIRS], 0]
        sb[backwards] = sb[backwards, ::-1]
        difference = sa - sb
        out[lo : lo + _PAIRS] = (np.einsum("ijk,ijk->ij", difference, difference) <= tolerance * tolerance).all(axis=1)
    return out


__all__ = ["SideMatching", "match_sides", "matching_tolerance", "sides_of_corners", "SIDE_CORNERS"]
