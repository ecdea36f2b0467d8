"""Independent smoothness check: find shared patch edges from geometry, measure G1.

Nothing here uses the construction's bookkeeping. Patch sides are matched by
their end, quarter and mid points (``adjacency.match_patch_sides``, clustered
with a k-d tree), so a construction bug that puts the wrong coefficients on an
edge shows up as a gap or as an unmatched edge instead of being trusted.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from .adjacency import match_patch_sides, side_offsets
from .bezier import bernstein_basis, raise_degree, unit_normals
from .rational import euclidean_derivatives, homogeneous


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
    crease_edges : int, shared edges that are C0 crease pieces (``crease_sides``): their normal
        jump is the crease's and is not in ``max_normal_jump``
    max_crease_gap : float, largest distance between the two sides of a crease piece
    unpaired_crease_sides : int, crease pieces whose two sides were not found at the same place
    """

    shared_edges: int
    boundary_edges: int
    overshared_edges: int
    max_gap: float
    max_normal_jump: float
    bbox_diagonal: float
    worst_pair: tuple
    crease_edges: int = 0
    max_crease_gap: float = 0.0
    unpaired_crease_sides: int = 0

    @property
    def relative_gap(self) -> float:
        return self.max_gap / self.bbox_diagonal if self.bbox_diagonal > 0 else self.max_gap

    @property
    def relative_crease_gap(self) -> float:
        return self.max_crease_gap / self.bbox_diagonal if self.bbox_diagonal > 0 else self.max_crease_gap

    def is_g1(self, angle_tolerance: float = 1e-9, gap_tolerance: float = 1e-9) -> bool:
        """G1 across every shared edge but the crease pieces, which must meet (C0) with a partner each."""
        return (self.overshared_edges == 0 and self.max_normal_jump <= angle_tolerance and self.relative_gap <= gap_tolerance
                and self.unpaired_crease_sides == 0 and self.relative_crease_gap <= gap_tolerance)


def side_frames(patches: np.ndarray, curves: np.ndarray, t: np.ndarray, reverse=None, rational: bool = False):
    """Points and unit normals along patch sides.

    Along a side, position and normal need only the boundary row of control
    points and the row next to it, so this never evaluates whole patches.

    Parameters
    ----------
    patches : (p, 4, 4, 3) bicubic coefficients, or with ``rational`` (p, 4, 4, 4)
        homogeneous ones (w x, w): points are then x = H / w and derivatives
        follow the quotient rule (``rational.euclidean_derivatives``)
    curves : (k,) int, ``4 * patch + side`` (sides numbered as ``adjacency.SIDE_CORNERS``)
    t : (m,) float, parameters along the side
    reverse : (k,) bool or None, run the side from 1 to 0

    Returns
    -------
    points, normals : (k * m, 3)
    """
    patch, side = np.divmod(curves, 4)
    flat = patches.reshape(patches.shape[0] * 16, patches.shape[-1])
    rows = flat[patch[:, None, None] * 16 + side_offsets(3)[side]]  # (k, 2, 4, d): boundary row, next row inwards
    if reverse is not None:
        # Running a side backwards reverses its control points; the derivative
        # along the side is taken in the patch's own direction, hence the sign.
        rows = np.where(reverse[:, None, None, None], rows[:, :, ::-1], rows)
    b, db = bernstein_basis(3, t), bernstein_basis(3, t, 1)
    # the next row lies at +v on side 0, -u on side 1, -v on side 2, +u on side 3
    sign_across = np.array([3.0, -3.0, -3.0, 3.0])[side]
    sign_along = np.where(reverse, -1.0, 1.0)[:, None, None] if reverse is not None else 1.0
    boundary = np.matmul(b, rows[:, 0])  # (k, m, d)
    along = np.matmul(db, rows[:, 0] * sign_along)
    across = np.matmul(b, (rows[:, 1] - rows[:, 0]) * sign_across[:, None, None])
    if rational:
        x = euclidean_derivatives({(0, 0): boundary, (1, 0): along, (0, 1): across})
        boundary, along, across = x[(0, 0)], x[(1, 0)], x[(0, 1)]
    u_fixed = (side % 2 == 1)[:, None, None]  # sides 1 and 3: across is x_u
    du = np.where(u_fixed, across, along)
    dv = np.where(u_fixed, along, across)
    return boundary.reshape(-1, 3), unit_normals(du.reshape(-1, 3), dv.reshape(-1, 3))


