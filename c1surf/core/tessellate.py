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


def tessellate(patch_groups, refined, frames: np.ndarray, resolution: int = 8, weights=None) -> Tessellation:
    """Sample patches on a welded grid.

    Parameters
    ----------
    patch_groups : list of (p_k, d_k+1, d_k+1, dim) float, in the order of ``frames``
    refined : HalfEdgeMesh, the twice-refined mesh the frames refer to
    frames : (sum p_k, 4) int
    resolution : int >= 2, samples per patch side
    weights : None or list of (p_k, d_k+1, d_k+1) float: rational patches (A2a)

    Returns
    -------
    Tessellation (the same as ``tessellate_patches(patch_groups, patch_adjacency(refined, frames), resolution)``)
    """
    return tessellate_patches(patch_groups, patch_adjacency(refined, frames), resolution, weights)


def tessellate_patches(patch_groups, adjacency: PatchAdjacency, resolution: int = 8, weights=None) -> Tessellation:
    """Sample patches on a welded grid given by plain adjacency arrays.

    ``convert`` and ``tessellate`` both call this with the same arrays (from
    the construction or from a patch file), so their outputs are identical.

    Parameters
    ----------
    patch_groups : list of (p_k, d_k+1, d_k+1, dim) float, patches in adjacency order
    adjacency : PatchAdjacency of the sum p_k patches
    resolution : int >= 2, samples per patch side
    weights : None or list of (p_k, d_k+1, d_k+1) float: rational patches (A2a), points
        divided by w and normals by the quotient rule (``core.rational``)

    Returns
    -------
    Tessellation
    """
    if resolution < 2:
        raise ValueError("resolution must be at least 2")
    if weights is not None:
        from .rational import tessellate_rational

        return tessellate_rational(tessellate_patches, patch_groups, weights, adjacency, resolution)
    n = int(resolution)
    grid = welded_grid_from_ids(adjacency, n)
    dim = patch_groups[0].shape[-1]
    points = np.empty((int(grid.max()) + 1 if grid.size else 0, dim))
    normals = np.empty((points.shape[0], 3))
    t = np.linspace(0.0, 1.0, n)
    inner = n - 2
    if points.shape[0] == adjacency.n_corners + adjacency.n_edges * inner + grid.shape[0] * inner * inner:
        # dense ids (always, for adjacency from the construction or a patch file): each vertex once
        _evaluate_welded(patch_groups, adjacency, n, points, normals)
        patch_groups = []
    start = 0
    for group in patch_groups:  # ids with gaps were closed: every sample of every patch
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
    triangles = np.take(flat, local.ravel(), axis=1).reshape(-1, 3)  # take: several times faster than flat[:, local]
    triangle_patch = np.repeat(np.arange(grid.shape[0]), local.shape[0])
    return Tessellation(points, normals, triangles, triangle_patch, grid)


# -- evaluation straight into the welded arrays ------------------------------------------

_CHUNK_BYTES = 1 << 23  # temporaries per block of patches (large enough to amortize BLAS threading)


def _last_owner(ids: np.ndarray, count: int) -> np.ndarray:
    """(count,) int: the last position in the flat ``ids`` holding each id 0..count-1."""
    owner = np.empty(count, dtype=np.int64)
    owner[ids.ravel()] = np.arange(ids.size)  # in order, so the last patch writing an id wins
    return owner


def _unit_into(out: np.ndarray, nx, ny, nz) -> None:
    """out[..., k] = (nx, ny, nz)[k] / |(nx, ny, nz)|; NaN where the length is zero."""
    length = np.sqrt(nx * nx + ny * ny + nz * nz)
    with np.errstate(invalid="ignore", divide="ignore"):
        inverse = np.where(length > 0, 1.0 / length, np.nan)
    for k, component in enumerate((nx, ny, nz)):
        out[..., k] = component * inverse


def _cross_components(a, b):
    """The components of a x b for (..., 3) arrays."""
    return (a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])


