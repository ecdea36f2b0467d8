"""Two surfaces (patch sets) or two polygon meshes compared: structure first, then coefficients.

Patch sets are compared as surfaces. Structure must match exactly: patch
counts and degrees run by run, weights present or not, the sources where both
files record them; for meshes the vertex and face counts, face sizes and face
vertices. Then every control point or vertex may move by at most
``tolerance`` times the bounding-box diagonal of the first input (Euclidean
distance), and weights by ``tolerance`` times the first's largest weight. The
differences are listed the way ``tests/test_golden.py`` does: the patch (its
kind and source when the file records one), the coefficient index, where it
was and where it went, how far it moved.

Merged pieces (``convert --merge``, and the packed faces of IGES and STEP
files) are a way of writing patches, not part of the surface: each piece is
cut into its patches and compared with the patches it stands for in its own
file (``piece_differences``), so a packed file and an unpacked one of the
same surface compare equal, and a piece that is not its patches is a difference.

When the two files do not hold their patches in the same order (a STEP file:
faces in shell order, its reader sets ``header["ordered"] = False``; or the
two files pack their patches into other pieces: an IGES or STEP file lists a
piece's patches together) B's patches are paired with A's, degree run by
degree run, by their centres (``paired``), and each is turned in its parameter
square (quarter turns: the orientation, hence the normal, is kept) to the turn
nearest A's patch (``turned_like``), since a packed face gives its patches
the piece's (u, v). Files of the same order and packing are compared patch by
patch as they are: a turned patch counts as moved.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from .merge import piece_patches
from .patch_set import KIND_BY_DEGREE, PatchSet

SHOW = 8  # differences listed of each kind; the rest are counted


@dataclass(frozen=True)
class Comparison:
    """Result of ``compare_patch_sets`` / ``compare_meshes``.

    structural : list of str, structural differences (coefficients are then not compared)
    moved : list of str, the largest coefficient moves beyond the tolerance, at most ``SHOW`` of each kind
    n_moved : int, coefficients (control points, weights, vertices) beyond the tolerance
    max_relative : float, largest move relative to its scale (the diagonal; 0 for a structural difference)
    tolerance : float
    """

    structural: list = field(default_factory=list)
    moved: list = field(default_factory=list)
    n_moved: int = 0
    max_relative: float = 0.0
    tolerance: float = 0.0

    @property
    def equal(self) -> bool:
        return not self.structural and self.n_moved == 0

    def lines(self) -> list[str]:
        """The report: differences, then one summary line."""
        if self.structural:
            return self.structural + ["A and B differ in structure"]
        if self.n_moved:
            return self.moved + [f"{self.n_moved} coefficients moved by more than {self.tolerance:g} "
                                 f"(largest {self.max_relative:.3e} of its scale)"]
        return [f"equal within {self.tolerance:g} (largest move {self.max_relative:.3e} of the bounding-box diagonal)"]


def bbox_diagonal(points: np.ndarray) -> float:
    """Diagonal of the bounding box of (n, d) points; 1 for none or a single point."""
    if points.size == 0:
        return 1.0
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) or 1.0


def largest_moves(a: np.ndarray, b: np.ndarray, scale: float, tolerance: float, show: int = SHOW):
    """The entries of ``b`` farthest from ``a``, beyond ``tolerance * scale``.

    Parameters
    ----------
    a, b : (n, ..., d) float of one shape: n items (patches, vertices) of coefficients with d coordinates
        (d = 1 for weights)
    scale : float > 0

    Returns
    -------
    worst : list of at most ``show`` (relative move, index tuple into a[..., 0]), largest first;
    count : int, entries beyond the tolerance; largest : float, the largest relative move (0 if none)
    """
    relative = np.sqrt(np.sum((np.asarray(b, np.float64) - a) ** 2, axis=-1)) / scale
    if relative.size == 0:
        return [], 0, 0.0
    beyond = np.flatnonzero(relative.ravel() > tolerance)
    order = beyond[np.argsort(-relative.ravel()[beyond], kind="stable")][:show]
    worst = [(float(relative.ravel()[k]), np.unravel_index(k, relative.shape)) for k in order]
    return worst, int(beyond.size), float(relative.max())


def _index(name: str, index) -> str:
    return name + "".join(f"[{int(i)}]" for i in index)


def _move_line(label: str, name: str, index, old, new, relative: float, what: str, tolerance: float) -> str:
    old, new = np.atleast_1d(old).tolist(), np.atleast_1d(new).tolist()
    distance = float(np.linalg.norm(np.subtract(new, old)))
    shown = (lambda x: repr(x[0])) if len(old) == 1 else repr
    return (f"{label}: {_index(name, index)} {shown(old)} -> {shown(new)} "
            f"(moved {distance:.3e}, {relative:.3e} of {what} > {tolerance:g})")


def patch_labels(patch_set: PatchSet) -> list[str]:
    """``patch k (kind, source face 7)`` of every patch, the source where the file records one."""
    kinds = [KIND_BY_DEGREE.get(du, f"degree {du}") if du == dv else f"degree {du} x {dv}"
             for du, dv in patch_set.degrees()]
    sources = patch_set.source_dicts()
    labels = []
    for k, (kind, source) in enumerate(zip(kinds, sources)):
        where = ", ".join(f"{key} {value}" for key, value in (source or {}).items())
        labels.append(f"patch {k} ({kind}{', source ' + where if where else ''})")
    return labels


def _runs(patch_set: PatchSet) -> str:
    """The degree runs of a patch set, e.g. '54 biquadratic, 42 bicubic'."""
    return ", ".join(f"{len(g)} {KIND_BY_DEGREE.get(g.shape[1] - 1, 'degree ' + str(g.shape[1] - 1))}"
                     if g.shape[1] == g.shape[2] else f"{len(g)} of degree {g.shape[1] - 1} x {g.shape[2] - 1}"
                     for g in patch_set.groups) or "no patches"


def patch_structure(a: PatchSet, b: PatchSet, show: int = SHOW) -> list[str]:
    """Structural differences of two patch sets (empty: the coefficients can be compared)."""
    problems = []
    if [g.shape[:3] for g in a.groups] != [g.shape[:3] for g in b.groups]:
        problems.append(f"patches: {_runs(a)} -> {_runs(b)}")
    if (a.weights is None) != (b.weights is None):
        problems.append(f"weights: {'rational' if a.weights is not None else 'polynomial'} -> "
                        f"{'rational' if b.weights is not None else 'polynomial'} patches")
    if not problems and a.source_kind is not None and b.source_kind is not None:
        problems += _source_changes(a, b, show)
    return problems


def _source_changes(a: PatchSet, b: PatchSet, show: int) -> list[str]:
    """Patches whose recorded source differs (both files record sources)."""
    changed = np.flatnonzero((a.source_kind != b.source_kind) | np.any(a.source != b.source, axis=1))
    old, new, labels = a.source_dicts(), b.source_dicts(), patch_labels(a)
    lines = [f"{labels[k]}: source {old[k]} -> {new[k]}" for k in changed[:show]]
    if changed.size > show:
        lines.append(f"... the source differs in {changed.size} patches")
    return lines


def compare_patch_sets(a: PatchSet, b: PatchSet, tolerance: float = 1e-12, show: int = SHOW) -> Comparison:
    """Compare patch set ``b`` with ``a``: structure, then control points, weights and merged pieces.

    Control points and merged pieces' points are measured relative to the bounding-box
    diagonal of ``a``'s control points, weights relative to ``a``'s largest weight.
    """
    structural = patch_structure(a, b, show)
    if structural:
        return Comparison(structural, tolerance=tolerance)
    written = b  # its pieces number its patches as the file holds them
    if not (a.header.get("ordered", True) and b.header.get("ordered", True)) or not same_packing(a, b):
        b = turned_like(a, paired(a, b))
    diagonal = bbox_diagonal(np.concatenate([g[..., :3].reshape(-1, 3) for g in a.groups] or [np.zeros((0, 3))]))
    labels, found = patch_labels(a), []
    starts = np.cumsum([0] + [len(g) for g in a.groups])
    for k, (p, q) in enumerate(zip(a.groups, b.groups)):
        found.append((largest_moves(p[..., :3], q[..., :3], diagonal, tolerance, show), p[..., :3], q[..., :3],
                      "points", starts[k], "the bounding-box diagonal"))
    if a.weights is not None:
        top = max(float(np.max(w)) for w in a.weights if w.size) if any(w.size for w in a.weights) else 1.0
        for k, (p, q) in enumerate(zip(a.weights, b.weights)):
            found.append((largest_moves(p[..., None], q[..., None], top, tolerance, show), p, q, "weights", starts[k],
                          "the largest weight"))
    comparison = _collect(found, labels, tolerance, show)
    return _with_pieces(comparison, a, written, diagonal, show)


def same_packing(a: PatchSet, b: PatchSet) -> bool:
    """Both patch sets pack the same patches, with the same turns, into merged pieces (or neither has any)."""
    return len(a.merged) == len(b.merged) and all(
        np.array_equal(p.patches, q.patches) and np.array_equal(p.rotation, q.rotation) for p, q in zip(a.merged, b.merged))


def _turns(square: bool) -> tuple:
    """Quarter turns of a patch's parameter rectangle onto itself that keep its orientation."""
    return (0, 1, 2, 3) if square else (0, 2)