def measure_smoothness(patch_groups, samples: int = 11, unoriented: bool = False, tolerance: float = 1e-9,
                       weights=None, crease_sides=None, crease_angle: float | None = None) -> SmoothnessReport:
    """Sample every shared patch edge; measure position gap and normal jump.

    Parameters
    ----------
    patch_groups : list of (p, du+1, dv+1, 3) float arrays, du, dv <= 3
    weights : None, or a list of (p, du+1, dv+1) float arrays (one per group):
        rational patches, evaluated as sum(w P B) / sum(w B)
    samples : int, points per edge (end points included)
    unoriented : bool, compare normals up to sign (non-orientable surfaces)
    tolerance : float, relative distance below which two points are the same
    crease_sides : (k, 2) int or None, curve ids ``4 p + s`` of the two sides of each C0 crease piece:
        found shared by those two sides, they are measured for their gap only
    crease_angle : float (radians) or None: without ``crease_sides``, the shared edges whose normals
        differ by more somewhere are crease pieces (for files that list none: IGES, STEP)

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
        # Rational patches: sides matched by the surface's own points, frames by
        # the quotient rule from the homogeneous patches (raised as such).
        weights = [np.asarray(w, dtype=np.float64) for g, w in zip(patch_groups, weights) if len(g)]
        patches = np.concatenate([raise_degree(homogeneous(g, w), 3, 3) for g, w in zip(groups, weights)])
    sides = match_patch_sides(groups, tolerance * max(diagonal, 1e-300), weights)
    first, second = sides.first, sides.second
    boundary, overshared = int(sides.lone.size), sides.overshared
    if first.size == 0:
        return SmoothnessReport(0, boundary, overshared, 0.0, 0.0, diagonal, (-1, -1),
                                unpaired_crease_sides=0 if crease_sides is None else len(crease_sides))

    t = np.linspace(0.0, 1.0, samples)
    xa, na = side_frames(patches, first, t, rational=weights is not None)
    xb, nb = side_frames(patches, second, t, sides.reversed, rational=weights is not None)
    pa_r, pb_r = np.repeat(first // 4, samples), np.repeat(second // 4, samples)
    gap = np.linalg.norm(xa - xb, axis=1)
    angle = normal_angles(na, nb, unoriented)
    if crease_sides is None and crease_angle is not None:  # the edges that bend more than it: crease pieces
        crease_sides = _bent_sides(angle, first, second, crease_angle)
    gap, angle, creases = _set_creases_apart(gap, angle, first, second, crease_sides, samples)
    overshared = _sheet_creases(creases, sides, patches, crease_sides, t, weights is not None, tolerance * diagonal)
    worst = int(np.argmax(angle))
    return SmoothnessReport(
        shared_edges=int(first.size),
        boundary_edges=boundary,
        overshared_edges=overshared,
        max_gap=float(gap.max()),
        max_normal_jump=float(angle.max()),
        bbox_diagonal=diagonal,
        worst_pair=(int(pa_r[worst]), int(pb_r[worst])),
        **creases,
    )


def normal_angles(na: np.ndarray, nb: np.ndarray, unoriented: bool = False) -> np.ndarray:
    """(k,) float: angles (rad) between unit normals (k, 3), from the cross product (arccos of a dot product
    near 1 keeps half the digits); up to sign when ``unoriented``; 0 where a normal is undefined (NaN)."""
    dot = np.einsum("ij,ij->i", na, nb)
    angle = np.arctan2(np.linalg.norm(np.cross(na, nb), axis=1), np.abs(dot) if unoriented else dot)
    return np.where(np.isnan(angle), 0.0, angle)  # singular points (zero-length derivative) have no normal


def _bent_sides(angle: np.ndarray, first: np.ndarray, second: np.ndarray, crease_angle: float) -> np.ndarray:
    """(k, 2) int: the matched side pairs whose normals differ by more than ``crease_angle`` somewhere along
    them (``angle``: (pairs * samples,) radians), to be measured as crease pieces."""
    bent = angle.reshape(first.size, -1).max(axis=1) > crease_angle
    return np.stack([first[bent], second[bent]], axis=1)


def _set_creases_apart(gap: np.ndarray, angle: np.ndarray, first, second, crease_sides, samples: int):
    """(gap, angle) with the samples on crease pieces zeroed, and the crease fields of the report."""
    crease, unpaired = _crease_edges(first, second, crease_sides)
    on_crease = np.repeat(crease, samples)
    creases = {"crease_edges": int(crease.sum()), "max_crease_gap": float(gap[on_crease].max(initial=0.0)),
               "unpaired_crease_sides": unpaired}
    return np.where(on_crease, 0.0, gap), np.where(on_crease, 0.0, angle), creases


def _sheet_creases(creases: dict, sides, patches, crease_sides, t, rational: bool, tolerance: float) -> int:
    """Measure the listed crease pieces on edges in more than two sides (non-manifold edges cut into
    sheets that meet along one crease: ``mesh.creases.non_manifold``) side against side, into
    ``creases``; return the edges in more than two sides that no listed piece accounts for."""
    over = sides.overshared_sides
    if crease_sides is None or len(crease_sides) == 0 or over.size == 0:
        return sides.overshared
    pairs = np.asarray(crease_sides, dtype=np.int64).reshape(-1, 2)
    direct = pairs[np.isin(pairs, over).all(axis=1)]
    if len(direct):
        forward = sides.forward.ravel()
        xa, _ = side_frames(patches, direct[:, 0], t, rational=rational)
        xb, _ = side_frames(patches, direct[:, 1], t, forward[direct[:, 0]] != forward[direct[:, 1]], rational=rational)
        gap = np.linalg.norm(xa - xb, axis=1).reshape(len(direct), -1).max(axis=1)
        creases["crease_edges"] += len(direct)
        creases["max_crease_gap"] = max(creases["max_crease_gap"], float(gap.max()))
        creases["unpaired_crease_sides"] += int(np.count_nonzero(gap > tolerance)) - len(direct)
    labels = sides.edges.ravel()
    unlisted = over[~np.isin(over, direct)]
    return int(np.unique(labels[unlisted]).size)


def _crease_edges(first: np.ndarray, second: np.ndarray, crease_sides) -> tuple:
    """((k,) bool: which matched side pairs are crease pieces, number of crease pieces not matched as such)."""
    if crease_sides is None or len(crease_sides) == 0:
        return np.zeros(first.size, dtype=bool), 0
    pairs = np.sort(np.asarray(crease_sides, dtype=np.int64).reshape(-1, 2), axis=1)
    matched = np.sort(np.stack([first, second], axis=1).astype(np.int64), axis=1)
    width = int(max(pairs.max(), matched.max(initial=0))) + 1
    known = np.unique(pairs[:, 0] * width + pairs[:, 1])
    found = matched[:, 0] * width + matched[:, 1]
    crease = np.isin(found, known)
    return crease, int(known.size - np.unique(found[crease]).size)
