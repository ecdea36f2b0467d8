"""Per-vertex curvature properties for ``convert --curvature`` (and ``tessellate``)."""
from __future__ import annotations

import numpy as np

from ..evaluation.curvature import tessellation_curvature
from ..evaluation.tessellate import fill_from_neighbours
from ..evaluation.tolerance.curvature import tolerance_curvature
from ..evaluation.tolerance.tessellation import ToleranceTessellation
from ..render.pictures import colormap, curvature_range, rgb8


def curvature_properties(groups, tess, progress=None, weights=None) -> dict:
    """Keyword arguments of ``io.meshes.write.write_triangle_mesh`` adding exact curvature.

    Parameters
    ----------
    groups : list of (p_k, du+1, dv+1, d) float, the tessellated patches (Euclidean, x, y, z first)
    tess : evaluation.tessellate.Tessellation of them, or a ToleranceTessellation (``--tolerance``)
    progress : callable(label, advance, total) or None
    weights : None or a list parallel to ``groups`` of (p_k, du+1, dv+1) float: rational patches (A2a)

    Returns
    -------
    dict with ``vertex_properties`` (kmax, K, H, quality = kmax) and ``vertex_colors``
    (kmax through viridis, from 0 to its 98th percentile); no NaN: where a degenerate patch
    point has no curvature, the mean of its neighbours' (``tessellate.fill_from_neighbours``)
    """
    if isinstance(tess, ToleranceTessellation):
        c = tolerance_curvature(groups, tess, progress, weights)
    else:
        c = tessellation_curvature(groups, tess.grid, tess.points.shape[0], progress, weights=weights)
    # a point without a tangent plane (a zero blend ratio) has no curvature: it takes its neighbours' mean
    defined = np.isfinite(c["kmax"])
    if not defined.all():
        c = {name: fill_from_neighbours(values, defined, tess.triangles) for name, values in c.items()}
    lo, hi = curvature_range(c["kmax"], signed=False)
    colors = rgb8(colormap(c["kmax"], lo, hi, "viridis"))
    props = {"kmax": c["kmax"], "K": c["K"], "H": c["H"], "quality": c["kmax"]}
    return {"vertex_properties": props, "vertex_colors": colors}
