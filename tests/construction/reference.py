"""Reference implementations the package does not use: plain per-patch sparse stencils of A2 and A3.

The package applies A2 and A3 as gathers and dense products (``stencils.layout``);
these build the same maps entry by entry from the patch frames and the hole
neighbourhoods, for tests that compare the two.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix

from c1surf.mesh.halfedges import HalfEdgeMesh


def face_corner_vertices(mesh: HalfEdgeMesh, h: np.ndarray) -> np.ndarray:
    """(..., 4) int: the vertices of the quad containing half-edge(s) ``h``."""
    return np.stack([mesh.origin[h], mesh.dest[h], mesh.dest[mesh.next[h]], mesh.origin[mesh.prev[h]]], axis=-1)


def biquadratic_stencil(mesh: HalfEdgeMesh, frames: np.ndarray) -> csr_matrix:
    """Step A2: Bezier coefficients of the biquadratic patch at each regular vertex.

    Corners are centroids of the four quads, edge coefficients midpoints of the
    vertex and an edge neighbour, the centre the vertex itself.

    Parameters
    ----------
    frames : (Nq, 4) int, from ``patch_frames``

    Returns
    -------
    (Nq * 9, V) csr_matrix; row ``9 p + 3 i + j`` gives coefficient Q[i, j] of patch p.
    """
    n = frames.shape[0]
    centre = mesh.origin[frames[:, 0]]
    # Rows Q00 Q01 Q02 Q10 Q11 Q12 Q20 Q21 Q22 hold 4 2 4 2 1 2 4 2 4 entries: 25 per patch.
    layout = [("quad", 2), ("pair", 2), ("quad", 1), ("pair", 3), ("centre", 0), ("pair", 1), ("quad", 3), ("pair", 0), ("quad", 0)]
    cols = np.empty((n, 25), dtype=np.int64)
    vals = np.empty(25)
    counts = []
    at = 0
    for kind, k in layout:
        if kind == "quad":
            cols[:, at : at + 4] = face_corner_vertices(mesh, frames[:, k])
            vals[at : at + 4] = 0.25
        elif kind == "pair":
            cols[:, at], cols[:, at + 1] = centre, mesh.dest[frames[:, k]]
            vals[at : at + 2] = 0.5
        else:
            cols[:, at], vals[at] = centre, 1.0
        width = {"quad": 4, "pair": 2, "centre": 1}[kind]
        counts.append(width)
        at += width
    prefix = np.concatenate([[0], np.cumsum(counts)[:-1]])
    indptr = np.empty(9 * n + 1, dtype=np.int64)
    indptr[:-1].reshape(n, 9)[:] = (25 * np.arange(n))[:, None] + prefix
    indptr[-1] = 25 * n
    return csr_matrix((np.tile(vals, n), cols.ravel(), indptr), shape=(9 * n, mesh.n_vertices))


def bicubic_stencil(mesh: HalfEdgeMesh, holes, hole_weights, keep=None) -> csr_matrix:
    """Step A3 for all holes: (Nc * 16, V) matrix, row ``16 p + 4 k + l`` = P_{kl} of patch p.

    Patches are numbered hole by hole in ``holes`` order, corner i within a hole.

    Parameters
    ----------
    holes : list of HoleGroup
    hole_weights : callable n -> (16 n, 4 n), weights on [A, B1, B2, C] (``HoleRules.weights``)
    keep : (Nc,) bool or None, patches kept
    """
    rows, cols, vals = [], [], []
    base = 0
    for g in holes:
        W = hole_weights(g.n).reshape(g.n, 16, 4 * g.n)
        i, r, c = np.nonzero(W)
        local = np.concatenate([g.A, g.B1, g.B2, g.C], axis=1)  # (k, 4n)
        patch = base + np.arange(g.cells.size)[:, None] * g.n + i[None, :]
        rows.append((patch * 16 + r[None, :]).ravel())
        cols.append(local[:, c].ravel())
        vals.append(np.broadcast_to(W[i, r, c], (g.cells.size, i.size)).ravel())
        base += g.cells.size * g.n
    if not rows:
        return csr_matrix((0, mesh.n_vertices))
    matrix = csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(base * 16, mesh.n_vertices))
    if keep is None:
        return matrix
    return matrix[(np.flatnonzero(keep)[:, None] * 16 + np.arange(16)).ravel()]
