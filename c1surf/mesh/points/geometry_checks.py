"""Geometry the construction cannot take: coordinates out of its floating-point range, meshes spanning no surface.

Plain functions on the vertex positions (no files): ``check_geometry`` raises ``GeometryError``
with the reason and what to do.

- Range: the construction forms cross products of edge vectors and their squared lengths,
  numbers of the mesh's size to the 4th power. A cube 2e80 across overflows there (every normal
  becomes zero, at 1e308 every point NaN), one 2e-100 across underflows to zero normals. Meshes
  whose bounding-box diagonal lies in [MIN_SIZE, MAX_SIZE] (1e-50 .. 1e50: a factor 1e25 inside
  both limits, measured on cube.obj scaled by 10^k: normals nonzero for |k| <= 77) and whose
  coordinates stay below MAX_COORDINATE are converted; others are refused with the power of ten
  that takes them to about unit size.
- Span: a mesh whose vertices (those used by faces) all coincide or all lie on one line has no
  tangent plane anywhere: refused with that reason. Collinearity is measured as the largest
  distance from the line through the two extreme vertices along the widest axis, relative to the
  mesh's size; below ``FLAT_RELATIVE`` (a few hundred units in the last place) the points lie on it.
"""
from __future__ import annotations

import math

import numpy as np

from ...arrays import column_bounds

__all__ = ["GeometryError", "check_geometry", "check_coordinate_range", "check_spans_surface",
           "MIN_SIZE", "MAX_SIZE", "MAX_COORDINATE", "FLAT_RELATIVE"]

MIN_SIZE = 1e-50  # smallest bounding-box diagonal converted
MAX_SIZE = 1e50  # largest bounding-box diagonal converted
MAX_COORDINATE = 1e50  # largest coordinate magnitude converted
FLAT_RELATIVE = 1e-13  # largest distance from a line, relative to the size, of points "on" it
_CHUNK = 1 << 20  # rows at a time for the distance pass: temporaries of some 10 MB
_SAMPLE = 4096  # vertices of the first collinearity test


class GeometryError(ValueError):
    """The vertex positions are not something the construction can use; ``message`` is one line."""

    def __init__(self, message: str):
        self.message = message
        super().__init__(message)


def check_geometry(points: np.ndarray, used: np.ndarray | None = None) -> None:
    """Refuse positions out of the construction's range or spanning no surface (``GeometryError``).

    Parameters
    ----------
    points : (V, >=3) float, vertex positions (further columns, e.g. weights, are ignored)
    used : (k,) int or None, the vertices to check (those faces use; repeats allowed); None: all. When
        every vertex is used (the usual case) nothing is copied: a few passes over the coordinates.
    """
    xyz = np.asarray(points, dtype=np.float64)[:, :3]
    if used is not None:
        kept = np.zeros(xyz.shape[0], dtype=bool)
        kept[np.asarray(used, dtype=np.int64).ravel()] = True
        if not kept.all():
            xyz = xyz[kept]
    if xyz.shape[0] == 0:
        return
    bounds = column_bounds(xyz)
    check_coordinate_range(xyz, bounds=bounds)
    check_spans_surface(xyz, bounds=bounds)


