"""What the c1surf patch file readers (JSON, NPZ) check, each refusal one line naming the file.

The arrays a file gives for the header, the adjacency, the weights and the
merged pieces become the parts of a ``PatchSet`` here, or a ``MeshInputError``
saying what is wrong.
"""
from __future__ import annotations

import numpy as np

from ...evaluation.adjacency import PatchAdjacency
from ...evaluation.merge import MergedPiece
from ...evaluation.patch_set import FORMAT_NAME, FORMAT_VERSION
from ...mesh.points.geometry_checks import GeometryError, check_coordinate_range
from ..errors import MeshInputError
from .merged import clamped_knots

__all__ = ["whole_numbers", "check_header", "checked_adjacency", "checked_weights", "checked_piece", "check_crease_sides", "check_patch_range",
           "check_net_range", "WEIGHT_RANGE"]


def whole_numbers(values) -> np.ndarray:
    """``values`` (nested lists or an array) as int64; ValueError (OverflowError for Python ints beyond int64)
    unless every one is a whole number of int64's range: a float array's NaN, 1e308 or 0.5 is no index."""
    array = np.asarray(values)
    if array.dtype.kind == "f":
        if not (np.all(np.abs(array) < 2.0**62) and np.all(array == np.round(array))):  # also refuses NaN
            raise ValueError("indices must be whole numbers below 2**62")
    elif array.dtype.kind == "u" and array.size and array.max() >= 2**62:
        raise ValueError("indices must be below 2**62")
    elif array.dtype.kind == "O" and array.size:
        array = np.asarray(values, dtype=np.int64)  # nested Python ints (JSON): OverflowError beyond int64
    elif array.dtype.kind not in "iub":  # complex numbers, strings, dates
        raise ValueError(f"indices must be whole numbers, not {array.dtype.name}")
    return array.astype(np.int64)


def check_header(path, header) -> None:
    """Refuse a header (dict) that is not of a c1surf patch file of the version this c1surf reads."""
    if not isinstance(header, dict) or header.get("format") != FORMAT_NAME:
        raise MeshInputError(str(path), f'not a c1surf patch file (missing "format": "{FORMAT_NAME}")')
    if header.get("version") != FORMAT_VERSION:
        raise MeshInputError(str(path), f"patch file version {header.get('version')} is not supported "
                             f"(this c1surf reads version {FORMAT_VERSION})")


def checked_adjacency(path, corners, edges, reversed_, n_patches: int) -> PatchAdjacency:
    """The PatchAdjacency of (P, 4) corner ids, edge ids and reversed flags, validated for ``n_patches``."""
    try:
        adjacency = PatchAdjacency(whole_numbers(corners), whole_numbers(edges), np.asarray(reversed_, dtype=bool))
        adjacency.validate(n_patches)
    except (TypeError, ValueError, OverflowError) as e:
        raise MeshInputError(str(path), f"malformed patch adjacency ({e})") from None
    return adjacency


