"""Per-patch and per-side segment counts from a guaranteed bound on the chordal error.

The bound. Let x(u, v) be a patch and L the linear interpolant of x on a
triangle of parameter space whose bounding box is h_u x h_v. Taylor's theorem
with integral remainder around a point p of the triangle, weighted by p's
barycentric coordinates lambda_i (sum lambda_i (q_i - p) = 0), gives
``|x(p) - L(p)| <= 1/2 sum lambda_i (M_uu du_i^2 + 2 M_uv |du_i dv_i| + M_vv dv_i^2)``
with (du_i, dv_i) = q_i - p and M_ab = max |x_ab| over the patch. The u terms
sum to the variance of the u's (at most h_u^2 / 4), the v terms likewise, and
by Cauchy-Schwarz the mixed terms to at most h_u h_v / 4, so

    |x - L| <= (M_uu h_u^2 + 2 M_uv h_u h_v + M_vv h_v^2) / 8

for *every* triangle whose parameter bounding box is at most h_u x h_v: the
cells of a grid of spacing (h_u, h_v), but also the transition triangles of
``triangulate`` (which keep every triangle inside such a box). So the
chordal error of a patch cut into m_u x m_v segments is at most
``tau`` when ``(M_uu / m_u^2 + 2 M_uv / (m_u m_v) + M_vv / m_v^2) / 8 <= tau``.

The constants M come from the control points (``second_derivative_bounds``):
for a polynomial patch of degree d, x_uu = d (d-1) sum Delta^2_u P B^{d-2} B^d
is a convex combination, so M_uu <= d (d-1) max |Delta^2_u P|, M_uv <= d^2 max
|Delta_u Delta_v P|. For a rational patch x = H / w (A2a) the bound is made in
homogeneous coordinates, conservatively and without measuring (see the
function). Only x, y, z count (attribute columns after them do not).
"""
from __future__ import annotations

import numpy as np

from ..bezier import bernstein_basis
from ..rational import homogeneous

# The most segments one patch side gets: a guard against absurd tolerances (the memory guard of the
# command line refuses the output long before: 4096^2 cells of one patch are 33 M triangles).
MAX_SEGMENTS = 4096


def second_derivative_bounds(group: np.ndarray, weights: np.ndarray | None = None, pieces: int = 2) -> np.ndarray:
    """Upper bounds of |x_uu|, |x_uv|, |x_vv| over each patch of a group.

    Each patch is cut into ``pieces`` x ``pieces`` sub-patches (de Casteljau: the
    control net of a piece lies closer to its surface, measured here: 1.6-2.0 x the
    true bicubic maxima from the whole net, 1.1-1.3 x from 2 x 2 pieces), each piece
    is bounded as below in its own parameter s = pieces (u - a) and the largest,
    times pieces^2 (x_ss = x_uu / pieces^2), is the patch's bound.

    Polynomial: d(d-1) max |Delta^2_u P|, d^2 max |Delta_u Delta_v P|, d(d-1) max |Delta^2_v P|.

    Rational (weights w > 0): with a reference point c (the middle of the patch's
    control points) let G = w (P - c), so x - c = G / w. Differentiating
    G = w (x - c) gives G_u = w_u (x - c) + w x_u, G_uu = w_uu (x - c) + 2 w_u x_u + w x_uu,
    G_uv = w_uv (x - c) + w_u x_v + w_v x_u + w x_uv, hence with w >= w_min = min w_ij
    and |x - c| <= R = max |P_ij - c| (the convex hull property of positive weights):
    |x_u| <= (|G_u| + |w_u| R) / w_min and
    |x_uu| <= (|G_uu| + 2 |w_u| |x_u| + |w_uu| R) / w_min (x_uv alike), every |.| of
    G and w bounded by its control differences as above. With all weights 1 this
    is the polynomial bound. No measuring: conservative, and guaranteed.

    Parameters
    ----------
    group : (p, du+1, dv+1, dim) float, patches (x, y, z first)
    weights : None or (p, du+1, dv+1) float > 0 (rational patches)
    pieces : int >= 1

    Returns
    -------
    (p, 3) float: M_uu, M_uv, M_vv
    """
    points = np.asarray(group, dtype=np.float64)[..., :3]
    h = points if weights is None else homogeneous(points, weights)
    out = np.zeros((points.shape[0], 3))
    for lo in range(0, points.shape[0], _BOUND_BLOCK):
        block = h[lo : lo + _BOUND_BLOCK]
        for piece in _pieces(block, pieces):
            if weights is None:
                m = _net_bounds(piece)
            else:
                m = _rational_net_bounds(piece[..., :3] / piece[..., 3:], piece[..., 3])
            np.maximum(out[lo : lo + _BOUND_BLOCK], m * pieces * pieces, out=out[lo : lo + _BOUND_BLOCK])
    return out


