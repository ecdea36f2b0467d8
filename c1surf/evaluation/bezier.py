"""Tensor-product Bezier patches: Bernstein bases as matrices, evaluation, derivatives.

A patch of degree (du, dv) is an array ``P`` of shape (du+1, dv+1, d) and means
``x(u, v) = sum_ij P[i, j] B_i^du(u) B_j^dv(v)`` on [0, 1]^2 (the first index goes
with u). Bases are matrices (rows = parameter samples, columns = basis functions)
contracted with the control points, so a whole group of patches of one degree is
evaluated with one ``einsum``.
"""
from __future__ import annotations

import numpy as np
from scipy.special import comb


def bernstein_basis(degree: int, t: np.ndarray, derivative: int = 0) -> np.ndarray:
    """Bernstein basis (or its derivative) sampled at ``t``.

    Parameters
    ----------
    degree : int
    t : (m,) float
    derivative : int
        0, 1 or 2: which derivative of the basis functions.

    Returns
    -------
    (m, degree + 1) float
    """
    t = np.asarray(t, dtype=np.float64)
    if derivative > degree:
        return np.zeros((t.size, degree + 1))
    if derivative > 0:
        # d/dt B_i^d = d (B_{i-1}^{d-1} - B_i^{d-1}), applied recursively.
        lower = bernstein_basis(degree - 1, t, derivative - 1)
        out = np.zeros((t.size, degree + 1))
        out[:, 1:] += lower
        out[:, :-1] -= lower
        return degree * out
    i = np.arange(degree + 1)
    with np.errstate(invalid="ignore"):
        # 0**0 = 1 is what the basis needs at the end points.
        basis = comb(degree, i) * np.power.outer(t, i) * np.power.outer(1.0 - t, degree - i)
    return basis


def evaluate_patches(points: np.ndarray, u: np.ndarray, v: np.ndarray, du: int = 0, dv: int = 0) -> np.ndarray:
    """Evaluate many patches of one degree on a tensor grid of parameters.

    Parameters
    ----------
    points : (p, du+1, dv+1, d) float
    u : (mu,) float
    v : (mv,) float
    du, dv : int
        derivative orders in u and v.

    Returns
    -------
    (p, mu, mv, d) float
    """
    bu = bernstein_basis(points.shape[1] - 1, u, du)
    bv = bernstein_basis(points.shape[2] - 1, v, dv)
    return np.einsum("ai,bj,pijd->pabd", bu, bv, points, optimize=True)


def evaluate_patches_at(points: np.ndarray, u: np.ndarray, v: np.ndarray, du: int = 0, dv: int = 0) -> np.ndarray:
    """Evaluate patch ``k`` at its own parameter ``(u[k], v[k])``.

    Parameters
    ----------
    points : (p, du+1, dv+1, d) float
    u, v : (p,) float

    Returns
    -------
    (p, d) float
    """
    bu = bernstein_basis(points.shape[1] - 1, np.atleast_1d(u), du)
    bv = bernstein_basis(points.shape[2] - 1, np.atleast_1d(v), dv)
    return np.einsum("pi,pj,pijd->pd", bu, bv, points, optimize=True)


def unit_normals(du_points: np.ndarray, dv_points: np.ndarray) -> np.ndarray:
    """Unit normals ``(x_u x x_v) / |x_u x x_v|`` from first derivatives.

    Parameters
    ----------
    du_points, dv_points : (..., 3) float

    Returns
    -------
    (..., 3) float; NaN where the surface is singular (zero cross product).
    """
    n = np.cross(du_points, dv_points)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(length > 0, n / length, np.nan)


def raise_degree(points: np.ndarray, du: int, dv: int) -> np.ndarray:
    """Degree-elevate patches to (du, dv) without changing the surface.

    Parameters
    ----------
    points : (p, m+1, n+1, d) float, with m <= du and n <= dv

    Returns
    -------
    (p, du+1, dv+1, d) float
    """
    out = points
    for axis, target in ((1, du), (2, dv)):
        while out.shape[axis] - 1 < target:
            m = out.shape[axis] - 1
            i = np.arange(1, m + 1)
            first = np.take(out, [0], axis=axis)
            last = np.take(out, [m], axis=axis)
            lower = np.take(out, i - 1, axis=axis)
            upper = np.take(out, i, axis=axis)
            shape = [1] * out.ndim
            shape[axis] = m
            w = (i / (m + 1)).reshape(shape)
            middle = w * lower + (1 - w) * upper
            out = np.concatenate([first, middle, last], axis=axis)
    return out