def check_coordinate_range(xyz: np.ndarray, what: str = "the mesh", bounds=None) -> None:
    """Refuse non-finite coordinates, coordinates beyond ``MAX_COORDINATE`` and bounding boxes whose
    diagonal lies outside [MIN_SIZE, MAX_SIZE] (unless it is 0: ``check_spans_surface`` says why that fails).

    xyz : (V, 3) float, V >= 1 (the corners of a bounding box will do)
    what : how the message names the thing measured ("the mesh", "the surface")
    bounds : (low (3,), high (3,)) of ``xyz`` when known (``arrays.column_bounds``)
    """
    with np.errstate(over="ignore", invalid="ignore"):
        total = xyz.sum()  # finite: every entry is (a sum of finite numbers this size cannot overflow to nan)
    if not np.isfinite(total) and not np.isfinite(xyz).all():
        raise GeometryError("a vertex has a NaN or infinite coordinate")
    low, high = column_bounds(xyz) if bounds is None else bounds
    largest = float(np.max(np.maximum(np.abs(low), np.abs(high))))
    if largest > MAX_COORDINATE:
        raise GeometryError(f"coordinates reach {largest:.3g}, beyond {MAX_COORDINATE:.0e} where the construction's "
                            f"products of lengths overflow: scale {what} by {_unit_scale(largest)} first (or by any "
                            "factor that brings it within that)")
    scale = np.abs(high - low).max()  # the diagonal, by its largest side (no overflow on the way)
    size = 0.0 if scale == 0 else float(scale * np.sqrt(np.sum(((high - low) / scale) ** 2)))
    if size > MAX_SIZE:
        raise GeometryError(f"{what} is {size:.3g} across (bounding-box diagonal), beyond {MAX_SIZE:.0e} where the "
                            f"construction's products of lengths overflow: scale it by {_unit_scale(size)} first "
                            "(to about unit size)")
    if 0 < size < MIN_SIZE:
        raise GeometryError(f"{what} is only {size:.3g} across (bounding-box diagonal), below {MIN_SIZE:.0e} where the "
                            f"construction's products of lengths underflow to zero normals: scale it by "
                            f"{_unit_scale(size)} first (to about unit size)")


def check_spans_surface(xyz: np.ndarray, bounds=None) -> None:
    """Refuse vertices that all coincide or all lie on one line (up to rounding: ``FLAT_RELATIVE``).

    The line is the one through an extreme vertex along the widest axis and the vertex farthest from it.
    An evenly spaced sample of some thousand vertices decides first: one vertex off the line proves a surface;
    only a sample on the line makes every vertex count.

    xyz : (V, 3) finite float, V >= 1; bounds : (low (3,), high (3,)) of ``xyz`` when known
    """
    low, high = column_bounds(xyz) if bounds is None else bounds
    magnitude = float(np.max(np.maximum(np.abs(low), np.abs(high))))
    extent = float(np.max(high - low))
    if extent <= 4 * np.finfo(np.float64).eps * magnitude:  # 0, or a few units in the last place of the positions
        raise GeometryError(f"all {xyz.shape[0]} vertices lie at one point ({_point(xyz[0])}): the mesh spans no "
                            "surface")
    axis = int(np.argmax(high - low))
    start = xyz[int(np.argmin(xyz[:, axis]))]  # an extreme vertex along the widest axis
    end = xyz[int(np.argmax(xyz[:, axis]))]  # the other: at least extent away, the line through both well defined
    direction = (end - start) / extent
    direction /= np.linalg.norm(direction)
    allowed = FLAT_RELATIVE + 4 * np.finfo(np.float64).eps * magnitude / extent
    sample = xyz[:: max(1, xyz.shape[0] // _SAMPLE)]
    if _line_distance(sample, start, direction, extent) > allowed:
        return
    if _line_distance(xyz, start, direction, extent) > allowed:
        return
    raise GeometryError(f"all {xyz.shape[0]} vertices lie on one line (through {_point(start)} and {_point(end)}): "
                        "the mesh spans no surface")


def _line_distance(xyz: np.ndarray, start: np.ndarray, direction: np.ndarray, extent: float) -> float:
    """The largest distance of ``xyz`` from the line ``start + t direction``, over ``extent`` (chunk by chunk)."""
    largest = 0.0
    for a in range(0, xyz.shape[0], _CHUNK):
        offsets = (xyz[a:a + _CHUNK] - start) / extent
        largest = max(largest, float(np.linalg.norm(np.cross(offsets, direction), axis=1).max()))
    return largest


def _unit_scale(value: float) -> str:
    """The power of ten taking ``value`` to about 1 (``1e-308`` for 2e308, ``1e300`` for 3e-300)."""
    return f"1e{-round(math.log10(value))}"


def _point(p: np.ndarray) -> str:
    return " ".join(f"{float(x):.6g}" for x in p)