_BOUND_BLOCK = 1 << 13  # patches bounded and given segments at once (bounded work arrays)


def _pieces(block: np.ndarray, k: int):
    """Yield the k x k sub-patches (p, du+1, dv+1, c) of patches ``block``, each on [a/k, (a+1)/k] x [b/k, (b+1)/k]."""
    du, dv = block.shape[1] - 1, block.shape[2] - 1

    def restriction(d, a):  # control points of the piece from those of the patch: (d+1, d+1)
        t = np.linspace(0.0, 1.0, d + 1)
        return np.linalg.solve(bernstein_basis(d, t), bernstein_basis(d, (a + t) / k))

    p, c = block.shape[0], block.shape[-1]
    for a in range(k):
        along_u = np.matmul(restriction(du, a), block.reshape(p, du + 1, (dv + 1) * c)).reshape(block.shape)
        for b in range(k):
            yield np.matmul(restriction(dv, b), along_u)  # over the v axis: (dv+1, dv+1) @ (p, du+1, dv+1, c)


def _net_bounds(points: np.ndarray) -> np.ndarray:
    """(p, 3) bounds of |x_uu|, |x_uv|, |x_vv| of polynomial patches (p, du+1, dv+1, 3) from their control net."""
    du, dv = points.shape[1] - 1, points.shape[2] - 1
    return np.stack(_difference_maxima(points, du, dv)[2:], axis=1)


