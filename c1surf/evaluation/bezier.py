"""Tensor-product Bezier patches: Bernstein bases, evaluation, derivatives.

A patch of degree (du, dv) is an array ``P`` of shape (du+1, dv+1, d) and means
``x(u, v) = sum_ij P[i, j] B_i^du(u) B_j^dv(v)`` on [0, 1]^2 (the first index goes
with u). Every evaluator of c1surf goes through this module, in one of two layouts:

- on a grid of parameters (tessellation, side frames, ray-casting meshes): the
  bases are matrices (rows = parameter samples, columns = basis functions,
  ``bernstein_basis``) contracted with the control points (``evaluate_grid``);
- at scattered samples, one (patch, u, v) each (curvature, Newton steps): the
  bases are lists of per-sample arrays (``bernstein_columns``) multiplied into
  the control points laid out coordinate-major (``patch_columns``,
  ``sample_derivatives``).

Rational patches (A2a) are evaluated in homogeneous coordinates with these and
turned Euclidean by ``evaluation.rational``.
"""
from __future__ import annotations

import math

import numpy as np


def binomials(degree: int) -> np.ndarray:
    """(degree + 1,) float: C(degree, i), i = 0..degree, as ``scipy.special.comb(degree, i)`` gives them.

    Exact integers up to degree 30, where scipy's floating values are those integers (checked
    for every degree up to 30), so c1surf need not import scipy.special (50 ms); beyond, scipy's own.
    """
    if degree <= 30:
        return np.array([float(math.comb(degree, i)) for i in range(degree + 1)])
    from scipy.special import comb

    return comb(degree, np.arange(degree + 1))


