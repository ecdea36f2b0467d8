"""Exact curvature of (rational) tensor-product Bezier patches.

First and second derivatives come from ``bezier.sample_derivatives`` (rational
patches: homogeneous derivatives and the quotient rule of ``rational``); the
fundamental forms give the principal curvatures. Everything is vectorized over
arrays of samples ``(patch, u, v)``.

Sign convention: the unit normal is ``n = x_u x x_v / |x_u x x_v|`` (outward for
c1surf surfaces) and a normal curvature is positive where the surface bends
away from ``n``: a sphere of radius r with outward normals has
``k1 = k2 = H = 1/r`` and ``K = 1/r^2``. ``k1 >= k2``; ``kmax = max(|k1|, |k2|)``.

Rational patches (A2a) are Euclidean control points with their weights passed
explicitly (``weights``, a list parallel to the groups, as ``PatchSet.weights``);
only x, y, z are evaluated, so attribute columns after them are ignored.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bezier import patch_columns, sample_derivatives
from .rational import euclidean_derivatives, homogeneous

# Derivative orders (du, dv) evaluated by ``PatchSampler.derivatives``, in output order.
_ORDERS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))
CURVATURE_NAMES = ("kmax", "K", "H", "k1", "k2")


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


def patch_offsets(groups) -> np.ndarray:
    """(len(groups) + 1,) int64: first global patch index of each group, then the total."""
    return np.concatenate([[0], np.cumsum([len(g) for g in groups])]).astype(np.int64)


class PatchSampler:
    """The patches of a surface, laid out for evaluation at scattered samples (patch, u, v).

    Global patch k is patch ``k - offsets[g]`` of group g, ``offsets[g] <= k <
    offsets[g + 1]`` (biquadratic first, then bicubic, as in a patch file).

    Parameters
    ----------
    groups : list of (p_g, du+1, dv+1, d) float, x, y, z first
    weights : None or a list parallel to ``groups`` of (p_g, du+1, dv+1) float: rational patches (A2a)
    """

    def __init__(self, groups, weights=None):
        self.offsets = patch_offsets(groups)
        self.rational = weights is not None
        self.columns = []
        for g, group in enumerate(groups):
            xyz = np.asarray(group, dtype=np.float64)[..., :3]
            evaluated = xyz if weights is None else homogeneous(xyz, weights[g])
            self.columns.append(patch_columns(evaluated) if len(group) else None)

    @property
    def n_patches(self) -> int:
        return int(self.offsets[-1])

    def derivatives(self, g: int, index, u, v, orders=_ORDERS) -> tuple:
        """x and its derivatives of ``orders`` at samples of group ``g``.

        Parameters
        ----------
        g : int, the group
        index : (m,) int, the patch of each sample within the group (None: patch k for sample k)
        u, v : (m,) float
        orders : tuple of (a, b), derivatives d^(a+b) x / du^a dv^b

        Returns
        -------
        tuple of (m, 3) float, one per order
        """
        h = sample_derivatives(self.columns[g], index, u, v, orders)
        x = euclidean_derivatives(h) if self.rational else h
        return tuple(x[o] for o in orders)

    def tangents(self, g: int, index, u, v) -> tuple:
        """x, x_u, x_v : (m, 3) float at samples of group ``g`` (arguments as ``derivatives``)."""
        return self.derivatives(g, index, u, v, _ORDERS[:3])

    def curvature(self, g: int, index, u, v) -> "Curvature":
        """Curvature at samples of group ``g`` (arguments as ``derivatives``)."""
        return curvature_from_derivatives(*self.derivatives(g, index, u, v))

    def runs(self, patch: np.ndarray, chunk: int):
        """Yield (g, which): positions in ``patch`` (global indices) of group g, at most ``chunk`` at a time."""
        for g in range(len(self.columns)):
            which = np.flatnonzero((patch >= self.offsets[g]) & (patch < self.offsets[g + 1]))
            for lo in range(0, which.size, chunk):
                yield g, which[lo : lo + chunk]

    def curvature_at(self, patch, u, v, chunk: int = 1 << 18, progress=None) -> "Curvature":
        """Curvature at samples given by global patch index and parameters.

        Parameters
        ----------
        patch : (m,) int, global patch index of each sample
        u, v : (m,) float (or scalars)
        chunk : int, samples evaluated at once (bounds memory)
        progress : callable(n) or None, called with the number of samples done per chunk

        Returns
        -------
        Curvature with (m,) fields
        """
        patch = np.asarray(patch, dtype=np.int64).ravel()
        u = np.broadcast_to(np.asarray(u, dtype=np.float64), patch.shape).ravel()
        v = np.broadcast_to(np.asarray(v, dtype=np.float64), patch.shape).ravel()
        bad = (patch < 0) | (patch >= self.n_patches)
        if bad.any():
            raise IndexError(f"patch index out of range 0..{self.n_patches - 1}: {patch[bad][0]}")
        out = {name: np.full(patch.size, np.nan) for name in CURVATURE_NAMES}
        out["point"], out["normal"] = np.full((patch.size, 3), np.nan), np.full((patch.size, 3), np.nan)
        for g, idx in self.runs(patch, chunk):
            c = self.curvature(g, patch[idx] - self.offsets[g], u[idx], v[idx])
            for name in out:
                out[name][idx] = c[name]
            if progress is not None:
                progress(idx.size)
        return Curvature(**out)


def patch_derivatives(points: np.ndarray, u, v, weights=None, index=None) -> tuple:
    """Position and first and second derivatives of the surface at one sample each.

    Parameters
    ----------
    points : (m, du+1, dv+1, d) float, one patch per sample; or, with ``index``, a
        group of patches sampled as ``points[index[k]]``
    u, v : (m,) float
    weights : None or (like points without the last axis) float: rational patches (A2a)
    index : (m,) int or None

    Returns
    -------
    x, x_u, x_v, x_uu, x_uv, x_vv : each (m, 3) float, of the Euclidean surface
    """
    return PatchSampler([points], None if weights is None else [weights]).derivatives(0, index, u, v)


def patch_tangents(points: np.ndarray, u, v, weights=None, index=None) -> tuple:
    """Position and first derivatives (arguments as ``patch_derivatives``).

    Returns
    -------
    x, x_u, x_v : each (m, 3) float
    """
    return PatchSampler([points], None if weights is None else [weights]).tangents(0, index, u, v)


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


def patch_curvature(points: np.ndarray, u, v, weights=None, index=None) -> Curvature:
    """Curvature at one sample each (arguments as ``patch_derivatives``)."""
    return curvature_from_derivatives(*patch_derivatives(points, u, v, weights, index))


def surface_curvature(groups, patch, u, v, chunk: int = 1 << 18, progress=None, weights=None) -> Curvature:
    """Curvature at samples given by global patch index and parameters.

    Parameters
    ----------
    groups : list of (p_k, d_k+1, d_k+1, dim) float, patch groups by degree; the global
        patch index runs through them in order (biquadratic first, then bicubic)
    patch : (m,) int, global patch index of each sample
    u, v : (m,) float
    chunk : int, samples evaluated at once (bounds memory)
    progress : callable(n) or None, called with the number of samples done per chunk
    weights : None or a list parallel to ``groups`` of (p_k, d_k+1, d_k+1) float (rational, A2a)

    Returns
    -------
    Curvature with (m,) fields
    """
    return PatchSampler(groups, weights).curvature_at(patch, u, v, chunk, progress)


def tessellation_curvature(groups, grid: np.ndarray, n_vertices: int | None = None, progress=None,
                           chunk_patches: int = 1 << 14, weights=None) -> dict:
    """Per-vertex curvature of a welded tessellation (``evaluation.tessellate.Tessellation``).

    Sample (i, j) of patch k is vertex ``grid[k, i, j]`` at u = i / (n-1), v = j / (n-1).
    A vertex on a patch edge or corner belongs to several patches; G1 surfaces have
    continuous normals but not continuous curvature there, so it gets the mean of the
    patches' values.

    Parameters
    ----------
    groups : list of patch groups, global patch order as ``grid``
    grid : (P, n, n) int
    n_vertices : int or None (default ``grid.max() + 1``)
    progress : callable(label, advance, total) or None
    chunk_patches : int, patches evaluated at once
    weights : None or a list parallel to ``groups`` of weight arrays (rational, A2a)

    Returns
    -------
    dict name -> (V,) float for kmax, K, H, k1, k2
    """
    n = grid.shape[1]
    t = np.linspace(0.0, 1.0, n)
    ii, jj = np.meshgrid(t, t, indexing="ij")
    v_count = int(n_vertices if n_vertices is not None else grid.max() + 1)
    sums = {name: np.zeros(v_count) for name in CURVATURE_NAMES}
    counts = np.zeros(v_count)
    sampler = PatchSampler(groups, weights)
    for g in range(len(groups)):
        for lo in range(0, len(groups[g]), chunk_patches):
            hi = min(len(groups[g]), lo + chunk_patches)
            index = np.repeat(np.arange(lo, hi), n * n)
            c = sampler.curvature(g, index, np.tile(ii.ravel(), hi - lo), np.tile(jj.ravel(), hi - lo))
            ids = grid[sampler.offsets[g] + lo : sampler.offsets[g] + hi].ravel()
            ok = np.isfinite(c.kmax)
            counts += np.bincount(ids[ok], minlength=v_count)
            for name in CURVATURE_NAMES:
                sums[name] += np.bincount(ids[ok], weights=c[name][ok], minlength=v_count)
            if progress is not None:
                progress("evaluating curvature", hi - lo, int(grid.shape[0]))
    with np.errstate(invalid="ignore", divide="ignore"):
        return {name: sums[name] / counts for name in CURVATURE_NAMES}


__all__ = ["Curvature", "PatchSampler", "CURVATURE_NAMES", "curvature_from_derivatives", "patch_derivatives",
           "patch_tangents", "patch_curvature", "surface_curvature", "tessellation_curvature", "patch_offsets"]