def _rational_net_bounds(points: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(p, 3) bounds of rational patches (Euclidean control points (p, du+1, dv+1, 3), weights (p, du+1, dv+1))."""
    du, dv = points.shape[1] - 1, points.shape[2] - 1
    low, high = points.min(axis=(1, 2)), points.max(axis=(1, 2))
    centre = 0.5 * (low + high)  # (p, 3)
    radius = np.linalg.norm(points - centre[:, None, None], axis=-1).max(axis=(1, 2))
    g = w[..., None] * (points - centre[:, None, None])
    gu, gv, guu, guv, gvv = _difference_maxima(g, du, dv)
    wu, wv, wuu, wuv, wvv = _difference_maxima(w[..., None], du, dv)
    w_min = w.min(axis=(1, 2))
    xu = (gu + wu * radius) / w_min
    xv = (gv + wv * radius) / w_min
    muu = (guu + 2 * wu * xu + wuu * radius) / w_min
    muv = (guv + wu * xv + wv * xu + wuv * radius) / w_min
    mvv = (gvv + 2 * wv * xv + wvv * radius) / w_min
    return np.stack([muu, muv, mvv], axis=1)


def _difference_maxima(values: np.ndarray, du: int, dv: int):
    """Bounds of |f_u|, |f_v|, |f_uu|, |f_uv|, |f_vv| over patches from their control values.

    values : (p, du+1, dv+1, k) float; returns five (p,) float arrays (0 where the degree is too low)
    """
    p = values.shape[0]

    def largest(diff, factor):
        if diff.size == 0:
            return np.zeros(p)
        return factor * np.linalg.norm(diff, axis=-1).reshape(p, -1).max(axis=1)

    first_u, first_v = np.diff(values, axis=1), np.diff(values, axis=2)
    return (largest(first_u, du), largest(first_v, dv), largest(np.diff(first_u, axis=1), du * (du - 1)),
            largest(np.diff(first_u, axis=2), du * dv), largest(np.diff(first_v, axis=2), dv * (dv - 1)))


def bound(bounds: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(p,) float, the guaranteed chordal error (M_uu h_u^2 + 2 M_uv h_u h_v + M_vv h_v^2) / 8.

    bounds : (p, 3) float from ``second_derivative_bounds``; segments : (p, 2) int, (m_u, m_v) (h = 1 / m)
    """
    hu, hv = 1.0 / segments[:, 0], 1.0 / segments[:, 1]
    return (bounds[:, 0] * hu * hu + 2 * bounds[:, 1] * hu * hv + bounds[:, 2] * hv * hv) / 8


def _fewest_second(first: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, tau: float) -> np.ndarray:
    """Fewest segments in the second direction given ``first`` in the first (inf where none suffices).

    a, b, c : (p, k) float, M of the first direction, mixed, second direction; first : (p, k) float
    Solves c h^2 + 2 b h_1 h + (a h_1^2 - 8 tau) <= 0 for the largest h, then m = ceil(1 / h).
    """
    h1 = 1.0 / first
    left = 8 * tau - a * h1 * h1  # what the second direction may use
    rest = np.maximum(left, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(b * b * h1 * h1 + c * rest)
        h = np.where(c > 0, (root - b * h1) / np.where(c > 0, c, 1.0),
                     np.where(b > 0, rest / (2 * np.where(b > 0, b, 1.0) * h1), np.inf))
        # a hair below the exact root so that rounding does not cost a segment (patch_segments checks the bound)
        m = np.where(left > -1e-12 * tau, np.maximum(1.0, np.ceil(1.0 / h * (1 - 1e-12))), np.inf)
    return m


_AROUND = np.linspace(0.75, 1.35, 13)  # factors of the continuous optimum tried as integer segment counts


def patch_segments(bounds: np.ndarray, tau: float) -> np.ndarray:
    """Segments (m_u, m_v) of each patch: the fewest cells m_u m_v whose bound is at most ``tau``.

    The continuous optimum of m_u m_v under the bound has a h_u^2 = c h_v^2 (a, b, c =
    M_uu, M_uv, M_vv; Lagrange), i.e. m_u : m_v = sqrt(a) : sqrt(c). The integers
    next to 0.75 to 1.35 times it (and the isotropic count, and one segment) are tried
    in each direction, the other direction made minimal; the one with the fewest
    cells wins (tests: within 2 % of a brute-force search). Flat directions get one
    segment (a flat patch is two triangles). Blocks of patches at a time: the
    candidates are some 60 numbers per patch.

    Parameters
    ----------
    bounds : (p, 3) float, ``second_derivative_bounds``
    tau : float > 0, absolute chordal error

    Returns
    -------
    (p, 2) int64, each in 1..MAX_SEGMENTS, with ``bound(bounds, result) <= tau`` (up to
    MAX_SEGMENTS)
    """
    if not (np.isfinite(tau) and tau > 0):
        raise ValueError(f"the tolerance must be a positive number, got {tau}")
    out = np.zeros((bounds.shape[0], 2), dtype=np.int64)
    for lo in range(0, bounds.shape[0], _BOUND_BLOCK):
        out[lo : lo + _BOUND_BLOCK] = _block_segments(bounds[lo : lo + _BOUND_BLOCK], tau)
    return out


def _block_segments(bounds: np.ndarray, tau: float) -> np.ndarray:
    """``patch_segments`` of one block of patches."""
    p = bounds.shape[0]
    a, b, c = (np.maximum(bounds[:, k], 0.0)[:, None] for k in range(3))
    iso = np.maximum(1.0, np.ceil(np.sqrt((a + 2 * b + c) / (8 * tau))))
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where((a > 0) & (c > 0), 4 * tau * np.sqrt(a * c) / (np.sqrt(a * c) + b), np.nan)
        optimum_u, optimum_v = np.sqrt(a / x), np.sqrt(c / x)  # NaN where a direction is flat
    best, best_cells = None, None
    for first_is_u, optimum in ((True, optimum_u), (False, optimum_v)):
        scaled = optimum * _AROUND  # (p, k): the integers next to these
        grid = np.concatenate([np.ones((p, 1)), iso, np.floor(scaled), np.ceil(scaled)], axis=1)
        grid = np.where(np.isfinite(grid), np.clip(grid, 1, MAX_SEGMENTS), iso)
        first_m, (ma, mc) = grid, ((a, c) if first_is_u else (c, a))
        second = _fewest_second(first_m, ma, b, mc, tau)
        pair = np.stack([first_m, second], axis=-1) if first_is_u else np.stack([second, first_m], axis=-1)
        # fewest cells; among equal counts the squarer one (its sides match more neighbours)
        cells = np.where(np.isfinite(second), first_m * second + 1e-3 * (first_m + second), np.inf)
        pick = np.argmin(cells, axis=1)
        chosen = np.take_along_axis(pair, pick[:, None, None], axis=1)[:, 0]
        chosen_cells = np.take_along_axis(cells, pick[:, None], axis=1)[:, 0]
        if best is None:
            best, best_cells = chosen, chosen_cells
        else:
            better = chosen_cells < best_cells
            best = np.where(better[:, None], chosen, best)
            best_cells = np.where(better, chosen_cells, best_cells)
    segments = np.clip(best, 1, MAX_SEGMENTS).astype(np.int64)
    # rounding in the closed forms: one more segment where the bound is over, the way that brings it lower
    for _ in range(8):
        over = np.flatnonzero(bound(bounds, segments) > tau * (1 + 1e-12))  # not for rounding in h = 1 / m
        if not over.size:
            break
        more_u, more_v = segments[over] + [1, 0], segments[over] + [0, 1]
        pick_u = bound(bounds[over], more_u) <= bound(bounds[over], more_v)
        segments[over] = np.minimum(np.where(pick_u[:, None], more_u, more_v), MAX_SEGMENTS)
    return segments


def side_segments(edges: np.ndarray, segments: np.ndarray):
    """Segments of every patch side: the largest of the patches that share it, so both sample it identically.

    Sides 0 and 2 run along u (m_u), sides 1 and 3 along v (m_v).

    Parameters
    ----------
    edges : (P, 4) int, edge ids (``adjacency.PatchAdjacency.edges``); segments : (P, 2) int

    Returns
    -------
    (P, 4) int64 per side, and (n_edges,) int64 per edge id (0 for an id no side uses)
    """
    own = segments[:, [0, 1, 0, 1]]
    flat = np.asarray(edges, dtype=np.int64).ravel()
    per_edge = np.zeros(int(flat.max()) + 1 if flat.size else 0, dtype=np.int64)
    np.maximum.at(per_edge, flat, own.ravel())
    return per_edge[flat].reshape(own.shape), per_edge


def template_triangles(segments: np.ndarray, sides: np.ndarray) -> np.ndarray:
    """(P,) int64, triangles of ``triangulate.template`` for (m_u, m_v) ``segments`` (P, 2) and ``sides`` (P, 4).

    Regular (every side at the patch's own count): 2 m_u m_v. Otherwise the interior grid of
    n_u x n_v samples (n = m - 1, or 1 for one segment) gives 2 (n_u - 1)(n_v - 1) and each side's
    strip s + n - 1 (its two rows merged).
    """
    m_u, m_v = segments[:, 0], segments[:, 1]
    regular = (sides[:, 0] == m_u) & (sides[:, 2] == m_u) & (sides[:, 1] == m_v) & (sides[:, 3] == m_v)
    n_u, n_v = np.maximum(m_u - 1, 1), np.maximum(m_v - 1, 1)
    ring = 2 * (n_u - 1) * (n_v - 1) + sides.sum(axis=1) + 2 * (n_u - 1) + 2 * (n_v - 1)
    return np.where(regular, 2 * m_u * m_v, ring)


def fewer_triangles(segments: np.ndarray, sides: np.ndarray) -> np.ndarray:
    """(P, 2) int64: each patch's interior counts raised to its opposite sides' where that gives fewer triangles.

    A side takes the larger count of its two patches, so a patch may get sides
    finer than its interior; raising m_u up to min(s_0, s_2) (m_v up to
    min(s_1, s_3)) can turn the border strip into the plain grid (cheaper for one
    segment: the strip puts an interior line at 1/2). It only shrinks h, so the
    bound still holds, and it leaves every side count as it is (they are at least
    the new counts), so no neighbour changes.
    """
    best, best_count = segments, template_triangles(segments, sides)
    up_u, up_v = np.minimum(sides[:, 0], sides[:, 2]), np.minimum(sides[:, 1], sides[:, 3])
    for candidate in (np.stack([up_u, segments[:, 1]], 1), np.stack([segments[:, 0], up_v], 1), np.stack([up_u, up_v], 1)):
        count = template_triangles(candidate, sides)
        better = count < best_count
        best = np.where(better[:, None], candidate, best)
        best_count = np.where(better, count, best_count)
    return best


def least_triangles(segments: np.ndarray, bounds: np.ndarray, tau: float, edges: np.ndarray):
    """(segments, sides): the per-patch counts, or a floor under them, that give the fewest triangles.

    Transitions cost triangles (a border strip where a side is finer than its
    patch), so where neighbours need nearly the same counts a few more
    segments everywhere can give fewer triangles in all. Tried: the counts as
    chosen, raised to floors k = 2 .. the uniform count (geometrically spaced), and
    the uniform count that meets the bound on every patch (so the result never has
    more triangles than that uniform grid). Raising counts only shrinks h: the bound
    holds for every candidate. Each is counted with ``fewer_triangles`` and
    ``template_triangles``, without building templates.

    Parameters
    ----------
    segments : (P, 2) int64 (``patch_segments``); bounds : (P, 3) float; tau : float; edges : (P, 4) int64

    Returns
    -------
    segments (P, 2) int64 after ``fewer_triangles``; sides (P, 4) int64; per_edge (n_edges,) int64
    """
    if segments.shape[0] == 0:
        sides, per_edge = side_segments(edges, segments)
        return segments, sides, per_edge
    # at most MAX_SEGMENTS (a tiny tau asks for astronomically many: the caller refuses what the cap cannot meet)
    needed = np.ceil(np.sqrt(bounds.clip(min=0) @ [1.0, 2.0, 1.0] / (8 * tau))).max()
    uniform = int(min(max(1.0, needed), MAX_SEGMENTS)) if np.isfinite(needed) else MAX_SEGMENTS
    while uniform < MAX_SEGMENTS and np.any(bound(bounds, np.full(segments.shape, uniform)) > tau * (1 + 1e-12)):
        uniform += 1
    floors = np.unique(np.round(np.geomspace(2, max(uniform, 2), 8)).astype(np.int64))
    candidates = [segments] + [np.maximum(segments, k) for k in floors if k > 1] + [np.full(segments.shape, uniform)]
    best = None
    for candidate in candidates:
        sides, per_edge = side_segments(edges, candidate)
        raised = fewer_triangles(candidate, sides)
        count = int(template_triangles(raised, sides).sum())
        if best is None or count < best[0]:
            best = (count, raised, sides, per_edge)
    return best[1:]


__all__ = ["least_triangles", "second_derivative_bounds", "bound", "patch_segments", "side_segments", "template_triangles",
           "fewer_triangles", "MAX_SEGMENTS"]