def turned_like(a: PatchSet, b: PatchSet) -> PatchSet:
    """``b`` with each patch turned in its parameter square (``np.rot90``, 0-3 quarter turns; a half turn for
    du != dv) to the turn whose control points lie nearest those of ``a``'s patch at the same place (the
    first such turn on a tie). The surface is unchanged. Same runs as ``a`` (``patch_structure``)."""
    groups, weights = list(b.groups), None if b.weights is None else list(b.weights)
    for k, (p, q) in enumerate(zip(a.groups, b.groups)):
        if not len(p):
            continue
        best, chosen = np.full(len(p), np.inf), np.zeros(len(p), np.int64)
        for turn in _turns(p.shape[1] == p.shape[2]):
            distance = np.abs(np.rot90(q, turn, axes=(1, 2))[..., :3] - p[..., :3]).max(axis=(1, 2, 3))
            better = distance < best
            best[better], chosen[better] = distance[better], turn
        for turn in np.unique(chosen[chosen > 0]).tolist():
            rows = chosen == turn
            groups[k] = groups[k].copy() if groups[k] is q else groups[k]
            groups[k][rows] = np.rot90(q[rows], turn, axes=(1, 2))
            if weights is not None:
                weights[k] = weights[k].copy() if weights[k] is b.weights[k] else weights[k]
                weights[k][rows] = np.rot90(b.weights[k][rows], turn, axes=(1, 2))
    return dataclasses.replace(b, groups=groups, weights=weights)


