"""Merging rectangular regions of biquadratic patches into B-spline surfaces (``--merge``).

Where the refined mesh is regular, the biquadratic patches are the Bezier
pieces of one uniform biquadratic B-spline surface (A2, Lemma 1.3.4: they
join parametrically C1). A rectangle of m x n such patches, turned to a
common orientation, is therefore exactly one clamped B-spline surface of
degree (2, 2) with (m + 2) x (n + 2) control points and knots
0 0 0 1 2 ... m m m (and the same in v): the interior control points are
the patches' centre coefficients (the refined mesh points), the border ones
their edge and corner coefficients.

Charts: starting from any patch, neighbours across shared sides get grid
coordinates and a rotation (frames are counter-clockwise, so neighbours
differ by a rotation only). A coordinate already taken (a grid that wraps
around, as on a torus) ends the chart there. Rectangles: cells are taken
row by row; each unused cell starts a run as wide as possible, then the
run grows row by row while the whole row below is unused and truly
adjacent (greedy, so every rectangle is maximal towards +i and +j when
made, not a minimum cover). Rational surfaces merge the same way in
homogeneous coordinates.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from .rational import dehomogenize, homogeneous

STEP = ((1, 0), (0, 1), (-1, 0), (0, -1))  # global directions 0..3: +i, +j, -i, -j


@dataclass(frozen=True)
class MergedPiece:
    """One B-spline surface made of m x n biquadratic patches.

    points : (m + 2, n + 2, d) float, control points (first index along u)
    weights : (m + 2, n + 2) float or None (rational surfaces)
    knots_u : (m + 5,) float, 0 0 0 1 ... m m m; knots_v : (n + 5,) float
    patches : (m, n) int, the biquadratic patch (index into ``Surface.biquadratic``) of each span
    rotation : (m, n) int, quarter turns taking each patch's (u, v) to the piece's
    """

    points: np.ndarray
    weights: np.ndarray | None
    knots_u: np.ndarray
    knots_v: np.ndarray
    patches: np.ndarray
    rotation: np.ndarray

    @property
    def degree(self) -> tuple:
        return (2, 2)


def _neighbours(refined, frames: np.ndarray):
    """(P, 4) neighbour patch across each side (-1: none) and (P, 4) rotation to it."""
    patch_of = np.full(refined.n_vertices, -1, dtype=np.int64)
    patch_of[refined.origin[frames[:, 0]]] = np.arange(frames.shape[0])
    other = patch_of[refined.dest[frames]]  # (P, 4)
    back = refined.twin[frames]  # half-edge from the neighbour back to the patch's vertex
    rot = np.zeros_like(other)
    has = other >= 0
    their = frames[np.where(has, other, 0)]  # (P, 4, 4)
    k_back = np.argmax(their == back[:, :, None], axis=2)
    found = np.any(their == back[:, :, None], axis=2)
    other = np.where(has & found, other, -1)
    rot = (k_back + 2 - np.arange(4)[None, :]) % 4  # local direction d here is d + rot there
    return other, rot


def _charts(other: np.ndarray, rot: np.ndarray):
    """Grid charts: list of dicts {(i, j): (patch, global rotation g)}."""
    n = other.shape[0]
    seen = np.zeros(n, dtype=bool)
    charts = []
    for seed in range(n):
        if seen[seed]:
            continue
        cells = {(0, 0): (seed, 0)}
        where = {seed: ((0, 0), 0)}
        seen[seed] = True
        queue = deque([seed])
        while queue:
            p = queue.popleft()
            (i, j), g = where[p]
            for k in range(4):
                q = int(other[p, k])
                if q < 0 or seen[q]:
                    continue
                direction = (k + g) % 4
                coord = (i + STEP[direction][0], j + STEP[direction][1])
                if coord in cells:
                    continue  # the grid wraps around: q starts another chart
                gq = (g - rot[p, k]) % 4
                cells[coord] = (q, gq)
                where[q] = (coord, gq)
                seen[q] = True
                queue.append(q)
        charts.append(cells)
    return charts


def _linked(cells, other, a, b, direction) -> bool:
    """Cells a and b = a + STEP[direction] hold patches that really are neighbours that way."""
    if a not in cells or b not in cells:
        return False
    p, g = cells[a]
    q, _ = cells[b]
    return int(other[p, (direction - g) % 4]) == q


def _glued_properly(cells, at, other, rot, rectangle) -> bool:
    """No side of ``rectangle`` (i0, j0, m, n) meets the rectangle itself, except as a seam.

    Two cells of a rectangle may be mesh neighbours without being grid
    neighbours: the chart's grid wraps around a tube (a seam, which the B-rep
    writes as an edge used twice by a face closed on it) or, on a field that
    turns, a strip winds round and its end lands on its own side (hand_closed's
    QuadriFlow layout: a 1 x 36 strip whose end side is its own 10th side; a
    face whose loop runs through one edge twice at unrelated places, which
    Open CASCADE's BRepCheck rightly calls invalid). Only a whole seam is kept:
    every row (or column) of the rectangle glued end to end, the same way round.
    ``at`` maps a patch to its cell.
    """
    i0, j0, m, n = rectangle
    rows, columns = set(), set()
    for a in range(i0, i0 + m):
        for b in range(j0, j0 + n):
            p, g = cells[(a, b)]
            for k in range(4):
                q = int(other[p, k])
                c = at.get(q)
                if c is None or not (i0 <= c[0] < i0 + m and j0 <= c[1] < j0 + n):
                    continue
                d = (k + g) % 4
                if c == (a + STEP[d][0], b + STEP[d][1]):
                    continue  # the grid neighbour
                if (k + rot[p, k] - 2 + cells[c][1]) % 4 != (d + 2) % 4:
                    return False  # glued turned: not a seam
                if (d, b, c) in ((1, j0 + n - 1, (a, j0)), (3, j0, (a, j0 + n - 1))):
                    rows.add(a)
                elif (d, a, c) in ((0, i0 + m - 1, (i0, b)), (2, i0, (i0 + m - 1, b))):
                    columns.add(b)
                else:
                    return False
    return len(rows) in (0, m) and len(columns) in (0, n)


def _rectangles(cells, other, rot):
    """Greedy cover of a chart by rectangles of truly adjacent cells: list of (i0, j0, m, n).

    A rectangle that meets itself other than along a whole seam
    (:func:`_glued_properly`) loses rows, then columns, until it does not.
    """
    at = {p: c for c, (p, _) in cells.items()}
    used = set()
    out = []
    for start in sorted(cells):
        if start in used:
            continue
        i0, j0 = start
        n = 1
        while (i0, j0 + n) not in used and _linked(cells, other, (i0, j0 + n - 1), (i0, j0 + n), 1):
            n += 1
        m = 1
        while True:
            row = [(i0 + m, j0 + c) for c in range(n)]
            if any(cell in used or cell not in cells for cell in row):
                break
            if not all(_linked(cells, other, (i0 + m - 1, j0 + c), (i0 + m, j0 + c), 0) for c in range(n)):
                break
            if not all(_linked(cells, other, row[c], row[c + 1], 1) for c in range(n - 1)):
                break
            m += 1
        while (m > 1 or n > 1) and not _glued_properly(cells, at, other, rot, (i0, j0, m, n)):
            m, n = (m - 1, n) if m > 1 else (m, n - 1)
        for a in range(m):
            for b in range(n):
                used.add((i0 + a, j0 + b))
        out.append((i0, j0, m, n))
    return out


def _clamped_knots(m: int) -> np.ndarray:
    return np.r_[0.0, 0.0, np.arange(m + 1, dtype=np.float64), float(m), float(m)]


def _index_map(m: int):
    """B-spline control index a -> (span, Bezier index) for m quadratic spans joined C1."""
    span = np.r_[0, np.arange(m), m - 1]
    local = np.r_[0, np.ones(m, dtype=np.int64), 2]
    return span, local


def merge_biquadratic(surface, min_patches: int = 2) -> list[MergedPiece]:
    """Merge rectangles of biquadratic patches of ``surface`` into B-spline surfaces.

    Parameters
    ----------
    surface : construction.surface.Surface
    min_patches : int, smallest rectangle worth merging (single patches stay Bezier)

    Returns
    -------
    list of MergedPiece
    """
    frames = surface.quad_frames
    if frames.shape[0] == 0:
        return []
    other, rot = _neighbours(surface.refined, frames)
    coefficients = surface.biquadratic
    weights = surface.biquadratic_weights
    if weights is not None:
        coefficients = homogeneous(coefficients, weights)
    pieces = []
    for cells in _charts(other, rot):
        for i0, j0, m, n in _rectangles(cells, other, rot):
            if m * n < min_patches:
                continue
            patches = np.array([[cells[(i0 + a, j0 + b)][0] for b in range(n)] for a in range(m)])
            turns = np.array([[cells[(i0 + a, j0 + b)][1] for b in range(n)] for a in range(m)])
            turned = np.empty((m, n) + coefficients.shape[1:])
            for a in range(m):
                for b in range(n):
                    # the patch's +u is global direction g: turn its array g quarter turns back
                    turned[a, b] = np.rot90(coefficients[patches[a, b]], k=turns[a, b], axes=(0, 1))
            su, lu = _index_map(m)
            sv, lv = _index_map(n)
            net = turned[su[:, None], sv[None, :], lu[:, None], lv[None, :]]  # (m + 2, n + 2, d)
            net, w = dehomogenize(net) if weights is not None else (net, None)
            pieces.append(MergedPiece(net, w, _clamped_knots(m), _clamped_knots(n), patches, turns))
    return pieces


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


def piece_dicts(pieces: list[MergedPiece]) -> list[dict]:
    """The pieces as ``io.iges.write_iges`` B-spline dicts (positions only)."""
    return [{"points": np.ascontiguousarray(p.points[..., :3]), "weights": p.weights, "knots_u": p.knots_u,
             "knots_v": p.knots_v, "degree": (2, 2)} for p in pieces]
