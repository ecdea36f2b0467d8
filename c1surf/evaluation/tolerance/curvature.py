"""Per-vertex exact curvature of a tessellation to a tolerance (``convert --tolerance --curvature``).

As ``evaluation.curvature.tessellation_curvature`` does for the uniform grid:
every sample of every patch is evaluated (a vertex on a patch side or corner
once per patch that has it, at that patch's parameters) and a vertex gets the
mean of its patches' values (a G1 surface has continuous normals, not
continuous curvature, across patch sides). The samples come template by
template (``TolerancePlan.blocks``): all patches of a template share their local
parameters.
"""
from __future__ import annotations

import numpy as np

from ..curvature import CURVATURE_NAMES, PatchSampler

_CHUNK = 1 << 18  # samples evaluated at once


def tolerance_curvature(groups, tess, progress=None, weights=None) -> dict:
    """dict name -> (V,) float for kmax, K, H, k1, k2 at the vertices of a ``ToleranceTessellation``.

    Parameters
    ----------
    groups : list of (p_k, du+1, dv+1, d) float, patches in global order (x, y, z first)
    tess : ToleranceTessellation of them
    progress : callable(label, advance, total) or None, advanced by patches
    weights : None or a list parallel to ``groups`` (rational patches, A2a)

    NaN where no patch has a tangent plane at the vertex (as the uniform version).
    """
    n_vertices = tess.points.shape[0]
    sums = {name: np.zeros(n_vertices) for name in CURVATURE_NAMES}
    counts = np.zeros(n_vertices)
    sampler = PatchSampler(groups, weights)
    for tpl, patches, ids in tess.plan.blocks():
        samples = tpl.uv.shape[0]
        patch, vertex = np.repeat(patches, samples), ids.ravel()
        u, v = np.tile(tpl.uv[:, 0], patches.size), np.tile(tpl.uv[:, 1], patches.size)
        for g, which in sampler.runs(patch, _CHUNK):
            c = sampler.curvature(g, patch[which] - sampler.offsets[g], u[which], v[which])
            ok = np.isfinite(c.kmax)
            at = vertex[which][ok]
            counts += np.bincount(at, minlength=n_vertices)
            for name in CURVATURE_NAMES:
                sums[name] += np.bincount(at, weights=c[name][ok], minlength=n_vertices)
        if progress is not None:
            progress("evaluating curvature", patches.size, tess.plan.n_patches)
    with np.errstate(invalid="ignore", divide="ignore"):
        return {name: sums[name] / counts for name in CURVATURE_NAMES}


__all__ = ["tolerance_curvature"]
