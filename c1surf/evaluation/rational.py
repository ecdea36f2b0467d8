"""Extension A2a: rational patches, the one place where homogeneous points become Euclidean.

The paper: treat the control points as vectors (w x, w) in R^4 and run the
same masks; the fourth coordinate is an additional shape parameter and the
patches x = (sum w P B) / (sum w B) join G1 because the masks preserve the
continuity conditions of the homogeneous surfaces. ``Surface(weights=...)``
does exactly that. Patches travel as Euclidean control points with a parallel
list of weights (``PatchSet.weights``), never as a fourth column to guess
from; the evaluators make homogeneous points with ``homogeneous``, evaluate
them as polynomial patches (``evaluation.bezier``) and come back with
``euclidean_derivatives`` (the quotient rule).

Quotient rule: x = H / w gives x_u = (H_u - w_u x) / w and, differentiating
again, x_uu = (H_uu - 2 w_u x_u - w_uu x) / w,
x_uv = (H_uv - w_u x_v - w_v x_u - w_uv x) / w.
"""
from __future__ import annotations

import numpy as np

from .bezier import bernstein_basis, evaluate_grid, unit_normals


def homogeneous(points: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Homogeneous points (w x, w).

    Parameters
    ----------
    points : (..., d) float
    weights : (...) float > 0

    Returns
    -------
    (..., d + 1) float
    """
    points = np.asarray(points, dtype=np.float64)
    weights = np.asarray(weights, dtype=np.float64)
    return np.concatenate([points * weights[..., None], weights[..., None]], axis=-1)


def dehomogenize(points: np.ndarray):
    """Euclidean points and weights of homogeneous points (w x, w).

    Parameters
    ----------
    points : (..., d + 1) float

    Returns
    -------
    x : (..., d) float; w : (...) float
    """
    w = points[..., -1]
    return points[..., :-1] / w[..., None], w


def euclidean_derivatives(h: dict) -> dict:
    """Derivatives of x = H / w from those of the homogeneous H = (w x, w) (the quotient rule).

    Parameters
    ----------
    h : dict (a, b) -> (..., d + 1) float, d^(a+b) H / du^a dv^b; holds (0, 0) and any of
        (1, 0), (0, 1), and (with both of those) (2, 0), (1, 1), (0, 2)

    Returns
    -------
    dict (a, b) -> (..., d) float, the same orders of x
    """
    p = {o: a[..., :-1] for o, a in h.items()}
    w = {o: a[..., -1:] for o, a in h.items()}
    w0 = w[(0, 0)]
    x = {(0, 0): p[(0, 0)] / w0}
    for order in ((1, 0), (0, 1)):
        if order in h:
            x[order] = (p[order] - w[order] * x[(0, 0)]) / w0
    if (2, 0) in h:
        x[(2, 0)] = (p[(2, 0)] - 2 * w[(1, 0)] * x[(1, 0)] - w[(2, 0)] * x[(0, 0)]) / w0
        x[(1, 1)] = (p[(1, 1)] - w[(1, 0)] * x[(0, 1)] - w[(0, 1)] * x[(1, 0)] - w[(1, 1)] * x[(0, 0)]) / w0
        x[(0, 2)] = (p[(0, 2)] - 2 * w[(0, 1)] * x[(0, 1)] - w[(0, 2)] * x[(0, 0)]) / w0
    return x


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
    du, dv = h.shape[1] - 1, h.shape[2] - 1
    bu, bv = bernstein_basis(du, u), bernstein_basis(dv, v)
    x = euclidean_derivatives({(0, 0): evaluate_grid(h, bu, bv),
                               (1, 0): evaluate_grid(h, bernstein_basis(du, u, 1), bv),
                               (0, 1): evaluate_grid(h, bu, bernstein_basis(dv, v, 1))})
    return x[(0, 0)], unit_normals(x[(1, 0)][..., :3], x[(0, 1)][..., :3])