def checked_weights(path, what: str, weights, shape: tuple) -> np.ndarray:
    """``weights`` as float64 of ``shape``, all positive and finite; ``what`` names them in the refusal."""
    try:
        w = np.asarray(weights, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as e:
        raise MeshInputError(str(path), f"{what}: malformed weights ({e})") from None
    if w.shape != tuple(shape) or not np.all(np.isfinite(w) & (w > 0)):
        raise MeshInputError(str(path), f"{what}: weights must be positive with shape {tuple(shape)}, got {w.shape}")
    return w


def checked_piece(path, k: int, points, weights, knots, patches, rotation, n_biquadratic: int) -> MergedPiece:
    """A MergedPiece from the arrays a patch file gives for merged piece ``k``.

    Parameters
    ----------
    points : (m + 2, n + 2, 3) float; weights : (m + 2, n + 2) float or None
    knots : (knots_u (m + 5,) float, knots_v (n + 5,) float), those of ``merged.clamped_knots``
    patches, rotation : (m, n) int, biquadratic patch numbers (< ``n_biquadratic``) and quarter turns 0..3
    """
    what = f"merged piece {k}"
    try:
        points = np.asarray(points, dtype=np.float64)
        knots_u, knots_v = (np.asarray(x, dtype=np.float64).ravel() for x in knots)
        patches, rotation = (whole_numbers(x) for x in (patches, rotation))
    except (TypeError, ValueError, OverflowError) as e:
        raise MeshInputError(str(path), f"{what}: malformed ({e})") from None
    if points.ndim != 3 or points.shape[2] != 3 or min(points.shape[:2]) < 3 or not np.isfinite(points).all():
        raise MeshInputError(str(path), f"{what}: points must be finite with shape (m + 2, n + 2, 3), m, n >= 1, "
                             f"got {points.shape}")
    m, n = points.shape[0] - 2, points.shape[1] - 2
    if not (np.array_equal(knots_u, clamped_knots(m)) and np.array_equal(knots_v, clamped_knots(n))):
        raise MeshInputError(str(path), f"{what}: knots must be 0 0 0 1 ... m m m for its {m} x {n} spans")
    if weights is not None:
        weights = checked_weights(path, what, weights, (m + 2, n + 2))
    if patches.shape != (m, n) or rotation.shape != (m, n):
        raise MeshInputError(str(path), f"{what}: patches and rotation must have shape {(m, n)}, "
                             f"got {patches.shape} and {rotation.shape}")
    if np.any((patches < 0) | (patches >= n_biquadratic)) or np.any((rotation < 0) | (rotation > 3)):
        raise MeshInputError(str(path), f"{what}: patches must number biquadratic patches (0 .. {n_biquadratic - 1}) "
                             "and rotation count quarter turns (0 .. 3)")
    return MergedPiece(points, weights, knots_u, knots_v, patches, rotation)


def check_crease_sides(path, header: dict, n_patches: int) -> None:
    """The header's "crease_sides" ([[patch, side, patch, side], ...], docs/patch-format.md), if any, must name
    sides of this file's patches, each at most once (but the first side of a piece shared by more than two
    sheets, once per other side)."""
    if "crease_sides" not in header:
        return
    try:
        rows = whole_numbers(header["crease_sides"]).reshape(-1, 4)
    except (ValueError, TypeError, OverflowError) as e:
        raise MeshInputError(str(path), f'"crease_sides" must be rows [patch, side, patch, side] ({e})') from None
    patches, sides = rows[:, [0, 2]], rows[:, [1, 3]]
    if np.any((patches < 0) | (patches >= n_patches) | (sides < 0) | (sides > 3)):
        raise MeshInputError(str(path), f'"crease_sides" names a side that is not one of the {n_patches} patches\' sides 0..3')
    first, second = 4 * patches[:, 0] + sides[:, 0], 4 * patches[:, 1] + sides[:, 1]
    # a piece of crease shared by k > 2 sheets (non-manifold edges) is k - 1 rows with the same first side;
    # any other side is named once
    if (np.unique(second).size != second.size or np.isin(second, first).any() or np.any(first == second)):
        raise MeshInputError(str(path), '"crease_sides" names a patch side twice')


def check_patch_range(path, patch_set) -> None:
    """Refuse (``MeshInputError``) control points whose bounding box is out of the range c1surf's evaluation
    takes (``mesh.points.geometry_checks.check_coordinate_range``: products of lengths would overflow or underflow)
    and weights out of ``WEIGHT_RANGE`` (``check_net_range``)."""
    arrays = [np.asarray(g)[..., :3].reshape(len(g), -1, 3) for g in patch_set.groups if len(g)]
    arrays += [np.asarray(p.points)[..., :3].reshape(1, -1, 3) for p in patch_set.merged or ()]
    weights = [np.asarray(w).reshape(len(w), -1) for w in patch_set.weights or () if len(w)]
    weights += [np.asarray(p.weights).reshape(1, -1) for p in patch_set.merged or () if p.weights is not None]
    check_net_range(path, arrays, weights)


WEIGHT_RANGE = (1e-50, 1e50, 1e12)  # a weight's smallest and largest value, the largest ratio within a patch


def check_net_range(path, points: list, weights: list = (), what: str = "the surface") -> None:
    """Refuse control points out of c1surf's range (``check_coordinate_range``) and weights that are not finite,
    not in ``WEIGHT_RANGE``, or whose ratio within a patch exceeds it (rational evaluation divides by the smallest
    and multiplies by the largest: beyond these, its products overflow).

    points : list of (P, n, 3) float arrays (P patches of n control points); weights : list of (P, n) float arrays
    """
    boxes = [np.stack([a.min(axis=(0, 1)), a.max(axis=(0, 1))]) for a in points if a.size]
    try:
        if boxes:
            check_coordinate_range(np.concatenate(boxes), what)
    except GeometryError as error:
        raise MeshInputError(str(path), error.message.replace("a vertex has", "a control point has")) from None
    low, high, ratio = WEIGHT_RANGE
    for w in weights:
        if not w.size:
            continue
        smallest, largest = w.min(axis=1), w.max(axis=1)
        if not (np.all(smallest >= low) and np.all(largest <= high)):  # also refuses NaN
            raise MeshInputError(str(path), f"weights must be finite numbers in [{low:.0e}, {high:.0e}], found one of "
                                 f"{_worst(w, low, high):.3g}: re-export the file")
        if np.any(largest > ratio * smallest):
            raise MeshInputError(str(path), f"a patch's weights differ by a factor of {np.max(largest / smallest):.3g}, "
                                 f"beyond {ratio:.0e} where rational evaluation loses every digit: re-export the file")


def _worst(w: np.ndarray, low: float, high: float) -> float:
    """The first weight of ``w`` outside [low, high] (or NaN)."""
    flat = w.ravel()
    bad = ~((flat >= low) & (flat <= high))
    return float(flat[np.argmax(bad)])
