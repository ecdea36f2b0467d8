"""Welded tessellation: every patch sampled on an N x N grid, shared points shared.

Patches are dual to the refined mesh (see ``patches``): patch corners are
centroids of refined faces and patch sides cross refined edges. So the welded
vertex numbering is index arithmetic on plain per-patch arrays (corner ids,
side edge ids and directions: ``adjacency.PatchAdjacency``): one vertex per
corner, N-2 per edge (in its own direction), (N-2)^2 per patch. No distance
search. The arrays are stored in patch files, so ``c1surf tessellate``
rebuilds exactly the mesh ``convert`` writes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bezier import bernstein_basis, unit_normals
from .adjacency import PatchAdjacency, adjacency_from_geometry, patch_adjacency  # noqa: F401 (re-exported)


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
    (P, n, n) int, a compact numbering 0..V-1 (see ``welded_grid_from_ids``)
    """
    return welded_grid_from_ids(patch_adjacency(refined, frames), n)


def welded_grid_from_ids(adjacency: PatchAdjacency, n: int) -> np.ndarray:
    """Global vertex index of every grid sample, from plain adjacency arrays.

    Vertices are numbered corners first (by corner id), then the n-2 inner
    samples of every edge (by edge id, in the edge's own direction), then the
    (n-2)^2 inner samples of every patch (patch by patch, u slowest). Sample
    (i, j) of a patch is the point at (u_i, v_j).

    Parameters
    ----------
    adjacency : PatchAdjacency, corner ids (P, 4), side edge ids (P, 4), reversed flags (P, 4)
    n : int >= 2, samples per side

    Returns
    -------
    (P, n, n) int, a compact numbering 0..V-1
    """
    corners, edges, reversed_ = adjacency.corners, adjacency.edges, adjacency.reversed
    p = corners.shape[0]
    inner = n - 2
    edge_base = adjacency.n_corners
    patch_base = edge_base + adjacency.n_edges * inner
    grid = np.empty((p, n, n), dtype=np.int64)
    grid[:, 0, 0] = corners[:, 0]
    grid[:, -1, 0] = corners[:, 1]
    grid[:, -1, -1] = corners[:, 2]
    grid[:, 0, -1] = corners[:, 3]
    if inner > 0:
        k = np.arange(inner)

        def side(s):
            idx = np.where(reversed_[:, s, None], inner - 1 - k[None, :], k[None, :])
            return edge_base + edges[:, s, None] * inner + idx

        grid[:, 1:-1, 0] = side(0)  # v = 0, u increasing
        grid[:, -1, 1:-1] = side(1)  # u = 1, v increasing
        grid[:, 1:-1, -1] = side(2)  # v = 1, u increasing
        grid[:, 0, 1:-1] = side(3)  # u = 0, v increasing
        grid[:, 1:-1, 1:-1] = patch_base + np.arange(p * inner * inner).reshape(p, inner, inner)
    total = patch_base + p * inner * max(inner, 0)
    used = np.zeros(total, dtype=bool)
    used[grid] = True
    if not used.all():  # ids with gaps: close them, keeping the order
        grid = (np.cumsum(used) - 1)[grid]
    return grid


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
    Tessellation (the same as ``tessellate_patches(patch_groups, patch_adjacency(refined, frames), resolution)``)
    """
    return tessellate_patches(patch_groups, patch_adjacency(refined, frames), resolution)


def tessellate_patches(patch_groups, adjacency: PatchAdjacency, resolution: int = 8) -> Tessellation:
    """Sample patches on a welded grid given by plain adjacency arrays.

    ``convert`` and ``tessellate`` both call this with the same arrays (from
    the construction or from a patch file), so their outputs are identical.

    Parameters
    ----------
    patch_groups : list of (p_k, d_k+1, d_k+1, dim) float, patches in adjacency order
    adjacency : PatchAdjacency of the sum p_k patches
    resolution : int >= 2, samples per patch side

    Returns
    -------
    Tessellation
    """
    if resolution < 2:
        raise ValueError("resolution must be at least 2")
    n = int(resolution)
    grid = welded_grid_from_ids(adjacency, n)
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
