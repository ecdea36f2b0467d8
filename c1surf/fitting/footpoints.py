"""Footpoints: the closest point on the exact patches of every scan sample.

A start grid (every patch sampled on k x k parameters, each sample carrying its (patch, u, v))
gives, through a k-d tree, a few candidate patches per sample: those of its nearest grid samples.
On each candidate, vectorised Newton steps on |x(u, v) - p|^2 with the parameters held in
[0, 1]^2 (a parameter on its bound whose gradient points outwards is held there, the other one
steps alone) find the closest point of that patch; the nearest of the candidates is the footpoint.
Trying several patches lets samples near a patch side land on the patch across it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..evaluation.bezier import evaluate_patches, patch_columns, raise_degree, sample_derivatives
from ..parallel import thread_count

__all__ = ["Footpoints", "PatchSet", "patch_set", "project_points"]

ORDERS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))


@dataclass(frozen=True)
class Footpoints:
    """The projections of m scan samples.

    patch : (m,) int, patch index (biquadratic first, then bicubic: the order of ``Surface.frames``)
    u, v : (m,) float in [0, 1], the parameters on that patch
    points : (m, 3) float, the surface points x(patch, u, v)
    distance : (m,) float, |points - samples|
    """

    patch: np.ndarray
    u: np.ndarray
    v: np.ndarray
    points: np.ndarray
    distance: np.ndarray


@dataclass(frozen=True)
class PatchSet:
    """Every patch of a surface, for Newton steps (each in its degree) and a start grid.

    quadratic : (3, 3, 3, Nq) float, ``bezier.patch_columns`` of the biquadratic patches
    cubic : (4, 4, 3, Nc) float, the same of the bicubic ones (patch Nq + k is bicubic k)
    grid : (P k k, 3) float, the start samples, patch by patch, (u_a, v_b) row-major
    grid_u, grid_v : (k k,) float, the parameters of one patch's start samples
    tree : cKDTree of ``grid``
    """

    quadratic: np.ndarray
    cubic: np.ndarray
    grid: np.ndarray
    grid_u: np.ndarray
    grid_v: np.ndarray
    tree: cKDTree

    @property
    def n_patches(self) -> int:
        return int(self.quadratic.shape[-1] + self.cubic.shape[-1])

    def derivatives(self, patch: np.ndarray, u: np.ndarray, v: np.ndarray, orders) -> dict:
        """``bezier.sample_derivatives`` at one (patch, u, v) each, every patch in its own degree:
        dict (a, b) -> (n, 3) float."""
        n_quad = self.quadratic.shape[-1]
        kinds = [(self.quadratic, np.nonzero(patch < n_quad)[0], 0),
                 (self.cubic, np.nonzero(patch >= n_quad)[0], n_quad)]
        out = {order: np.empty((patch.size, 3)) for order in orders}
        for columns, rows, first in kinds:
            if rows.size:
                part = sample_derivatives(columns, patch[rows] - first, u[rows], v[rows], orders)
                for order in orders:
                    out[order][rows] = part[order]
        return out


def patch_set(biquadratic: np.ndarray, bicubic: np.ndarray, resolution: int = 4) -> PatchSet:
    """The ``PatchSet`` of a surface's patches.

    Parameters
    ----------
    biquadratic : (Nq, 3, 3, 3) float; bicubic : (Nc, 4, 4, 3) float (``Surface.biquadratic``, ``bicubic``)
    resolution : int >= 1, start samples per patch side (at the centres of a k x k grid of cells)
    """
    quadratic, cubic = np.asarray(biquadratic)[..., :3], np.asarray(bicubic)[..., :3]
    grid_cubic = np.concatenate([raise_degree(quadratic, 3, 3), cubic])
    t = (np.arange(int(resolution)) + 0.5) / int(resolution)  # cell centres: the nearest is inside its patch
    grid = evaluate_patches(grid_cubic, t, t).reshape(-1, 3)
    grid_u, grid_v = (a.ravel() for a in np.meshgrid(t, t, indexing="ij"))
    return PatchSet(patch_columns(quadratic), patch_columns(cubic), grid, grid_u, grid_v, cKDTree(grid))


def project_points(patches: PatchSet, samples: np.ndarray, candidates: int = 3, steps: int = 8,
                   start: Footpoints | None = None) -> Footpoints:
    """Project every sample onto the nearest of its candidate patches.

    Parameters
    ----------
    patches : PatchSet
    samples : (m, 3) float
    candidates : int >= 1, distinct patches tried per sample where the first one is in doubt
    steps : int >= 1, most Newton steps on each
    start : Footpoints or None, the previous round's projections (same samples): the first patch tried

    Returns
    -------
    Footpoints

    The first patch tried is ``start``'s, else that of the nearest start sample. Only where its
    footpoint is in doubt (on a side of the patch's domain, or farther than the nearest start
    sample) are the other candidates (the patches of the next nearest start samples) tried.
    """
    samples = np.asarray(samples, dtype=np.float64)
    m, per_patch = samples.shape[0], patches.grid_u.size
    grid_distance, nearest = patches.tree.query(samples, workers=thread_count())
    if start is None:
        patch, u, v = nearest // per_patch, patches.grid_u[nearest % per_patch], patches.grid_v[nearest % per_patch]
    else:
        patch, u, v = start.patch, start.u, start.v
    u, v, x = newton_projection(patches, patch, u, v, samples, steps)
    distance = _norm(x - samples)
    doubt = np.nonzero((np.minimum(u, v) <= 0) | (np.maximum(u, v) >= 1) | (distance > grid_distance))[0]
    if doubt.size == 0 or candidates == 1:
        return Footpoints(patch, u, v, x, distance)
    # the other patches among the nearest start samples: the first sample of each distinct patch, up to candidates
    near = min(3 * candidates, patches.grid.shape[0])
    index = patches.tree.query(samples[doubt], k=near, workers=thread_count())[1].reshape(doubt.size, near)
    grid_patch = index // per_patch
    repeated = grid_patch == patch[doubt][:, None]
    for j in range(1, near):
        repeated[:, j] |= (grid_patch[:, :j] == grid_patch[:, j : j + 1]).any(axis=1)
    rank = np.cumsum(~repeated, axis=1)
    rows, cols = np.nonzero(~repeated & (rank < candidates))
    tried = index[rows, cols]
    which = doubt[rows]
    cu, cv, cx = newton_projection(patches, tried // per_patch, patches.grid_u[tried % per_patch],
                                   patches.grid_v[tried % per_patch], samples[which], steps)
    cd = _norm(cx - samples[which])
    order = np.lexsort((cd, which))  # the nearest candidate of each sample
    first = np.ones(order.size, dtype=bool)
    first[1:] = which[order][1:] != which[order][:-1]
    best = order[first]
    better = best[cd[best] < distance[which[best]]]
    k = which[better]
    patch, u, v, x, distance = patch.copy(), u.copy(), v.copy(), x.copy(), distance.copy()
    patch[k], u[k], v[k], x[k], distance[k] = tried[better] // per_patch, cu[better], cv[better], cx[better], cd[better]
    return Footpoints(patch, u, v, x, distance)


def newton_projection(patches: PatchSet, patch: np.ndarray, u: np.ndarray, v: np.ndarray, samples: np.ndarray,
                      steps: int = 8, tolerance: float = 1e-12):
    """Newton steps on f(u, v) = |x(u, v) - p|^2 / 2 within [0, 1]^2, one (patch, u, v, p) each.

    Parameters
    ----------
    patches : PatchSet
    patch : (n,) int; u, v : (n,) float, the starts; samples : (n, 3) float, the points p
    steps : int, most steps; a sample stops once its step is below ``tolerance`` (in parameters)

    Returns
    -------
    u, v : (n,) float, the parameters reached; x : (n, 3) float, the patch points there

    The Hessian is the full one, [x_u.x_u + r.x_uu, ...], where it is positive definite, else the
    Gauss-Newton one (its first part). A parameter on its bound with the gradient pointing out of
    [0, 1] is held there (the other steps alone along that side); steps are limited to half the domain.
    """
    patch = np.asarray(patch)
    u, v = u.astype(np.float64).copy(), v.astype(np.float64).copy()
    active = np.arange(u.size)
    for _ in range(int(steps)):
        if active.size == 0:
            break
        du, dv = _newton_step(patches, patch[active], u[active], v[active], samples[active])
        u[active] = np.clip(u[active] + du, 0.0, 1.0)
        v[active] = np.clip(v[active] + dv, 0.0, 1.0)
        active = active[np.maximum(np.abs(du), np.abs(dv)) > tolerance]
    x = patches.derivatives(patch, u, v, ((0, 0),))[(0, 0)]
    return u, v, np.ascontiguousarray(x)


def _newton_step(patches: PatchSet, patch, u, v, samples):
    """(du, dv): one projected Newton step of ``newton_projection`` at each sample."""
    d = patches.derivatives(patch, u, v, ORDERS)
    r = d[(0, 0)] - samples
    xu, xv = d[(1, 0)], d[(0, 1)]
    gu, gv = _dot(xu, r), _dot(xv, r)
    a, b, c = _dot(xu, xu), _dot(xu, xv), _dot(xv, xv)
    fa, fb, fc = a + _dot(d[(2, 0)], r), b + _dot(d[(1, 1)], r), c + _dot(d[(0, 2)], r)
    full = (fa > 0) & (fa * fc - fb * fb > 1e-12 * (a * c + 1e-300))
    a, b, c = np.where(full, fa, a), np.where(full, fb, b), np.where(full, fc, c)
    hold_u = ((u <= 0) & (gu > 0)) | ((u >= 1) & (gu < 0))
    hold_v = ((v <= 0) & (gv > 0)) | ((v >= 1) & (gv < 0))
    tiny = 1e-300
    det = a * c - b * b
    both = ~hold_u & ~hold_v & (np.abs(det) > 1e-14 * (a * c + tiny))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        du = np.where(both, (-c * gu + b * gv) / np.where(both, det, 1.0), 0.0)
        dv = np.where(both, (b * gu - a * gv) / np.where(both, det, 1.0), 0.0)
        alone_u = ~hold_u & ~both  # v held (or a singular 2 x 2): u steps alone
        alone_v = hold_u & ~hold_v
        du = np.where(alone_u, -gu / np.maximum(a, tiny), du)
        dv = np.where(alone_v, -gv / np.maximum(c, tiny), dv)
    du = np.nan_to_num(du, nan=0.0, posinf=0.0, neginf=0.0)
    dv = np.nan_to_num(dv, nan=0.0, posinf=0.0, neginf=0.0)
    scale = np.minimum(1.0, 0.5 / np.maximum(np.maximum(np.abs(du), np.abs(dv)), tiny))
    return scale * du, scale * dv


def _norm(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("ij,ij->i", x, x))


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)
