"""The deviation picture: a triangle mesh (the scan) coloured by a per-vertex distance, with a colour bar.

What a CAD user looks at first after a fit: where the surface leaves the scan, and by how much.
One ray per pixel (``raycast.RayCaster``, Embree when available) from a framing camera
(``camera.frame_camera``, the 3/4 ``iso`` view by default); the hit triangle's corner values are
interpolated with the hit's barycentric weights, mapped through a colour map
(``pictures.colormap``) and shaded by a headlight (ambient + (1 - ambient) |n . d|, n the
triangle's normal); the colour bar (``pictures.add_colorbar``) shows the range, as a fraction of
the bounding-box diagonal when one is given. ``io.images.png`` writes the result.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .camera import frame_camera
from .pictures import BACKGROUND, add_colorbar, colormap, rgb8
from .raycast import RayCaster

__all__ = ["deviation_picture", "DeviationStyle", "AMBIENT"]

AMBIENT = 0.45  # the curvature previews' ambient share


@dataclass(frozen=True)
class DeviationStyle:
    """How ``deviation_picture`` draws.

    width, height : int, pixels
    view : a key of ``camera.VIEWS`` ("iso": the 3/4 view)
    value_range : (lo, hi) or None: the colour range in the bar's units; default the values' min and max
    name : colour map ("viridis", "gray")
    legend : draw the colour bar
    label : the bar's title; default "distance / diagonal" (or "distance" without a diagonal)
    """

    width: int = 960
    height: int = 720
    view: str = "iso"
    value_range: tuple | None = None
    name: str = "viridis"
    legend: bool = True
    label: str | None = None


def deviation_picture(points, triangles, values, diagonal: float | None = None, **style) -> np.ndarray:
    """(H, W, 3) uint8 sRGB picture of a triangle mesh coloured by ``values``.

    Parameters
    ----------
    points : (m, 3) float
    triangles : (t, 3) int
    values : (m,) float, per vertex (a distance); NaN vertices are drawn at the range's bottom
    diagonal : float > 0 or None: values and bar labels are divided by it (fractions of the diagonal)
    **style : the fields of ``DeviationStyle`` (size, view, range, colour map, bar)

    Returns
    -------
    (height, width, 3) uint8
    """
    s = DeviationStyle(**style)
    width, height, view, value_range, name, legend, label = (s.width, s.height, s.view, s.value_range, s.name,
                                                             s.legend, s.label)
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    scale = float(diagonal) if diagonal else 1.0
    scaled = np.asarray(values, dtype=np.float64) / scale
    finite = scaled[np.isfinite(scaled)]
    if value_range is None:
        value_range = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    lo, hi = value_range
    camera = frame_camera(points, width, height, view)
    origins, directions = camera.rays()
    triangle, b1, b2, _ = RayCaster(points, triangles).cast(origins, directions)
    hit = triangle >= 0
    corners = triangles[triangle[hit]]
    weights = np.stack([1.0 - b1[hit] - b2[hit], b1[hit], b2[hit]], axis=1)
    value = np.einsum("ij,ij->i", weights, np.nan_to_num(scaled[corners], nan=lo))
    p = points[corners]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    shade = AMBIENT + (1.0 - AMBIENT) * np.abs(np.einsum("ij,ij->i", normal, directions[hit]))
    rgb = np.broadcast_to(np.asarray(BACKGROUND), (width * height, 3)).copy()
    rgb[hit] = colormap(value, lo, hi, name) * shade[:, None]
    picture = rgb8(rgb.reshape(height, width, 3))
    if legend:
        title = label if label is not None else ("distance / diagonal" if diagonal else "distance")
        picture = add_colorbar(picture, lo, hi, name, title)
    return picture