def piece_differences(patch_set: PatchSet, scale: float, tolerance: float, show: int = SHOW):
    """The merged pieces of ``patch_set`` against the patches they stand for (A2, Lemma 1.3.4: a piece is its
    patches, each turned by its rotation), control points relative to ``scale``.

    Returns
    -------
    list of (relative move, line) of at most ``show`` per piece, the count of coefficients beyond the
    tolerance and the largest relative move (0 without pieces)
    """
    quads = [g for g in patch_set.groups if g.shape[1:3] == (3, 3)]
    if not patch_set.merged or not quads:
        return [], 0, 0.0
    quad = np.concatenate(quads)[..., :3] if len(quads) > 1 else quads[0][..., :3]
    rows, count, largest = [], 0, 0.0
    for k, piece in enumerate(patch_set.merged):
        cut = piece_patches(piece)[0][..., :3]
        numbers, turns = piece.patches.ravel(), piece.rotation.ravel() % 4
        own = np.empty_like(cut)
        for turn in range(4):
            rows_k = turns == turn
            if rows_k.any():
                own[rows_k] = np.rot90(quad[numbers[rows_k]], turn, axes=(1, 2))
        worst, n, top = largest_moves(own, cut, scale, tolerance, show)
        count, largest = count + n, max(largest, top)
        n_v = piece.patches.shape[1]
        rows += [(relative, _move_line(f"merged piece {k} (span {index[0] // n_v} {index[0] % n_v} against patch "
                                       f"{int(numbers[index[0]])})", "points", index[1:], own[index], cut[index],
                                       relative, "the bounding-box diagonal", tolerance)) for relative, index in worst]
    return rows, count, largest


