"""Independent smoothness check: find shared patch edges from geometry, measure G1.

Nothing here uses the construction's bookkeeping. Patch boundary curves are
matched by their end points and mid point (clustered with a k-d tree), so a
construction bug that puts the wrong coefficients on an edge shows up as a gap
or as an unmatched edge instead of being trusted.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .bezier import bernstein_basis, raise_degree, unit_normals

# Sides of a patch: (fixed parameter, its value); the other parameter runs 0 -> 1.
_SIDES = (("u", 0.0), ("u", 1.0), ("v", 0.0), ("v", 1.0))


@dataclass(frozen=True)
class SmoothnessReport:
    """Result of ``measure_smoothness``.

    shared_edges : int, patch edges found in exactly two patches
    boundary_edges : int, patch edges found in one patch only (open surfaces)
    overshared_edges : int, patch edges found in more than two patches
    max_gap : float, largest distance between the two sides of a shared edge
    max_normal_jump : float, largest angle (radians) between the two normals
    bbox_diagonal : float, diagonal of the control points' bounding box
    worst_pair : (2,) int, patches with the largest normal jump (-1 if none)
    """

    shared_edges: int
    boundary_edges: int
    overshared_edges: int
    max_gap: float
    max_normal_jump: float
    bbox_diagonal: float
    worst_pair: tuple

    @property
    def relative_gap(self) -> float:
        return self.max_gap / self.bbox_diagonal if self.bbox_diagonal > 0 else self.max_gap

    def is_g1(self, angle_tolerance: float = 1e-9, gap_tolerance: float = 1e-9) -> bool:
        return self.overshared_edges == 0 and self.max_normal_jump <= angle_tolerance and self.relative_gap <= gap_tolerance


def _cluster_points(points: np.ndarray, tolerance: float) -> np.ndarray:
    """(k,) int label per point; points closer than ``tolerance`` share one."""
    tree = cKDTree(points)
    pairs = tree.query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    return connected_components(graph, directed=False)[1].astype(np.int64)  # int32 labels would overflow in edge keys


def boundary_curves(patches: np.ndarray):
    """Control points of the 4 sides of each bicubic patch.

    Parameters
    ----------
    patches : (p, 4, 4, 3)

    Returns
    -------
    (p, 4, 4, 3): side s (order of ``_SIDES``: u=0, u=1, v=0, v=1), control point k
    """
    return np.stack([patches[:, 0, :], patches[:, -1, :], patches[:, :, 0], patches[:, :, -1]], axis=1)


def side_frames(patches: np.ndarray, curves: np.ndarray, t: np.ndarray, reverse=None, rational: bool = False):
    """Points and unit normals along patch sides.

    Along a side, position and normal need only the boundary row of control
    points and the row next to it, so this never evaluates whole patches.

    Parameters
    ----------
    patches : (p, 4, 4, 3) bicubic coefficients, or with ``rational`` (p, 4, 4, 4)
        homogeneous ones (w x, w): points are then x = H / w and derivatives
        follow the quotient rule, (H' - x w') / w
    curves : (k,) int, ``4 * patch + side`` (sides as in ``_SIDES``)
    t : (m,) float, parameters along the side
    reverse : (k,) bool or None, run the side from 1 to 0

    Returns
    -------
    points, normals : (k * m, 3)
    """
    patch, side = np.divmod(curves, 4)
    outer = np.where(side % 2 == 0, 0, 3)  # boundary row index
    inner = np.where(side % 2 == 0, 1, 2)  # the row next to it
    u_side = side < 2
    rows = np.where(u_side[:, None, None, None],
                    np.stack([patches[patch, outer], patches[patch, inner]], axis=1),
                    np.stack([patches[patch, :, outer], patches[patch, :, inner]], axis=1))  # (k, 2, 4, 3)
    if reverse is not None:
        # Running a side backwards reverses its control points; the derivative
        # along the side is taken in the patch's own direction, hence the sign.
        rows = np.where(reverse[:, None, None, None], rows[:, :, ::-1], rows)
    b, db = bernstein_basis(3, t), bernstein_basis(3, t, 1)
    sign_across = np.where(side % 2 == 1, -3.0, 3.0)  # at u=1 / v=1 the inner row is behind the boundary
    if reverse is not None:
        sign_along = np.where(reverse, -1.0, 1.0)[:, None, None]
    else:
        sign_along = 1.0
    boundary = np.matmul(b, rows[:, 0])  # (k, m, 3)
    along = np.matmul(db, rows[:, 0] * sign_along)
    across = np.matmul(b, (rows[:, 1] - rows[:, 0]) * sign_across[:, None, None])
    if rational:
        w = boundary[..., 3:]
        boundary = boundary[..., :3] / w
        along = (along[..., :3] - boundary * along[..., 3:]) / w
        across = (across[..., :3] - boundary * across[..., 3:]) / w
    u_side = u_side[:, None, None]
    du = np.where(u_side, across, along)
    dv = np.where(u_side, along, across)
    return boundary.reshape(-1, 3), _unit_cross(du.reshape(-1, 3), dv.reshape(-1, 3))


def _unit_cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise unit cross product of (k, 3) arrays (NaN where it vanishes); faster than np.cross."""
    n = np.empty_like(a)
    n[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    n[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    n[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    length = np.sqrt(np.einsum("ij,ij->i", n, n))
    with np.errstate(invalid="ignore", divide="ignore"):
        n /= length[:, None]
    return n


@dataclass(frozen=True)
class SideMatching:
    """Patch sides (``4 * patch + side``, sides as in ``_SIDES``) matched by geometry.

    first, second : (k,) int, the two sides of each shared edge
    reversed : (k,) bool, the two run in opposite directions
    lone : (m,) int, sides found in one patch only (the surface's boundary)
    overshared : int, edges found in more than two patches
    """

    first: np.ndarray
    second: np.ndarray
    reversed: np.ndarray
    lone: np.ndarray
    overshared: int


def match_patch_sides(patches: np.ndarray, tolerance: float) -> SideMatching:
    """Pair patch sides with the same end points and mid point (within ``tolerance``).

    Parameters
    ----------
    patches : (p, 4, 4, 3) bicubic coefficients (raise lower degrees first), or
        (p, 4, 4, 4) homogeneous ones (w x, w) of rational patches
    tolerance : float, absolute distance below which two points are the same
    """
    p = patches.shape[0]
    # Per patch: 4 corners, then the mid point of each side (order of _SIDES).
    corners = patches[:, [0, 3, 0, 3], [0, 0, 3, 3]]  # P00, P30, P03, P33
    curves = boundary_curves(patches)
    mids = (curves[:, :, 0] + 3 * curves[:, :, 1] + 3 * curves[:, :, 2] + curves[:, :, 3]) / 8
    if patches.shape[-1] == 4:  # rational: the points of the surface itself
        corners, mids = corners[..., :3] / corners[..., 3:], mids[..., :3] / mids[..., 3:]
    labels = _cluster_points(np.concatenate([corners, mids], axis=1).reshape(-1, 3), tolerance).reshape(p, 8)
    side_start = np.array([0, 1, 0, 2])  # u=0: P00 -> P03, u=1: P30 -> P33, v=0: P00 -> P30, v=1: P03 -> P33
    side_end = np.array([2, 3, 1, 3])
    start, end, mid = labels[:, side_start], labels[:, side_end], labels[:, 4:]
    n_labels = int(labels.max()) + 1
    key = ((np.minimum(start, end) * n_labels + np.maximum(start, end)) * n_labels + mid).ravel()
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    degenerate = (start == end).ravel()
    count_of_curve = counts[inverse]
    shared = np.flatnonzero((count_of_curve == 2) & ~degenerate)
    order = shared[np.argsort(inverse[shared], kind="stable")]
    first, second = order[0::2], order[1::2]
    return SideMatching(
        first=first,
        second=second,
        reversed=start.ravel()[first] != start.ravel()[second],
        lone=np.flatnonzero((count_of_curve == 1) & ~degenerate),
        overshared=int(np.unique(inverse[(count_of_curve > 2) & ~degenerate]).size),
    )


def measure_smoothness(patch_groups, samples: int = 11, unoriented: bool = False, tolerance: float = 1e-9,
                       weights=None) -> SmoothnessReport:
    """Sample every shared patch edge; measure position gap and normal jump.

    Parameters
    ----------
    patch_groups : list of (p, du+1, dv+1, 3) float arrays, du, dv <= 3
    weights : None, or a list of (p, du+1, dv+1) float arrays (one per group):
        rational patches, evaluated as sum(w P B) / sum(w B)
    samples : int, points per edge (end points included)
    unoriented : bool, compare normals up to sign (non-orientable surfaces)
    tolerance : float, relative distance below which two points are the same

    Returns
    -------
    SmoothnessReport
    """
    groups = [np.asarray(g, dtype=np.float64)[..., :3] for g in patch_groups if len(g)]
    if not groups:
        return SmoothnessReport(0, 0, 0, 0.0, 0.0, 0.0, (-1, -1))
    patches = np.concatenate([raise_degree(g, 3, 3) for g in groups])
    flat = patches.reshape(-1, 3)
    diagonal = float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0)))
    if weights is not None:
        # Rational patches: match sides by the surface's own corner and mid
        # points, and take frames by the quotient rule (homogeneous patches).
        weights = [np.asarray(w, dtype=np.float64) for g, w in zip(patch_groups, weights) if len(g)]
        patches = np.concatenate([raise_degree(np.concatenate([g * w[..., None], w[..., None]], axis=-1), 3, 3)
                                  for g, w in zip(groups, weights)])
    sides = match_patch_sides(patches, tolerance * max(diagonal, 1e-300))
    first, second = sides.first, sides.second
    boundary, overshared = int(sides.lone.size), sides.overshared
    if first.size == 0:
        return SmoothnessReport(0, boundary, overshared, 0.0, 0.0, diagonal, (-1, -1))

    t = np.linspace(0.0, 1.0, samples)
    reversed_ = sides.reversed
    xa, na = side_frames(patches, first, t, rational=weights is not None)
    xb, nb = side_frames(patches, second, t, reversed_, rational=weights is not None)
    pa_r = np.repeat(first // 4, samples)
    pb_r = np.repeat(second // 4, samples)
    gap = np.linalg.norm(xa - xb, axis=1)
    cross = np.linalg.norm(np.cross(na, nb), axis=1)
    dot = np.einsum("ij,ij->i", na, nb)
    if unoriented:
        dot = np.abs(dot)
    angle = np.arctan2(cross, dot)
    angle = np.where(np.isnan(angle), 0.0, angle)  # singular points (zero-length derivative) have no normal
    worst = int(np.argmax(angle))
    return SmoothnessReport(
        shared_edges=int(first.size),
        boundary_edges=boundary,
        overshared_edges=overshared,
        max_gap=float(gap.max()),
        max_normal_jump=float(angle.max()),
        bbox_diagonal=diagonal,
        worst_pair=(int(pa_r[worst]), int(pb_r[worst])),
    )
