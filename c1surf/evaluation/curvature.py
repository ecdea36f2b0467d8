"""Exact curvature of (rational) tensor-product Bezier patches.

First and second derivatives come from the Bernstein bases of ``bezier``; the
fundamental forms give the principal curvatures. Everything is vectorized over
arrays of samples ``(patch, u, v)``.

Sign convention: the unit normal is ``n = x_u x x_v / |x_u x x_v|`` (outward for
c1surf surfaces) and a normal curvature is positive where the surface bends
away from ``n``: a sphere of radius r with outward normals has
``k1 = k2 = H = 1/r`` and ``K = 1/r^2``. ``k1 >= k2``; ``kmax = max(|k1|, |k2|)``.

Rational patches are given in homogeneous form: ``d == 4`` means the control
points are ``(x w, y w, z w, w)`` and the surface is the first three columns
divided by the fourth.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scipy.special import comb


# Derivative orders (du, dv) evaluated by ``patch_derivatives``, in output order.
_ORDERS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))


@dataclass(frozen=True)
class Curvature:
    """Curvature quantities at many surface samples; every field is (m,) float
    except ``point`` and ``normal`` (m, 3). NaN where the surface is singular
    (``x_u x x_v = 0``)."""

    k1: np.ndarray
    k2: np.ndarray
    K: np.ndarray
    H: np.ndarray
    kmax: np.ndarray
    point: np.ndarray
    normal: np.ndarray

    def __getitem__(self, name: str) -> np.ndarray:
        return getattr(self, name)


def bernstein_columns(degree: int, t: np.ndarray, derivative: int) -> list:
    """The ``derivative``-th derivative of the degree-``degree`` Bernstein basis at ``t``,
    as a list of degree + 1 arrays shaped like ``t`` (de Casteljau recursion; same values
    as ``bezier.bernstein_basis``, several times faster for low degrees)."""
    s = 1.0 - t
    levels = [[np.ones_like(t)]]
    for k in range(1, degree - derivative + 1):
        prev = levels[-1]
        levels.append([s * prev[0]] + [s * prev[i] + t * prev[i - 1] for i in range(1, k)] + [t * prev[k - 1]])
    if derivative > degree:
        return [np.zeros_like(t) for _ in range(degree + 1)]
    low = levels[degree - derivative]
    # d^r/dt^r B_i^n = n!/(n-r)! sum_k (-1)^(r-k) C(r, k) B_{i-k}^{n-r}
    factor = float(np.prod(np.arange(degree - derivative + 1, degree + 1)))
    signs = [(-1) ** (derivative - k) * float(comb(derivative, k, exact=True)) for k in range(derivative + 1)]
    out = []
    for i in range(degree + 1):
        acc = None
        for k, sign in enumerate(signs):
            if 0 <= i - k <= degree - derivative:
                term = sign * low[i - k]
                acc = term if acc is None else acc + term
        out.append(factor * acc if acc is not None else np.zeros_like(t))
    return out


def patch_columns(group: np.ndarray) -> np.ndarray:
    """(du+1, dv+1, d, p) contiguous copy of a (p, du+1, dv+1, d) group: the layout
    ``polynomial_derivatives`` gathers from (pass it as ``columns`` to reuse it)."""
    return np.ascontiguousarray(np.asarray(group, dtype=np.float64).transpose(1, 2, 3, 0))


def polynomial_derivatives(group: np.ndarray, index, u, v, orders=_ORDERS, columns=None) -> dict:
    """Partial derivatives of the (homogeneous) polynomial patches at one sample each.

    Parameters
    ----------
    group : (p, du+1, dv+1, d) float, patches of one degree
    index : (m,) int into ``group`` (the patch of each sample), or None when
        ``group`` already holds one patch per sample (p == m)
    u, v : (m,) float
    orders : iterable of (a, b): which derivatives d^(a+b) / du^a dv^b
    columns : ``patch_columns(group)`` if already computed, else None

    Returns
    -------
    dict (a, b) -> (m, d) float (transposed views of (d, m) arrays)
    """
    if columns is None:
        columns = patch_columns(group)
    u = np.atleast_1d(np.asarray(u, dtype=np.float64))
    v = np.atleast_1d(np.asarray(v, dtype=np.float64))
    du, dv = columns.shape[0] - 1, columns.shape[1] - 1
    orders = tuple(orders)
    bu = {a: bernstein_columns(du, u, a) for a in {o[0] for o in orders}}
    bv = {b: bernstein_columns(dv, v, b) for b in {o[1] for o in orders}}
    # Control point by control point on (d, m) arrays: a few dozen contiguous vector
    # operations, several times faster than einsum over gathered (m, du+1, dv+1, d) blocks.
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


def _euclidean(d: dict, rational: bool):
    """x and its derivatives up to the orders present in ``d`` (quotient rule for x = P / w)."""
    if not rational:
        return {o: a[:, :3] for o, a in d.items()}
    P = {o: a[:, :3] for o, a in d.items()}
    w = {o: a[:, 3:4] for o, a in d.items()}
    w0 = w[(0, 0)]
    x = {(0, 0): P[(0, 0)] / w0}
    x[(1, 0)] = (P[(1, 0)] - w[(1, 0)] * x[(0, 0)]) / w0
    x[(0, 1)] = (P[(0, 1)] - w[(0, 1)] * x[(0, 0)]) / w0
    if (2, 0) in d:
        x[(2, 0)] = (P[(2, 0)] - 2 * w[(1, 0)] * x[(1, 0)] - w[(2, 0)] * x[(0, 0)]) / w0
        x[(1, 1)] = (P[(1, 1)] - w[(1, 0)] * x[(0, 1)] - w[(0, 1)] * x[(1, 0)] - w[(1, 1)] * x[(0, 0)]) / w0
        x[(0, 2)] = (P[(0, 2)] - 2 * w[(0, 1)] * x[(0, 1)] - w[(0, 2)] * x[(0, 0)]) / w0
    return x


def patch_derivatives(points: np.ndarray, u, v, rational: bool | None = None, index=None, columns=None):
    """Position and first and second derivatives of the surface at one sample each.

    Parameters
    ----------
    points : (m, du+1, dv+1, d) float, one patch per sample (d = 3, or 4 = homogeneous);
        or, with ``index``, a group of patches sampled as ``points[index[k]]``
    u, v : (m,) float
    rational : bool or None, default ``d == 4``
    index : (m,) int or None
    columns : ``patch_columns(points)`` to reuse, or None

    Returns
    -------
    x, x_u, x_v, x_uu, x_uv, x_vv : each (m, 3) float, of the Euclidean surface
    """
    if rational is None:
        rational = np.shape(points)[-1] == 4
    x = _euclidean(polynomial_derivatives(points, index, u, v, _ORDERS, columns), rational)
    return tuple(x[o] for o in _ORDERS)


def patch_tangents(points: np.ndarray, u, v, rational: bool | None = None, index=None, columns=None):
    """Position and first derivatives (arguments as ``patch_derivatives``).

    Returns
    -------
    x, x_u, x_v : each (m, 3) float
    """
    if rational is None:
        rational = np.shape(points)[-1] == 4
    x = _euclidean(polynomial_derivatives(points, index, u, v, _ORDERS[:3], columns), rational)
    return x[(0, 0)], x[(1, 0)], x[(0, 1)]


def curvature_from_derivatives(x, xu, xv, xuu, xuv, xvv) -> Curvature:
    """Principal, Gaussian, mean and largest absolute curvature from derivatives.

    Parameters
    ----------
    x, xu, xv, xuu, xuv, xvv : (m, 3) float

    Returns
    -------
    Curvature
    """
    cross = np.cross(xu, xv)
    area2 = np.einsum("md,md->m", cross, cross)  # E G - F^2
    with np.errstate(invalid="ignore", divide="ignore"):
        n = cross / np.sqrt(area2)[:, None]
        # Second fundamental form against -n, so convex (outward n) is positive.
        L = -np.einsum("md,md->m", xuu, n)
        M = -np.einsum("md,md->m", xuv, n)
        N = -np.einsum("md,md->m", xvv, n)
        # Shape operator in the orthonormal frame e1 = x_u / |x_u|, e2 = n x e1, where
        # x_u = a e1 and x_v = b e1 + c e2: S = J^-T II J^-1 with J = [[a, b], [0, c]].
        # Its entries give H and (k1 - k2) / 2 without the cancellation of sqrt(H^2 - K)
        # near umbilics.
        a = np.sqrt(np.einsum("md,md->m", xu, xu))
        b = np.einsum("md,md->m", xv, xu) / a
        c = np.sqrt(area2) / a
        s11 = L / (a * a)
        s12 = (M - L * b / a) / (a * c)
        s22 = (N - 2 * M * b / a + L * (b / a) ** 2) / (c * c)
        H = 0.5 * (s11 + s22)
        K = s11 * s22 - s12 * s12
        root = np.hypot(0.5 * (s11 - s22), s12)
        k1 = H + root
        k2 = H - root
        kmax = np.abs(H) + root
    singular = ~(area2 > 0)
    if singular.any():
        for a in (K, H, k1, k2, kmax):
            a[singular] = np.nan
    return Curvature(k1=k1, k2=k2, K=K, H=H, kmax=kmax, point=x, normal=n)


def patch_curvature(points: np.ndarray, u, v, rational: bool | None = None, index=None) -> Curvature:
    """Curvature at one sample each (arguments as ``patch_derivatives``)."""
    return curvature_from_derivatives(*patch_derivatives(points, u, v, rational, index))


def surface_curvature(groups, patch, u, v, chunk: int = 1 << 18, progress=None) -> Curvature:
    """Curvature at samples given by global patch index and parameters.

    Parameters
    ----------
    groups : list of (p_k, d_k+1, d_k+1, dim) float, patch groups by degree; the global
        patch index runs through them in order (biquadratic first, then bicubic)
    patch : (m,) int, global patch index of each sample
    u, v : (m,) float
    chunk : int, samples evaluated at once (bounds memory)
    progress : callable(n) or None, called with the number of samples done per chunk

    Returns
    -------
    Curvature with (m,) fields
    """
    patch = np.asarray(patch, dtype=np.int64).ravel()
    u = np.broadcast_to(np.asarray(u, dtype=np.float64), patch.shape).ravel()
    v = np.broadcast_to(np.asarray(v, dtype=np.float64), patch.shape).ravel()
    m = patch.size
    out = {name: np.full(m, np.nan) for name in ("k1", "k2", "K", "H", "kmax")}
    out["point"] = np.full((m, 3), np.nan)
    out["normal"] = np.full((m, 3), np.nan)
    start = 0
    for group in groups:
        count = group.shape[0]
        which = np.flatnonzero((patch >= start) & (patch < start + count))
        columns = patch_columns(group) if which.size else None
        for lo in range(0, which.size, chunk):
            idx = which[lo : lo + chunk]
            d = patch_derivatives(group, u[idx], v[idx], index=patch[idx] - start, columns=columns)
            c = curvature_from_derivatives(*d)
            for name in out:
                out[name][idx] = c[name]
            if progress is not None:
                progress(idx.size)
        start += count
    bad = (patch < 0) | (patch >= start)
    if bad.any():
        raise IndexError(f"patch index out of range 0..{start - 1}: {patch[bad][0]}")
    return Curvature(**out)


def grid_curvature(group: np.ndarray, t: np.ndarray) -> Curvature:
    """Curvature of every patch of one degree on the tensor grid ``t x t``.

    Parameters
    ----------
    group : (p, d+1, d+1, dim) float
    t : (n,) float

    Returns
    -------
    Curvature with fields of shape (p * n * n,) (and (p * n * n, 3)), ordered (patch, i, j)
    with u = t[i], v = t[j]
    """
    p, n = group.shape[0], t.size
    ii, jj = np.meshgrid(t, t, indexing="ij")
    idx = np.repeat(np.arange(p), n * n)
    u = np.tile(ii.ravel(), p)
    v = np.tile(jj.ravel(), p)
    return patch_curvature(group, u, v, index=idx)


def patch_offsets(groups) -> np.ndarray:
    """(len(groups) + 1,) int: first global patch index of each group, then the total."""
    return np.concatenate([[0], np.cumsum([g.shape[0] for g in groups])]).astype(np.int64)




def tessellation_curvature(groups, grid: np.ndarray, n_vertices: int | None = None, progress=None,
                           chunk_patches: int = 1 << 14) -> dict:
    """Per-vertex curvature of a welded tessellation (``core.tessellate.Tessellation``).

    Sample (i, j) of patch k is vertex ``grid[k, i, j]`` at u = i / (n-1), v = j / (n-1).
    A vertex on a patch edge or corner belongs to several patches; G1 surfaces have
    continuous normals but not continuous curvature there, so it gets the mean of the
    patches' values.

    Parameters
    ----------
    groups : list of patch groups, global patch order as ``grid``
    grid : (P, n, n) int
    progress : callable(label, advance, total) or None

    Returns
    -------
    dict name -> (V,) float for kmax, K, H, k1, k2
    """
    n = grid.shape[1]
    t = np.linspace(0.0, 1.0, n)
    v_count = int(n_vertices if n_vertices is not None else grid.max() + 1)
    names = ("kmax", "K", "H", "k1", "k2")
    sums = {name: np.zeros(v_count) for name in names}
    counts = np.zeros(v_count)
    total = int(grid.shape[0])
    start = 0
    for group in groups:
        columns = patch_columns(group)
        for lo in range(0, group.shape[0], chunk_patches):
            hi = min(group.shape[0], lo + chunk_patches)
            p = hi - lo
            ii, jj = np.meshgrid(t, t, indexing="ij")
            index = np.repeat(np.arange(lo, hi), n * n)
            d = patch_derivatives(group, np.tile(ii.ravel(), p), np.tile(jj.ravel(), p), index=index, columns=columns)
            c = curvature_from_derivatives(*d)
            ids = grid[start + lo : start + hi].ravel()
            ok = np.isfinite(c.kmax)
            counts += np.bincount(ids[ok], minlength=v_count)
            for name in names:
                sums[name] += np.bincount(ids[ok], weights=c[name][ok], minlength=v_count)
            if progress is not None:
                progress("evaluating curvature", p, total)
        start += group.shape[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        return {name: sums[name] / counts for name in names}


__all__ = ["Curvature", "tessellation_curvature", "bernstein_columns", "patch_columns", "polynomial_derivatives", "patch_derivatives", "patch_tangents", "curvature_from_derivatives", "patch_curvature", "surface_curvature", "grid_curvature", "patch_offsets"]
