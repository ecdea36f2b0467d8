"""Independent smoothness check: find shared patch edges from geometry, measure G1.

Nothing here uses the construction's bookkeeping. Patch sides are matched by
their end, quarter and mid points (``sides.matching``: the corners clustered,
the sides of two end points compared), so a construction bug that puts the wrong coefficients on an
edge shows up as a gap or as an unmatched edge instead of being trusted.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from .adjacency import SIDE_SAMPLES, _side_points, side_offsets
from .sides.matching import matching_tolerance, sides_of_corners
from ..mesh.points.clusters import cluster_points
from .bezier import bernstein_basis, cross3, unit_normals
from .rational import euclidean_derivatives, homogeneous
from .stream.patches import BLOCK, ArrayPatches, patch_blocks
from .stream.welded import in_order_on_threads
from .measure import compiled_loops
from ..memory import return_freed_memory
from ..parallel import for_each_range


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
    patches : (p, d+1, d+1, 3) coefficients of degree (d, d), or with ``rational`` (p, d+1, d+1, 4)
        homogeneous ones (w x, w): points are then x = H / w and derivatives
        follow the quotient rule (``rational.euclidean_derivatives``)
    curves : (k,) int, ``4 * patch + side`` (sides numbered as ``adjacency.SIDE_CORNERS``)
    t : (m,) float, parameters along the side
    reverse : (k,) bool or None, run the side from 1 to 0

    Returns
    -------
    points, normals : (k * m, 3)
    """
    d = patches.shape[1] - 1
    patch, side = np.divmod(curves, 4)
    flat = patches.reshape(patches.shape[0] * (d + 1) ** 2, patches.shape[-1])
    rows = flat[patch[:, None, None] * (d + 1) ** 2 + side_offsets(d)[side]]  # (k, 2, d+1, dim): boundary, next row
    if reverse is not None and reverse.any():
        # Running a side backwards reverses its control points; the derivative
        # along the side is taken in the patch's own direction, hence the sign.
        rows[reverse] = rows[reverse][:, :, ::-1]
    b, db = bernstein_basis(d, t), bernstein_basis(d, t, 1)
    # the next row lies at +v on side 0, -u on side 1, -v on side 2, +u on side 3
    sign_across = np.array([d, -d, -d, d], dtype=np.float64)[side]
    sign_along = np.where(reverse, -1.0, 1.0)[:, None, None] if reverse is not None else 1.0
    boundary = np.matmul(b, rows[:, 0])  # (k, m, dim)
    along = np.matmul(db, rows[:, 0] * sign_along)
    across = np.matmul(b, (rows[:, 1] - rows[:, 0]) * sign_across[:, None, None])
    if rational:
        x = euclidean_derivatives({(0, 0): boundary, (1, 0): along, (0, 1): across})
        boundary, along, across = x[(0, 0)], x[(1, 0)], x[(0, 1)]
    u_fixed = side % 2 == 1  # sides 1 and 3: across is x_u
    du, dv = along, across
    du[u_fixed], dv[u_fixed] = across[u_fixed], along[u_fixed]
    return boundary.reshape(-1, 3), unit_normals(du.reshape(-1, 3), dv.reshape(-1, 3))


@dataclass(frozen=True)
class SmoothnessSettings:
    """How ``measure_smoothness`` samples and matches (its keywords; see its docstring)."""

    samples: int = 11
    unoriented: bool = False
    tolerance: float = 1e-9
    crease_angle: float | None = None
    block: int = BLOCK


