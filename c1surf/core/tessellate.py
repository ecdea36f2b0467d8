"""Welded tessellation: every patch sampled on an N x N grid, shared points shared.

Patches are dual to the refined mesh (see ``patches``): patch corners are
centroids of refined faces and patch sides cross refined edges. So the welded
vertex numbering is index arithmetic: one vertex per refined face, N-2 per
refined edge (in a canonical direction), (N-2)^2 per patch. No distance search.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bezier import bernstein_basis, unit_normals


@dataclass(frozen=True)
class Tessellation:
    """A triangle mesh sampled from the patches.

    points : (V, d) float; normals : (V, 3) float (exact, from patch derivatives)
    triangles : (T, 3) int, counter-clockwise from outside
    triangle_patch : (T,) int, patch index (biquadratic first, then bicubic)
    grid : (P, N, N) int, vertex index of sample (i, j) = (u_i, v_j) of each patch
    """

    points: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    triangle_patch: np.ndarray
    grid: np.ndarray

    @property
    def resolution(self) -> int:
        return int(self.grid.shape[1])

    def triangle_uv(self) -> np.ndarray:
        """(T, 3, 2) float: patch parameters (u, v) of each triangle corner."""
        n = self.resolution
        local = _grid_triangles(n)
        t = np.linspace(0.0, 1.0, n)
        i, j = np.divmod(local, n)
        uv = np.stack([t[i], t[j]], axis=-1)  # (2 (n-1)^2, 3, 2)
        return np.tile(uv, (self.grid.shape[0], 1, 1))


def _grid_triangles(n: int) -> np.ndarray:
    """(2 (n-1)^2, 3) int: triangles of an n x n grid numbered i * n + j."""
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    b, c, d = a + n, a + n + 1, a + 1  # (i+1, j), (i+1, j+1), (i, j+1)
    # u x v points outward, so (i,j) -> (i+1,j) -> (i+1,j+1) is counter-clockwise.
    return np.stack([np.stack([a, b, c], 1), np.stack([a, c, d], 1)], axis=1).reshape(-1, 3)


def welded_grid(refined, frames: np.ndarray, n: int) -> np.ndarray:
    """Global vertex index of every grid sample of every patch.

    Parameters
    ----------
    refined : HalfEdgeMesh, the twice-refined mesh
    frames : (P, 4) int, half-edges e0..e3 of each patch
    n : int >= 2, samples per side

    Returns
    -------
    (P, n, n) int, a compact numbering 0..V-1
    """
    p = frames.shape[0]
    h = np.arange(refined.n_halfedges)
    canonical = h[h < refined.twin]
    edge_id = np.full(refined.n_halfedges, -1, dtype=np.int64)
    edge_id[canonical] = np.arange(canonical.size)
    edge_id[refined.twin[canonical]] = np.arange(canonical.size)
    inner = n - 2
    edge_base = refined.n_faces
    patch_base = edge_base + canonical.size * inner

    grid = np.empty((p, n, n), dtype=np.int64)
    face = refined.face
    e0, e1, e2, e3 = frames.T
    grid[:, 0, 0] = face[e2]
    grid[:, -1, 0] = face[e3]
    grid[:, -1, -1] = face[e0]
    grid[:, 0, -1] = face[e1]
    if inner > 0:
        k = np.arange(inner)

        def side(x):
            # Samples running from face(x) to face(twin x); canonical direction
            # is from face(c) to face(twin c) for the smaller half-edge c.
            forward = x < refined.twin[x]
            idx = np.where(forward[:, None], k[None, :], inner - 1 - k[None, :])
            return edge_base + edge_id[x][:, None] * inner + idx

        grid[:, -1, 1:-1] = side(refined.twin[e0])  # u = 1, v increasing
        grid[:, 1:-1, -1] = side(e1)  # v = 1, u increasing
        grid[:, 0, 1:-1] = side(e2)  # u = 0, v increasing
        grid[:, 1:-1, 0] = side(refined.twin[e3])  # v = 0, u increasing
        grid[:, 1:-1, 1:-1] = patch_base + np.arange(p * inner * inner).reshape(p, inner, inner)
    used, compact = np.unique(grid, return_inverse=True)
    return compact.reshape(p, n, n)


def tessellate(patch_groups, refined, frames: np.ndarray, resolution: int = 8) -> Tessellation:
    """Sample patches on a welded grid.

    Parameters
    ----------
    patch_groups : list of (p_k, d_k+1, d_k+1, dim) float, in the order of ``frames``
    refined : HalfEdgeMesh, the twice-refined mesh the frames refer to
    frames : (sum p_k, 4) int
    resolution : int >= 2, samples per patch side

    Returns
    -------
    Tessellation
    """
    if resolution < 2:
        raise ValueError("resolution must be at least 2")
    n = int(resolution)
    grid = welded_grid(refined, frames, n)
    dim = patch_groups[0].shape[-1]
    points = np.empty((int(grid.max()) + 1 if grid.size else 0, dim))
    normals = np.empty((points.shape[0], 3))
    t = np.linspace(0.0, 1.0, n)
    start = 0
    for group in patch_groups:
        count = group.shape[0]
        if count == 0:
            continue
        degree = group.shape[1] - 1
        b, db = bernstein_basis(degree, t), bernstein_basis(degree, t, 1)
        ids = grid[start : start + count]
        points[ids] = np.einsum("ai,bj,pijd->pabd", b, b, group, optimize=True)
        xu = np.einsum("ai,bj,pijd->pabd", db, b, group[..., :3], optimize=True)
        xv = np.einsum("ai,bj,pijd->pabd", b, db, group[..., :3], optimize=True)
        normals[ids] = unit_normals(xu, xv)
        start += count
    local = _grid_triangles(n)
    flat = grid.reshape(grid.shape[0], -1)
    triangles = flat[:, local].reshape(-1, 3)
    triangle_patch = np.repeat(np.arange(grid.shape[0]), local.shape[0])
    return Tessellation(points, normals, triangles, triangle_patch, grid)
