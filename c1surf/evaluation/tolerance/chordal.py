"""Measured chordal error of a tessellation against its exact patches.

For every triangle, the exact patch is evaluated at parameters inside the
triangle (by default its centroid and its three edge midpoints) and compared
with the triangle's linear interpolation at the same barycentric coordinates,
i.e. the mesh actually written (its vertices as evaluated, not recomputed).
This measures; it uses no bound, so it checks ``resolution``'s bound too.

Both kinds of tessellation are measured the same way: a layout is a sequence of
blocks (patches (n,), local (u, v) samples (L, 2), local triangles (T, 3),
vertex ids (n, L), triangle rows (n, T)), all patches of a block sharing the
local samples. ``uniform_blocks`` gives the one block of a uniform
``evaluation.tessellate.Tessellation``, ``tolerance_blocks`` those of a
``ToleranceTessellation``. Within a block and a degree, the samples are the same
for every patch, so the basis matrix is built once and applied to all patches as
one matrix product.
"""
from __future__ import annotations

import numpy as np

from ..bezier import bernstein_basis
from ..rational import homogeneous
from ..tessellate import grid_triangles

# Barycentric coordinates of the points measured in every triangle: the centroid and the edge midpoints.
CENTROID_AND_MIDPOINTS = np.array([[1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])
_BLOCK_PATCHES = 1 << 12


def uniform_blocks(tess):
    """The layout of a uniform tessellation (``tess.grid`` (P, n, n)): one block of every patch."""
    n = tess.grid.shape[1]
    t = np.linspace(0.0, 1.0, n)
    uv = np.stack(np.meshgrid(t, t, indexing="ij"), axis=-1).reshape(-1, 2)
    local = grid_triangles(n)
    patches = np.arange(tess.grid.shape[0])
    rows = patches[:, None] * local.shape[0] + np.arange(local.shape[0])
    yield patches, uv, local, tess.grid.reshape(patches.size, -1), rows


def tolerance_blocks(tess):
    """The layout of a ``ToleranceTessellation``: one block per template."""
    plan = tess.plan
    for tpl, patches, ids in plan.blocks():
        rows = plan.triangle_start[patches, None] + np.arange(tpl.triangles.shape[0])
        yield patches, tpl.uv, tpl.triangles, ids, rows


def chordal_errors(groups, points: np.ndarray, triangles_count: int, blocks, weights=None,
                   barycentric: np.ndarray = CENTROID_AND_MIDPOINTS) -> np.ndarray:
    """Largest distance, per triangle, between the exact patch and the triangle at ``barycentric`` samples.

    Parameters
    ----------
    groups : list of (p_k, d_k+1, d_k+1, dim) float, patches in global order (x, y, z first)
    points : (V, >= 3) float, the tessellation's vertices (only x, y, z are used)
    triangles_count : int, T
    blocks : iterable of layout blocks (``uniform_blocks``, ``tolerance_blocks``)
    weights : None or a list parallel to ``groups`` (rational patches, A2a)
    barycentric : (S, 3) float, rows summing to 1

    Returns
    -------
    (T,) float, absolute distances (NaN for a triangle no block covers)
    """
    out = np.full(triangles_count, np.nan)
    starts = np.concatenate([[0], np.cumsum([len(g) for g in groups])])
    xyz = np.asarray(points)[:, :3]
    nets = [g[..., :3] if weights is None else homogeneous(g[..., :3], weights[k]) for k, g in enumerate(groups)]
    for patches, uv, local, ids, rows in blocks:
        # (T S, 2) parameters of the samples, the same for every patch of the block
        params = np.einsum("sk,tkc->tsc", barycentric, uv[local]).reshape(-1, 2)
        for k, h in enumerate(nets):
            mine = np.flatnonzero((patches >= starts[k]) & (patches < starts[k + 1]))
            if not mine.size:
                continue
            d_u, d_v = h.shape[1] - 1, h.shape[2] - 1
            basis = np.einsum("qi,qj->qij", bernstein_basis(d_u, params[:, 0]),
                              bernstein_basis(d_v, params[:, 1])).reshape(params.shape[0], -1)  # (T S, C)
            for lo in range(0, mine.size, _BLOCK_PATCHES):
                sel = mine[lo : lo + _BLOCK_PATCHES]
                control = h[patches[sel] - starts[k]].reshape(sel.size, -1, h.shape[-1])  # (n, C, 3 or 4)
                exact = np.matmul(basis, control)  # (n, T S, 3 or 4)
                if weights is not None:
                    exact = exact[..., :3] / exact[..., 3:]
                corners = xyz[ids[sel][:, local]]  # (n, T, 3, 3)
                linear = np.einsum("sk,ntkc->ntsc", barycentric, corners)
                gap = np.linalg.norm(exact.reshape(linear.shape) - linear, axis=-1).max(axis=-1)  # (n, T)
                out[rows[sel]] = gap
    return out


def bounding_diagonal(points: np.ndarray) -> float:
    """Bounding-box diagonal of (V, >= 3) points (x, y, z)."""
    xyz = np.asarray(points)[:, :3]
    return float(np.linalg.norm(xyz.max(axis=0) - xyz.min(axis=0))) if len(xyz) else 0.0


def measured_chordal_error(groups, tess, weights=None) -> float:
    """Largest chordal error of any triangle of ``tess``, relative to its vertices' bounding-box diagonal.

    tess : ``evaluation.tessellate.Tessellation`` (uniform) or ``ToleranceTessellation``
    """
    blocks = uniform_blocks(tess) if hasattr(tess, "grid") else tolerance_blocks(tess)
    errors = chordal_errors(groups, tess.points, tess.triangles.shape[0], blocks, weights)
    diagonal = bounding_diagonal(tess.points)
    return float(np.nanmax(errors) / diagonal) if errors.size and diagonal > 0 else 0.0


__all__ = ["chordal_errors", "measured_chordal_error", "uniform_blocks", "tolerance_blocks", "bounding_diagonal",
           "CENTROID_AND_MIDPOINTS"]
