"""Merged B-spline pieces (``convert --merge``) in patch files: the patches they stand for, both ways.

A piece (``evaluation.merge.MergedPiece``) is a clamped B-spline surface of
degree (2, 2) over m x n spans, knots ``0 0 0 1 ... m m m``, that equals a
rectangle of biquadratic patches (A2, Lemma 1.3.4: they join parametrically
C1). ``piece.patches`` numbers those patches among the biquadratic patches
of the file, in file order.

- JSON and NPZ keep every patch and add the pieces (their readers check
  them with ``checks.checked_piece``).
- IGES and STEP write a piece *instead of* its patches (:func:`uncovered_groups`),
  cut into strips one span wide (:func:`cad_patch_set`); the IGES and STEP
  readers give the patches back by cutting each piece at its knots
  (:func:`piece_patches`), in the piece's orientation.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ...evaluation.merge import MergedPiece, piece_patches

__all__ = ["uncovered_groups", "piece_patches", "clamped_knots", "is_piece_knots", "strip_pieces", "cad_patch_set"]


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


def _sub_net(net: np.ndarray, start: int, stop: int) -> np.ndarray:
    """The control net (k + 2, ...) of spans ``start .. stop - 1`` (k = stop - start) of a clamped uniform quadratic
    B-spline net (m + 2, ...) along its first axis: the inner points as they are, each end the joint point (the
    midpoint of its two neighbours) where the cut is inside, the net's own end where it is not. Homogeneous
    coordinates for a rational net."""
    m = net.shape[0] - 2
    first = net[:1] if start == 0 else 0.5 * (net[start : start + 1] + net[start + 1 : start + 2])
    last = net[-1:] if stop == m else 0.5 * (net[stop : stop + 1] + net[stop + 1 : stop + 2])
    return np.concatenate([first, net[start + 1 : stop + 1], last])


def _turned(piece: MergedPiece) -> MergedPiece:
    """The same surface turned a quarter turn in its parameter plane (u becomes v, v becomes -u): orientation kept."""
    weights = None if piece.weights is None else np.rot90(piece.weights)
    return MergedPiece(np.rot90(piece.points, axes=(0, 1)).copy(), None if weights is None else weights.copy(),
                       piece.knots_v, piece.knots_u, np.rot90(piece.patches).copy(),
                       (np.rot90(piece.rotation) + 1) % 4)


def strip_pieces(piece: MergedPiece, max_spans: int | None = None) -> list:
    """``piece`` cut into strips one span wide in u (at most ``max_spans`` long in v; None: the whole length), turned
    first where that gives fewer strips, every second strip a half turn: the faces of the CAD B-reps
    (``io.patches.brep``), see ``cad_patch_set``.

    The half turns make neighbouring strips meet u = 1 to u = 1, then u = 0 to u = 0, and so on: a side at u = 0 adds
    nothing to Open CASCADE's default mass properties, so there the B-rep keeps one edge for the whole line
    (``brep.edge_chains``), and only every second line needs one edge per span.

    Returns
    -------
    list of MergedPiece, each (3, k + 2) control points, knots 0 0 0 1 1 1 in u and 0 0 0 1 .. k k k in v,
    its patches and rotations those of the spans it covers
    """
    m, n = piece.patches.shape
    cap = max(m, n) if max_spans is None else max_spans
    if m * -(-n // cap) > n * -(-m // cap):
        piece = _turned(piece)
        m, n = n, m
    net = piece.points if piece.weights is None else np.concatenate(
        [piece.points * piece.weights[..., None], piece.weights[..., None]], axis=-1)
    out = []
    for i in range(m):
        column = _sub_net(net, i, i + 1)  # (3, n + 2, d)
        for j0 in range(0, n, cap):
            j1 = min(n, j0 + cap)
            strip = np.swapaxes(_sub_net(np.swapaxes(column, 0, 1), j0, j1), 0, 1)
            points, weights = strip, None
            if piece.weights is not None:
                weights = np.ascontiguousarray(strip[..., -1])
                points = strip[..., :-1] / weights[..., None]
            strip = MergedPiece(np.ascontiguousarray(points), weights, clamped_knots(1), clamped_knots(j1 - j0),
                                piece.patches[i : i + 1, j0:j1].copy(), piece.rotation[i : i + 1, j0:j1].copy())
            out.append(_turned(_turned(strip)) if i % 2 else strip)
    return out


def cad_patch_set(patch_set, max_spans: int | None = None):
    """``patch_set`` as the IGES and STEP B-reps write it: its merged pieces cut into strips (:func:`strip_pieces`),
    strips of a single span left out (their patch is written as a Bezier face like any uncovered patch).

    Why strips: Open CASCADE's default mass properties integrate a face with one Gauss rule across it in u and
    one along each edge, over the whole range (not cut at knots), exact over one span only (docs/patch-format.md).
    ``max_spans`` caps the strips' length (None: the pieces' whole length; a longer strip makes Open CASCADE take
    more Gauss points per edge, max(8, 6 k) up to 61, which costs its time, not its accuracy).
    """
    if not patch_set.merged:
        return patch_set
    strips = [s for p in patch_set.merged for s in strip_pieces(p, max_spans)]
    return dataclasses.replace(patch_set, merged=[s for s in strips if s.patches.size > 1])