def patch_centres(group: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Points at (u, v) = (1/2, 1/2) of Bezier patches (p, du+1, dv+1, >= 3), rational with weights (p, du+1, dv+1).

    The same for a patch turned or transposed in its parameter square. Returns (p, 3) float.
    """
    du, dv = group.shape[1] - 1, group.shape[2] - 1
    bu, bv = (np.array([math.comb(d, i) for i in range(d + 1)]) / 2.0**d for d in (du, dv))
    w = np.ones(group.shape[:3]) if weights is None else weights
    wb = w * bu[:, None] * bv[None, :]  # (p, du+1, dv+1)
    return np.einsum("pij,pijc->pc", wb, group[..., :3]) / wb.sum(axis=(1, 2))[:, None]


def paired(a: PatchSet, b: PatchSet) -> PatchSet:
    """``b`` with the patches of each degree run in the order of ``a``'s, paired by their centres.

    A run whose centres do not pair one to one (nearest centres) is left in
    ``b``'s order. ``a`` and ``b`` must have the same runs (``patch_structure``).
    """
    groups, weights = list(b.groups), None if b.weights is None else list(b.weights)
    for k, (p, q) in enumerate(zip(a.groups, b.groups)):
        if not len(p):
            continue
        centres_a = patch_centres(p, None if a.weights is None else a.weights[k])
        centres_b = patch_centres(q, None if b.weights is None else b.weights[k])
        _, order = cKDTree(centres_b).query(centres_a)
        if np.array_equal(np.sort(order), np.arange(len(q))):
            groups[k] = q[order]
            if weights is not None:
                weights[k] = weights[k][order]
    return dataclasses.replace(b, groups=groups, weights=weights)


def _collect(found, labels, tolerance: float, show: int) -> Comparison:
    """One Comparison of the (moves, old, new, name, first patch, scale name) of ``largest_moves`` runs."""
    rows, count, largest = [], 0, 0.0
    for (worst, n, top), old, new, name, start, what in found:
        count, largest = count + n, max(largest, top)
        for relative, index in worst:
            label = labels[start + int(index[0])]
            rows.append((relative, _move_line(label, name, index[1:], old[index], new[index], relative, what, tolerance)))
    rows.sort(key=lambda r: -r[0])
    return Comparison([], [line for _, line in rows[:show]], count, largest, tolerance)


def _with_pieces(comparison: Comparison, a: PatchSet, b: PatchSet, diagonal: float, show: int) -> Comparison:
    """``comparison`` with every merged piece of A and of B compared with its own patches (``piece_differences``)."""
    rows = [(-1.0, line) for line in comparison.moved]  # the patches' own moves first, as they were
    count, largest = comparison.n_moved, comparison.max_relative
    for name, patch_set in (("A", a), ("B", b)):
        found, n, top = piece_differences(patch_set, diagonal, comparison.tolerance, show)
        rows += [(relative, f"{name}: {line}") for relative, line in found]
        count, largest = count + n, max(largest, top)
    return Comparison([], [line for _, line in rows[:show]], count, largest, comparison.tolerance)


def mesh_structure(sizes_a, vertices_a, n_a: int, sizes_b, vertices_b, n_b: int, show: int = SHOW) -> list[str]:
    """Structural differences of two polygon meshes (counts, face sizes, face vertices).

    Parameters
    ----------
    sizes_a, sizes_b : (F,) int, vertices per face; vertices_a, vertices_b : (sum sizes,) int, 0-based
    n_a, n_b : int, vertex counts
    """
    problems = []
    if n_a != n_b:
        problems.append(f"vertices: {n_a} -> {n_b}")
    if len(sizes_a) != len(sizes_b):
        problems.append(f"faces: {len(sizes_a)} -> {len(sizes_b)}")
        return problems
    changed = np.flatnonzero(np.asarray(sizes_a) != np.asarray(sizes_b))
    problems += [f"face {f}: {sizes_a[f]} -> {sizes_b[f]} sides" for f in changed[:show]]
    if changed.size:
        return problems + ([f"... {changed.size} faces have another size"] if changed.size > show else [])
    offsets = np.concatenate([[0], np.cumsum(sizes_a)])
    face_of = np.repeat(np.arange(len(sizes_a)), sizes_a)
    changed = np.unique(face_of[np.asarray(vertices_a) != np.asarray(vertices_b)])
    problems += [f"face {f}: vertices {vertices_a[offsets[f]:offsets[f + 1]].tolist()} -> "
                 f"{vertices_b[offsets[f]:offsets[f + 1]].tolist()}" for f in changed[:show]]
    if changed.size > show:
        problems.append(f"... {changed.size} faces have other vertices")
    return problems


def compare_meshes(points_a, sizes_a, vertices_a, points_b, sizes_b, vertices_b, tolerance: float = 1e-12,
                   show: int = SHOW) -> Comparison:
    """Compare mesh b with mesh a: structure, then vertex positions relative to a's bounding-box diagonal.

    Parameters
    ----------
    points_a, points_b : (V, 3) float
    sizes_a, sizes_b : (F,) int; vertices_a, vertices_b : (sum sizes,) int
    """
    points_a, points_b = np.asarray(points_a, np.float64)[:, :3], np.asarray(points_b, np.float64)[:, :3]
    structural = mesh_structure(sizes_a, vertices_a, len(points_a), sizes_b, vertices_b, len(points_b), show)
    if structural:
        return Comparison(structural, tolerance=tolerance)
    found = [(largest_moves(points_a, points_b, bbox_diagonal(points_a), tolerance, show), points_a, points_b,
              "position", 0, "the bounding-box diagonal")]
    return _collect(found, [f"vertex {v}" for v in range(len(points_a))], tolerance, show)


__all__ = ["Comparison", "compare_patch_sets", "paired", "turned_like", "same_packing", "piece_differences", "patch_centres", "compare_meshes", "patch_structure", "mesh_structure", "largest_moves",
           "bbox_diagonal", "patch_labels", "SHOW"]
