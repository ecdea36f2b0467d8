"""Merged B-spline pieces (``convert --merge``) in patch files: the patches they stand for, both ways.

A piece (``evaluation.merge.MergedPiece``) is a clamped B-spline surface of
degree (2, 2) over m x n spans, knots ``0 0 0 1 ... m m m``, that equals a
rectangle of biquadratic patches (A2, Lemma 1.3.4: they join parametrically
C1). ``piece.patches`` numbers those patches among the biquadratic patches
of the file, in file order.

- JSON and NPZ keep every patch and add the pieces (their readers check
  them with ``checks.checked_piece``).
- IGES and STEP write a piece *instead of* its patches (:func:`uncovered_groups`);
  the IGES reader gives the patches back by cutting each piece at its knots
  (:func:`piece_patches`), in the piece's orientation.
"""
from __future__ import annotations

import numpy as np

from ...evaluation.merge import MergedPiece

__all__ = ["uncovered_groups", "piece_patches", "clamped_knots", "is_piece_knots"]


def clamped_knots(spans: int) -> np.ndarray:
    """Knots 0 0 0 1 2 ... m m m of a clamped uniform quadratic B-spline over ``spans`` (m) spans: (m + 5,) float."""
    return np.r_[0.0, 0.0, np.arange(spans + 1, dtype=np.float64), float(spans), float(spans)]


def is_piece_knots(knots: np.ndarray) -> bool:
    """Whether ``knots`` are those of a merged piece (``clamped_knots(m)`` for some m >= 1)."""
    return knots.size >= 6 and np.array_equal(knots, clamped_knots(knots.size - 5))


def uncovered_groups(patch_set) -> tuple[list, list]:
    """The patch groups of ``patch_set`` without the biquadratic patches its merged pieces stand for.

    Returns
    -------
    groups : list of (p_k, du+1, dv+1, 3) float (empty groups left out)
    weights : list parallel to ``groups`` of (p_k, du+1, dv+1) float or None each
    """
    covered = np.concatenate([piece.patches.ravel() for piece in patch_set.merged] or [np.zeros(0, np.int64)])
    weights = patch_set.weights or [None] * len(patch_set.groups)
    groups, kept_weights, first = [], [], 0  # first: biquadratic number of the group's first patch
    for group, w in zip(patch_set.groups, weights):
        if group.shape[1:3] == (3, 3):
            keep = np.ones(len(group), dtype=bool)
            inside = covered[(covered >= first) & (covered < first + len(group))]
            keep[inside - first] = False
            first += len(group)
            if not keep.all():
                group, w = group[keep], (None if w is None else w[keep])
        if len(group):
            groups.append(np.ascontiguousarray(group))
            kept_weights.append(w)
    return groups, kept_weights


def _cut(net: np.ndarray) -> np.ndarray:
    """Cut a C1 quadratic B-spline net (m + 2, ...) along its first axis into m Bezier spans (m, 3, ...).

    Span i is (left, net[i + 1], right): its end points are the midpoints of
    neighbouring net points, and the first and last net points at the clamped ends.
    """
    joints = 0.5 * (net[1:-2] + net[2:-1])  # the points at the m - 1 inner knots
    return np.stack([np.concatenate([net[:1], joints]), net[1:-1], np.concatenate([joints, net[-1:]])], axis=1)


def piece_patches(piece: MergedPiece):
    """The m x n Bezier patches of a merged piece, row by row (span i slowest), in the piece's (u, v).

    Rational pieces are cut in homogeneous coordinates (w x, w).

    Returns
    -------
    points : (m n, 3, 3, d) float
    weights : (m n, 3, 3) float, or None for a polynomial piece
    """
    net = piece.points if piece.weights is None else np.concatenate(
        [piece.points * piece.weights[..., None], piece.weights[..., None]], axis=-1)
    along_u = _cut(net)  # (m, 3, n + 2, d)
    both = _cut(along_u.transpose(2, 0, 1, 3))  # (n, 3, m, 3, d): v span, v index, u span, u index
    m, n = along_u.shape[0], both.shape[0]
    patches = both.transpose(2, 0, 3, 1, 4).reshape(m * n, 3, 3, -1)
    if piece.weights is None:
        return np.ascontiguousarray(patches), None
    w = patches[..., -1]
    return np.ascontiguousarray(patches[..., :-1] / w[..., None]), np.ascontiguousarray(w)