def bernstein_basis(degree: int, t: np.ndarray, derivative: int = 0) -> np.ndarray:
    """Bernstein basis (or its derivative) sampled at ``t``, as a matrix.

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
        basis = binomials(degree) * np.power.outer(t, i) * np.power.outer(1.0 - t, degree - i)
    return basis


def bernstein_columns(degree: int, t: np.ndarray, derivative: int = 0) -> list:
    """The basis of ``bernstein_basis`` as ``degree + 1`` arrays shaped like ``t``.

    For scattered samples: each basis function is one array over the samples,
    built by the de Casteljau recursion (the same values as ``bernstein_basis``
    to rounding, several times faster for low degrees and many samples).

    Parameters
    ----------
    degree : int
    t : (m,) float
    derivative : int, 0, 1 or 2

    Returns
    -------
    list of degree + 1 (m,) float arrays
    """
    if derivative > degree:
        return [np.zeros_like(t) for _ in range(degree + 1)]
    s = 1.0 - t
    levels = [[np.ones_like(t)]]
    for k in range(1, degree - derivative + 1):
        prev = levels[-1]
        levels.append([s * prev[0]] + [s * prev[i] + t * prev[i - 1] for i in range(1, k)] + [t * prev[k - 1]])
    low = levels[degree - derivative]
    # d^r/dt^r B_i^n = n!/(n-r)! sum_k (-1)^(r-k) C(r, k) B_{i-k}^{n-r}
    factor = float(np.prod(np.arange(degree - derivative + 1, degree + 1)))
    signs = [(-1) ** (derivative - k) * float(math.comb(derivative, k)) for k in range(derivative + 1)]
    out = []
    for i in range(degree + 1):
        acc = None
        for k, sign in enumerate(signs):
            if 0 <= i - k <= degree - derivative:
                term = sign * low[i - k]
                acc = term if acc is None else acc + term
        out.append(factor * acc if acc is not None else np.zeros_like(t))
    return out


def tensor_basis(bu: np.ndarray, bv: np.ndarray) -> np.ndarray:
    """Tensor-product basis matrix: samples (a, b) by control points (i, j).

    Parameters
    ----------
    bu : (mu, du+1) float, a ``bernstein_basis`` in u; bv : (mv, dv+1) float, one in v

    Returns
    -------
    (mu mv, (du+1)(dv+1)) float, entry [a mv + b, i (dv+1) + j] = bu[a, i] bv[b, j]
    """
    return np.einsum("ai,bj->abij", bu, bv).reshape(bu.shape[0] * bv.shape[0], bu.shape[1] * bv.shape[1])


def evaluate_grid(points: np.ndarray, bu: np.ndarray, bv: np.ndarray) -> np.ndarray:
    """Many patches of one degree on the tensor grid of two sampled bases.

    Two batched matrix products (v first, then u), several times faster than a
    three-operand ``einsum``.

    Parameters
    ----------
    points : (p, du+1, dv+1, d) float
    bu : (mu, du+1) float, ``bernstein_basis`` (or a derivative) in u
    bv : (mv, dv+1) float, the same in v

    Returns
    -------
    (p, mu, mv, d) float
    """
    p, rows, _, d = points.shape
    mu, mv = bu.shape[0], bv.shape[0]
    along_v = np.matmul(bv, points)  # (p, du+1, mv, d)
    return np.matmul(bu, along_v.reshape(p, rows, mv * d)).reshape(p, mu, mv, d)


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
    return evaluate_grid(points, bu, bv)


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


def patch_columns(group: np.ndarray) -> np.ndarray:
    """Control points laid out for ``sample_derivatives``: one contiguous row per (i, j, coordinate).

    Parameters
    ----------
    group : (p, du+1, dv+1, d) float

    Returns
    -------
    (du+1, dv+1, d, p) float, a contiguous copy
    """
    return np.ascontiguousarray(np.asarray(group, dtype=np.float64).transpose(1, 2, 3, 0))


def sample_derivatives(columns: np.ndarray, index, u, v, orders) -> dict:
    """Partial derivatives of polynomial patches at one sample (patch, u, v) each.

    Control point by control point on (d, m) arrays: a few dozen contiguous
    vector operations, several times faster than an ``einsum`` over gathered
    (m, du+1, dv+1, d) blocks.

    Parameters
    ----------
    columns : (du+1, dv+1, d, p) float, ``patch_columns`` of the patches
    index : (m,) int, the patch of each sample, or None when p == m (one patch per sample)
    u, v : (m,) float
    orders : iterable of (a, b): which derivatives d^(a+b) / du^a dv^b

    Returns
    -------
    dict (a, b) -> (m, d) float (transposed views of (d, m) arrays)
    """
    u = np.atleast_1d(np.asarray(u, dtype=np.float64))
    v = np.atleast_1d(np.asarray(v, dtype=np.float64))
    du, dv = columns.shape[0] - 1, columns.shape[1] - 1
    orders = tuple(orders)
    bu = {a: bernstein_columns(du, u, a) for a in {o[0] for o in orders}}
    bv = {b: bernstein_columns(dv, v, b) for b in {o[1] for o in orders}}
    if index is None:
        cps = [[columns[i, j] for j in range(dv + 1)] for i in range(du + 1)]
    else:
        index = np.asarray(index)
        cps = [[np.take(columns[i, j], index, axis=1) for j in range(dv + 1)] for i in range(du + 1)]
    out = {}
    for b in sorted(bv):
        rows = [sum(bv[b][j] * cps[i][j] for j in range(dv + 1)) for i in range(du + 1)]
        for a, bb in orders:
            if bb == b:
                out[(a, b)] = sum(bu[a][i] * rows[i] for i in range(du + 1)).T
    return out


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of (..., 3) float arrays, the same arithmetic (a1 b2 - a2 b1, ...: the same bits) without its
    promotions and axis moves (about 3x faster on millions of rows)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    np.multiply(a[..., 1], b[..., 2], out=out[..., 0])
    out[..., 0] -= a[..., 2] * b[..., 1]
    np.multiply(a[..., 2], b[..., 0], out=out[..., 1])
    out[..., 1] -= a[..., 0] * b[..., 2]
    np.multiply(a[..., 0], b[..., 1], out=out[..., 2])
    out[..., 2] -= a[..., 1] * b[..., 0]
    return out


def unit_normals(du_points: np.ndarray, dv_points: np.ndarray) -> np.ndarray:
    """Unit normals ``(x_u x x_v) / |x_u x x_v|`` from first derivatives.

    Parameters
    ----------
    du_points, dv_points : (..., 3) float

    Returns
    -------
    (..., 3) float; NaN where the surface is singular (zero cross product).
    """
    n = cross3(du_points, dv_points)
    length = np.sqrt(np.einsum("...i,...i->...", n, n))  # faster than np.linalg.norm on (..., 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        n /= length[..., None]  # 0 / 0: NaN
    return n


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
