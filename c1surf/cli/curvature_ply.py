"""Per-vertex curvature properties for ``convert --curvature`` (and ``tessellate``)."""
from __future__ import annotations

import numpy as np

from ..evaluation.curvature import tessellation_curvature
from ..render.pictures import colormap, curvature_range


def curvature_properties(groups, tess, progress=None) -> dict:
    """Keyword arguments of ``io.mesh_out.write_triangle_mesh`` adding exact curvature.

    Returns
    -------
    dict with ``vertex_properties`` (kmax, K, H, quality = kmax) and ``vertex_colors``
    (kmax through viridis, from 0 to its 98th percentile)
    """
    c = tessellation_curvature(groups, tess.grid, tess.points.shape[0], progress)
    lo, hi = curvature_range(c["kmax"], signed=False)
    colors = (colormap(c["kmax"], lo, hi, "viridis") * 255 + 0.5).astype(np.uint8)
    props = {"kmax": c["kmax"], "K": c["K"], "H": c["H"], "quality": c["kmax"]}
    return {"vertex_properties": props, "vertex_colors": colors}
