"""Extension A2a: rational patches from homogeneous control points.

The paper: treat the control points as vectors (w x, w) in R^4 and run the
same masks; the fourth coordinate is an additional shape parameter and the
patches x = (sum w P B) / (sum w B) join G1 because the masks preserve the
continuity conditions of the homogeneous surfaces. ``Surface(weights=...)``
does exactly that. This module holds what the rational surface needs
afterwards: homogeneous coordinates, evaluation and normals by the quotient
rule, and the welded tessellation.

Normals: x = H / w gives x_u = (H_u - x w_u) / w, so
x_u x x_v = ((H_u - x w_u) x (H_v - x w_v)) / w^2.
"""
from __future__ import annotations

import numpy as np

from .bezier import bernstein_basis, unit_normals


def homogeneous(points: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(..., d) points and (...) weights -> (..., d + 1) homogeneous points (w x, w)."""
    points = np.asarray(points, dtype=np.float64)
    weights = np.asarray(weights, dtype=np.float64)
    return np.concatenate([points * weights[..., None], weights[..., None]], axis=-1)


def evaluate_rational(points: np.ndarray, weights: np.ndarray, u: np.ndarray, v: np.ndarray):
    """Points and unit normals of rational patches on a tensor grid.

    Parameters
    ----------
    points : (p, du+1, dv+1, d) float (first 3 columns positions)
    weights : (p, du+1, dv+1) float > 0
    u, v : (mu,), (mv,) float

    Returns
    -------
    x : (p, mu, mv, d) float; normals : (p, mu, mv, 3) float
    """
    h = homogeneous(points, weights)
    bu, bv = bernstein_basis(h.shape[1] - 1, u), bernstein_basis(h.shape[2] - 1, v)
    dbu, dbv = bernstein_basis(h.shape[1] - 1, u, 1), bernstein_basis(h.shape[2] - 1, v, 1)
    H = np.einsum("ai,bj,pijd->pabd", bu, bv, h, optimize=True)
    Hu = np.einsum("ai,bj,pijd->pabd", dbu, bv, h, optimize=True)
    Hv = np.einsum("ai,bj,pijd->pabd", bu, dbv, h, optimize=True)
    w = H[..., -1:]
    x = H[..., :-1] / w
    xu = Hu[..., :3] - x[..., :3] * Hu[..., -1:]
    xv = Hv[..., :3] - x[..., :3] * Hv[..., -1:]
    return x, unit_normals(xu, xv)


def tessellate_rational(tessellate_patches, patch_groups, weights, adjacency, resolution: int):
    """Welded tessellation of rational patches (called by ``tessellate.tessellate_patches``).

    The homogeneous patches are tessellated as polynomial ones (the welding
    is the same), then points are divided by w and normals recomputed by the
    quotient rule.
    """
    from .tessellate import Tessellation

    groups = [homogeneous(g, w) for g, w in zip(patch_groups, weights)]
    tess = tessellate_patches(groups, adjacency, resolution)
    points = tess.points[:, :-1] / tess.points[:, -1:]
    normals = np.empty((points.shape[0], 3))
    t = np.linspace(0.0, 1.0, resolution)
    start = 0
    for g, w in zip(patch_groups, weights):
        count = g.shape[0]
        if count == 0:
            continue
        _, n = evaluate_rational(g, w, t, t)
        normals[tess.grid[start : start + count]] = n
        start += count
    return Tessellation(points, normals, tess.triangles, tess.triangle_patch, tess.grid)