def measure_smoothness(patch_groups, weights=None, crease_sides=None, progress=None, **settings) -> SmoothnessReport:
    """Sample every shared patch edge; measure position gap and normal jump.

    Parameters
    ----------
    patch_groups : list of (p, du+1, dv+1, 3) float arrays, du, dv <= 3 (memory-mapped ones are read by blocks);
        or a ``stream.patches`` reader (``ArrayPatches``, ``SourcePatches``: a streamed Surface), ``weights`` None
    weights : None, or a list of (p, du+1, dv+1) float arrays (one per group):
        rational patches, evaluated as sum(w P B) / sum(w B)
    samples : int, points per edge (end points included)
    unoriented : bool, compare normals up to sign (non-orientable surfaces)
    tolerance : float, relative distance below which two points are the same
    crease_sides : (k, 2) int or None, curve ids ``4 p + s`` of the two sides of each C0 crease piece:
        found shared by those two sides, they are measured for their gap only
    crease_angle : float (radians) or None: without ``crease_sides``, the shared edges whose normals
        differ by more somewhere are crease pieces (for files that list none: IGES, STEP)
    block : int, patches (and shared edges) evaluated at a time: the result does not depend on it (every
        value is computed patch by patch or side by side, and only maxima are taken across blocks)
    progress : callable(label, advance, total) or None
    samples, unoriented, tolerance, crease_angle, block : keywords, the fields of ``SmoothnessSettings``

    Returns
    -------
    SmoothnessReport

    Long: the independent check's steps in their order, each array let go as soon as the next step has what
    it needs (side keys, corner and side clusters, the pairing), then the shared edges by blocks on the thread
    pool with their maxima: split, the arrays would live on in the callers' frames.
    """
    s = SmoothnessSettings(**settings)
    samples, unoriented, tolerance, crease_angle, block = s.samples, s.unoriented, s.tolerance, s.crease_angle, s.block
    patches = patch_groups if hasattr(patch_groups, "take") else ArrayPatches(patch_groups, weights)
    if not patches.counts:
        return SmoothnessReport(0, 0, 0, 0.0, 0.0, 0.0, (-1, -1))
    if compiled_loops(patches):  # numba (150 MB) before the matching's arrays: what the glibc heap kept goes first
        return_freed_memory()
    corners, points, diagonal = _side_keys(patches, block, progress)
    if progress is not None:
        progress("matching the patch sides", 0, 1)
    compiled = compiled_loops(patches)
    n, absolute = corners.shape[0], matching_tolerance(corners, tolerance * max(diagonal, 1e-300), compiled)
    corner_label = cluster_points(corners.reshape(-1, 3), absolute,
                                  _compiled_components if compiled else None).reshape(n, 4)
    del corners  # as ``sides.matching.match_sides``, each array let go as soon as it is used
    if compiled:  # the clustering's arrays given back (the command line has glibc keep freed memory)
        return_freed_memory()
    sides = sides_of_corners(corner_label, points, absolute, compiled)
    del corner_label, points
    if progress is not None:
        progress("matching the patch sides", 1, 1)
    first, second = _compact(sides.first), _compact(sides.second)
    boundary, overshared, reversed_ = int(sides.lone.size), sides.overshared, sides.reversed
    if sides.overshared_sides.size == 0:  # nothing for _sheet_creases: the matching's (P, 4) arrays let go
        sides = None  # (issue 36: 150 MB of a 1.2 M-patch check, before numba's 150 MB come)
    if first.size == 0:
        return SmoothnessReport(0, boundary, overshared, 0.0, 0.0, diagonal, (-1, -1),
                                unpaired_crease_sides=0 if crease_sides is None else len(crease_sides))
    t = np.linspace(0.0, 1.0, samples)
    listed = None if crease_sides is None else _crease_edges(first, second, crease_sides)
    edges = _EdgeMaxima()
    bend = crease_angle if crease_sides is None else None

    if compiled:  # the matching's arrays given back (the command line has glibc keep freed memory)
        return_freed_memory()

    # compiled: the edges in order of their lower patch, so that a block reads a few MB of a memory-mapped file
    # (the file order's: half the pages of the whole file per block, which stayed mapped, 0.57 GB of 1.2 M patches)
    order = np.argsort(np.minimum(first, second) >> 2, kind="stable") if compiled else None

    def measure(a: int):  # a block of shared edges, on the thread pool
        z = min(a + block, first.size)
        at = slice(a, z) if order is None else order[a:z]
        return a, z, _edge_samples(patches, first[at], second[at], reversed_[at], t, unoriented, compiled)
    bent = []
    for a, z, (gap, angle) in in_order_on_threads(range(0, first.size, block), measure, per_task=2):
        at = slice(a, z) if order is None else order[a:z]
        crease = None if listed is None else listed[0][at]
        bent.append(edges.add(gap, angle, first[at], second[at], samples, crease, bend,
                              a if order is None else order[a:z]))
        patches.release()
        if progress is not None:
            progress("measuring the shared edges", z - a, int(first.size))
    if crease_sides is None and crease_angle is not None:  # the edges that bend more than it: crease pieces
        crease_sides = np.concatenate(bent)
    creases = {"crease_edges": edges.crease_edges, "max_crease_gap": edges.max_crease_gap,
               "unpaired_crease_sides": 0 if listed is None else listed[1]}
    overshared = _sheet_creases(creases, sides, patches, crease_sides, t, tolerance * diagonal)
    worst = edges.worst // samples
    return SmoothnessReport(
        shared_edges=int(first.size),
        boundary_edges=boundary,
        overshared_edges=overshared,
        max_gap=edges.max_gap,
        max_normal_jump=edges.max_angle,
        bbox_diagonal=diagonal,
        worst_pair=(int(first[worst] // 4), int(second[worst] // 4)),
        **creases,
    )


def _compact(sides: np.ndarray) -> np.ndarray:
    """A contiguous copy of flat side ids (k,), int32 where they fit (``SideMatching.first`` is a strided view
    of a (2 k,) int64 array, which it would keep alive)."""
    return np.array(sides, dtype=np.int32 if sides.size and sides.max() < 2**31 else np.int64)


def _compiled_components(points, key, order, tolerance, pairs) -> np.ndarray:
    """``cluster_points``' components by ``kernels.cell_components`` (a union-find over the pairs of one cell
    hash and the other pairs: the labels of scipy's connected components of the same pairs)."""
    from .compiled import kernels  # numba: imported where the loops run

    labels = np.empty(points.shape[0], dtype=np.int64)
    kernels.cell_components(points, key, order, float(tolerance), pairs.reshape(-1, 2), labels)
    return labels


def _side_keys(patches, block: int, progress):
    """(corners (P, 4, 3), side points (P, 4, 3, 3), diagonal of the control points' bounding box), by blocks;
    in the compiled loops where ``compiled_loops`` says so (``kernels.side_keys``, on the thread pool)."""
    n = int(sum(patches.counts))
    corners, points = np.empty((n, 4, 3)), np.empty((n, 4, len(SIDE_SAMPLES), 3))
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    if compiled_loops(patches):
        from .compiled import kernels  # numba: imported where the loops run

        boxes = []
        for start, k, a, z in patch_blocks(patches, block):
            part = np.ascontiguousarray(patches.block(k, a, z)[0], dtype=np.float64)
            bases = [bernstein_basis(d, SIDE_SAMPLES) for d in patches.degrees[k]]

            def fill(lo: int, hi: int) -> None:  # a range of the block's patches, on the thread pool
                box = np.stack([np.full(3, np.inf), np.full(3, -np.inf)])
                kernels.side_keys(part[lo:hi], *bases, corners[start + lo : start + hi],
                                  points[start + lo : start + hi], box)
                boxes.append(box)  # minima and maxima: the same whatever the ranges
            for_each_range(z - a, fill, minimum=1 << 12)
            if progress is not None:
                progress("finding the shared edges", z - a, n)
        box = np.concatenate(boxes) if boxes else np.zeros((2, 3))
        return corners, points, float(np.linalg.norm(box[1::2].max(axis=0) - box[0::2].min(axis=0)))
    for start, k, a, z in patch_blocks(patches, block):
        part, weights = patches.block(k, a, z)
        corners[start : start + z - a], points[start : start + z - a] = _side_points(
            [part], None if weights is None else [weights])
        flat = part.reshape(-1, 3)
        low, high = np.minimum(low, flat.min(axis=0)), np.maximum(high, flat.max(axis=0))
        if progress is not None:
            progress("finding the shared edges", z - a, n)
    return corners, points, float(np.linalg.norm(high - low))


class _EdgeMaxima:
    """The maxima over blocks of shared edges: gap and normal jump (first position of the largest, as
    ``np.argmax`` over all samples), crease pieces' gap and count."""

    def __init__(self):
        self.max_gap = self.max_angle = self.max_crease_gap = 0.0
        self.best, self.worst, self.crease_edges = -1.0, 0, 0

    def add(self, gap, angle, first, second, samples: int, crease, crease_angle, offset):
        """Take in the ``_edge_samples`` of the edges of sides first, second (k,) int (the k edges from
        ``offset`` on, or ``offset`` (k,) int the edges' positions: blocks out of order, the worst sample still
        the first of the largest in the edges' order); return the (b, 2) side pairs found bent more than
        ``crease_angle`` (none without it); ``crease``: (k,) bool, the listed crease pieces, or None."""
        bent = np.zeros((0, 2), dtype=np.int64)
        if crease is None and crease_angle is not None:
            crease = angle.reshape(first.size, -1).max(axis=1) > crease_angle
            bent = np.stack([first[crease], second[crease]], axis=1)
        if crease is not None:
            on_crease = np.repeat(crease, samples)
            self.crease_edges += int(crease.sum())
            self.max_crease_gap = max(self.max_crease_gap, float(gap[on_crease].max(initial=0.0)))
            gap, angle = np.where(on_crease, 0.0, gap), np.where(on_crease, 0.0, angle)
        self.max_gap = max(self.max_gap, float(gap.max()))
        worst = int(np.argmax(angle))
        value = float(angle[worst])
        if isinstance(offset, np.ndarray):  # positions: the tied samples' lowest one
            tied = np.flatnonzero(angle == value)
            index = int((offset[tied // samples].astype(np.int64) * samples + tied % samples).min())
        else:
            index = offset * samples + worst
        if value > self.best or (value == self.best and index < self.worst):
            self.best, self.worst = value, index
        self.max_angle = max(self.best, 0.0)
        return bent


def _edge_samples(patches, first, second, reversed_, t, unoriented: bool, compiled: bool = False):
    """(gap, angle) (k * m,) float at the m parameters ``t`` along the k shared edges of sides ``first``, ``second``;
    with ``compiled``, in the compiled loops (``_compiled_edge_samples``)."""
    if compiled:
        return _compiled_edge_samples(patches, first, second, reversed_, t, unoriented)
    xa, na = _patch_side_frames(patches, first, t, None)
    xb, nb = _patch_side_frames(patches, second, t, reversed_)
    return np.linalg.norm(xa - xb, axis=1), normal_angles(na, nb, unoriented)


def _compiled_edge_samples(patches, first, second, reversed_, t, unoriented: bool):
    """``_edge_samples`` of polynomial patches by ``kernels.side_frames`` and ``kernels.frame_jumps``: the same
    values as numpy's to rounding (each side's sums in their own order), a side at a time (the same bits in any
    block)."""
    from .compiled import kernels  # numba: imported where the loops run

    k, m = first.size, t.size
    frames = [np.empty((k, m, 3)) for _ in range(4)]
    starts = np.concatenate([[0], np.cumsum(patches.counts)])
    for curves, reverse, (x, n) in ((first, np.zeros(k, dtype=bool), frames[:2]), (second, reversed_, frames[2:])):
        curves = np.asarray(curves, dtype=np.int64)
        group = np.searchsorted(starts, curves // 4, side="right") - 1
        for g in np.unique(group):
            mine = np.flatnonzero(group == g)
            ids = curves[mine] // 4 - starts[g]
            whole = _whole_group(patches, int(g))
            part, ids = (whole, ids) if whole is not None else (
                np.ascontiguousarray(patches.take(int(g), ids)[0], dtype=np.float64), np.arange(ids.size))
            d = part.shape[1] - 1
            edges = (ids, mine, curves[mine] % 4, np.asarray(reverse[mine], dtype=bool))
            layout = (side_offsets(d).astype(np.int64), bernstein_basis(d, t), bernstein_basis(d, t, 1),
                      np.array([d, -d, -d, d], dtype=np.float64))
            kernels.side_frames(part.reshape(part.shape[0], (d + 1) ** 2, part.shape[-1]), edges, layout, (x, n))
    gap, angle = np.empty(k * m), np.empty(k * m)
    kernels.frame_jumps(*frames, bool(unoriented), gap, angle)
    return gap, angle


def _whole_group(patches, k: int):
    """Group ``k`` of an ``ArrayPatches`` reader as the array it holds (memory-mapped: the compiled loops read the
    rows they need, no gather), when it is C-contiguous float64; else None (``take`` then)."""
    groups = getattr(patches, "groups", None)
    if groups is None or patches.rational:
        return None
    g = groups[k]
    return g if isinstance(g, np.ndarray) and g.dtype == np.float64 and g.flags.c_contiguous else None


def _patch_side_frames(patches, curves: np.ndarray, t: np.ndarray, reverse):
    """``side_frames`` of sides ``curves`` (k,) (global ``4 * patch + side``) of a patch reader, each at its own
    patch's degree (biquadratic sides are not raised): points, normals (k * m, 3)."""
    m = t.size
    points, normals = np.empty((curves.size * m, 3)), np.empty((curves.size * m, 3))
    starts = np.concatenate([[0], np.cumsum(patches.counts)])
    group = np.searchsorted(starts, curves // 4, side="right") - 1
    for k in np.unique(group):
        mine = np.flatnonzero(group == k)
        part, weights = patches.take(int(k), curves[mine] // 4 - starts[k])
        coefficients = part if weights is None else homogeneous(part, weights)
        rows = (mine[:, None] * m + np.arange(m)).reshape(-1)
        points[rows], normals[rows] = side_frames(coefficients, 4 * np.arange(mine.size) + curves[mine] % 4, t,
                                                  None if reverse is None else reverse[mine], patches.rational)
    return points, normals


def normal_angles(na: np.ndarray, nb: np.ndarray, unoriented: bool = False) -> np.ndarray:
    """(k,) float: angles (rad) between unit normals (k, 3), from the cross product (arccos of a dot product
    near 1 keeps half the digits); up to sign when ``unoriented``; 0 where a normal is undefined (NaN)."""
    dot = np.einsum("ij,ij->i", na, nb)
    angle = np.arctan2(np.linalg.norm(cross3(na, nb), axis=1), np.abs(dot) if unoriented else dot)
    return np.where(np.isnan(angle), 0.0, angle)  # singular points (zero-length derivative) have no normal


def _sheet_creases(creases: dict, sides, patches, crease_sides, t, tolerance: float) -> int:
    """Measure the listed crease pieces on edges in more than two sides (non-manifold edges cut into
    sheets that meet along one crease: ``mesh.creases.non_manifold``) side against side, into
    ``creases``; return the edges in more than two sides that no listed piece accounts for (``sides`` None:
    there are none)."""
    if sides is None:
        return 0
    over = sides.overshared_sides
    if crease_sides is None or len(crease_sides) == 0 or over.size == 0:
        return sides.overshared
    pairs = np.asarray(crease_sides, dtype=np.int64).reshape(-1, 2)
    direct = pairs[np.isin(pairs, over).all(axis=1)]
    if len(direct):
        forward = sides.forward.ravel()
        gap = np.concatenate([_edge_samples(patches, part[:, 0], part[:, 1],
                                            forward[part[:, 0]] != forward[part[:, 1]], t, False)[0]
                              for part in np.array_split(direct, -(-len(direct) // BLOCK))])
        gap = gap.reshape(len(direct), -1).max(axis=1)
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