def _evaluate_welded(patch_groups, adjacency: PatchAdjacency, n: int, points: np.ndarray, normals: np.ndarray) -> None:
    """Fill the welded ``points`` and ``normals`` (numbered as ``welded_grid_from_ids``).

    Every welded vertex is evaluated once, from the last patch that has it (as
    writing all patches in order would leave it): corners are control points
    with normals from first differences, edge samples come from the side's
    boundary curve and the next row of control points, and patch interiors are
    one dense basis matrix (samples x coefficients) per degree applied with a
    matrix product written into the output block.
    """
    corners, edges, reversed_ = adjacency.corners, adjacency.edges, adjacency.reversed
    starts = np.cumsum([0] + [g.shape[0] for g in patch_groups])
    dim = points.shape[1]
    inner = n - 2
    n_corners, n_edges = adjacency.n_corners, adjacency.n_edges
    # corners
    patch, slot = np.divmod(_last_owner(corners, n_corners), 4)
    for k, g in enumerate(patch_groups):
        mine = np.flatnonzero((patch >= starts[k]) & (patch < starts[k + 1]))
        if mine.size == 0:
            continue
        d = g.shape[1] - 1
        p, s = patch[mine] - starts[k], slot[mine]
        i = np.where((s == 1) | (s == 2), d, 0)  # corner c at (u, v) = (0,0), (1,0), (1,1), (0,1)
        j = np.where(s >= 2, d, 0)
        points[mine] = g[p, i, j]
        corner = g[p, i, j, :3]
        xu = (g[p, np.where(i == 0, 1, d - 1), j, :3] - corner) * np.where(i == 0, 1.0, -1.0)[:, None]
        xv = (g[p, i, np.where(j == 0, 1, d - 1), :3] - corner) * np.where(j == 0, 1.0, -1.0)[:, None]
        unit = np.empty((mine.size, 3))
        _unit_into(unit, *_cross_components(xu, xv))
        normals[mine] = unit
    if inner <= 0:
        return
    t = np.linspace(0.0, 1.0, n)[1:-1]
    # edge samples, in each edge's own direction
    owner = _last_owner(edges, n_edges)
    patch, side = np.divmod(owner, 4)
    flip = reversed_.ravel()[owner]
    edge_points = points[n_corners : n_corners + n_edges * inner].reshape(n_edges, inner, dim)
    edge_normals = normals[n_corners : n_corners + n_edges * inner].reshape(n_edges, inner, 3)
    for k, g in enumerate(patch_groups):
        d = g.shape[1] - 1
        b, db = bernstein_basis(d, t), bernstein_basis(d, t, 1)
        for s in range(4):
            mine = np.flatnonzero((patch >= starts[k]) & (patch < starts[k + 1]) & (side == s))
            if mine.size == 0:
                continue
            p = patch[mine] - starts[k]
            # the side's control polygon (increasing parameter) and the row next to it, pointing inwards
            row, nxt = {0: (g[:, :, 0], g[:, :, 1]), 1: (g[:, d], g[:, d - 1]),
                        2: (g[:, :, d], g[:, :, d - 1]), 3: (g[:, 0], g[:, 1])}[s]
            row, nxt = np.take(row, p, axis=0), np.take(nxt, p, axis=0)  # take: faster than g[p, :, 0]
            # columns: positions (sample, coordinate), then along and across the side (coordinate, sample)
            basis = np.zeros((2, d + 1, dim, inner * dim + 6 * inner))
            basis[0, :, :, : inner * dim] = np.kron(b, np.eye(dim)).T.reshape(d + 1, dim, inner * dim)
            for c in range(3):
                basis[0, :, c, inner * dim + c * inner : inner * dim + (c + 1) * inner] = db.T
                basis[1, :, c, inner * dim + (3 + c) * inner : inner * dim + (4 + c) * inner] = b.T
                basis[0, :, c, inner * dim + (3 + c) * inner : inner * dim + (4 + c) * inner] = -b.T
            values = np.concatenate([row.reshape(p.size, -1), nxt.reshape(p.size, -1)], axis=1) @ basis.reshape(-1, basis.shape[-1])
            position = values[:, : inner * dim].reshape(p.size, inner, dim)
            derivatives = values[:, inner * dim :].reshape(p.size, 2, 3, inner)  # (edge, along/across, coordinate, sample)
            # across points inwards: +x_v on side 0, -x_u on side 1, -x_v on side 2, +x_u on side 3,
            # so x_u x x_v is along x across on sides 0 and 1, across x along on sides 2 and 3
            a, c = (derivatives[:, 0], derivatives[:, 1]) if s < 2 else (derivatives[:, 1], derivatives[:, 0])
            unit = np.empty((p.size, inner, 3))
            _unit_into(unit, a[:, 1] * c[:, 2] - a[:, 2] * c[:, 1], a[:, 2] * c[:, 0] - a[:, 0] * c[:, 2],
                       a[:, 0] * c[:, 1] - a[:, 1] * c[:, 0])
            back = flip[mine]
            position[back], unit[back] = position[back, ::-1], unit[back, ::-1]
            edge_points[edges.ravel()[owner[mine]]] = position
            edge_normals[edges.ravel()[owner[mine]]] = unit
    # patch interiors: a block of inner^2 vertices per patch, in patch order
    m = inner * inner
    base = n_corners + n_edges * inner
    block_points = points[base:].reshape(-1, m * dim)
    block_normals = normals[base:].reshape(-1, m, 3)
    for k, g in enumerate(patch_groups):
        count = g.shape[0]
        if count == 0:
            continue
        d = g.shape[1] - 1
        b, db = bernstein_basis(d, t), bernstein_basis(d, t, 1)
        size = (d + 1) ** 2
        # columns: positions (sample, coordinate), then x_u and x_v (coordinate, sample)
        basis = np.zeros((size * dim, m * dim + 6 * m))
        basis[:, : m * dim] = np.kron(np.einsum("ai,bj->abij", b, b).reshape(m, size), np.eye(dim)).T
        for c in range(3):
            basis[c::dim, m * dim + c * m : m * dim + (c + 1) * m] = np.einsum("ai,bj->ijab", db, b).reshape(size, m)
            basis[c::dim, m * dim + (3 + c) * m : m * dim + (4 + c) * m] = np.einsum("ai,bj->ijab", b, db).reshape(size, m)
        flat = g.reshape(count, size * dim)
        chunk = max(1, _CHUNK_BYTES // (8 * basis.shape[1]))
        for a in range(0, count, chunk):
            z = min(count, a + chunk)
            values = flat[a:z] @ basis
            block_points[starts[k] + a : starts[k] + z] = values[:, : m * dim]
            derivatives = values[:, m * dim :].reshape(z - a, 2, 3, m)
            xu, xv = derivatives[:, 0], derivatives[:, 1]
            _unit_into(block_normals[starts[k] + a : starts[k] + z],
                       xu[:, 1] * xv[:, 2] - xu[:, 2] * xv[:, 1], xu[:, 2] * xv[:, 0] - xu[:, 0] * xv[:, 2],
                       xu[:, 0] * xv[:, 1] - xu[:, 1] * xv[:, 0])
