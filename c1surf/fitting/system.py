"""The sparse least-squares system of one fitting round (footpoints fixed).

The surface point of a footpoint (patch p, u, v) is a Bernstein combination of the patch's
coefficients, which are the stencil rows ``Surface.stencil()`` applied to the control points:
x_i = B_i S X with B (m x R) the basis rows and S (R x V). So A = B S (m x V, sparse: a patch
depends on a few dozen control points) maps control points to footpoint positions, and the energy
of ``options.FitOptions`` is a quadratic form in X. The point-to-plane term couples the three
coordinates, so the unknowns are x = X.ravel() (3 V, coordinate fastest) and the normal equations
are N x = b with N = sum of

    plane / m  P^T P        P (m x 3V): entry (i, 3a + c) = A_ia n_ic (built as six A^T diag A blocks)
    point / m  A^T A (x) I_3
    fairness / P  K (x) I_3           K the thin-plate form of the P patches (``thin_plate``), or
    fairness / V  L^T L (x) I_3       L the umbrella Laplacian of the control mesh (``fairness_term``)
    damping I                         damping = 1e-12 of N's mean diagonal, towards the current points

all sparse (never a dense matrix). The damping only makes N definite where no sample and no
fairness holds a control point; at a fixed point of the iteration it changes nothing.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..evaluation.bezier import bernstein_columns
from .footpoints import Footpoints

__all__ = ["basis_rows", "umbrella_laplacian", "normal_equations", "vertex_normals", "fairness_form", "DAMPING"]

DAMPING = 1e-12


def basis_rows(footpoints: Footpoints, n_quad: int, n_rows: int) -> sp.csr_matrix:
    """(m, R) csr_matrix B: the Bernstein weights of each footpoint on its patch's rows of the stencil.

    Parameters
    ----------
    footpoints : Footpoints, patches numbered biquadratic first (n_quad of them), then bicubic
    n_quad : int, Nq
    n_rows : int, R = 9 Nq + 16 Nc (rows of ``Surface.stencil()``; its row layout)
    """
    patch, u, v = footpoints.patch, footpoints.u, footpoints.v
    rows, cols, vals = [], [], []
    for degree, mask in ((2, patch < n_quad), (3, patch >= n_quad)):
        samples = np.nonzero(mask)[0]
        if samples.size == 0:
            continue
        bu, bv = bernstein_columns(degree, u[samples]), bernstein_columns(degree, v[samples])
        n = degree + 1
        first = 9 * patch[samples] if degree == 2 else 9 * n_quad + 16 * (patch[samples] - n_quad)
        for i in range(n):
            for j in range(n):
                rows.append(samples)
                cols.append(first + n * i + j)
                vals.append(bu[i] * bv[j])
    m = patch.size
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, n_rows))


def umbrella_laplacian(edges: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    """(V, V) csr_matrix L: (L X)_v = X_v minus the mean of its neighbours (zero row for a lone vertex).

    Parameters
    ----------
    edges : (k, 2) int, undirected edges of the control mesh (each once or twice: duplicates are merged)
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    a, b = np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]]
    adjacency = sp.csr_matrix((np.ones(a.size), (a, b)), shape=(n_vertices, n_vertices))
    adjacency.data[:] = 1.0  # duplicates summed: count each neighbour once
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    inverse = np.divide(1.0, degree, out=np.zeros_like(degree), where=degree > 0)
    return (sp.diags((degree > 0).astype(float)) - sp.diags(inverse) @ adjacency).tocsr()


def vertex_normals(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(m, 3) float: area-weighted unit vertex normals of a triangle mesh (zero where undefined)."""
    p = np.asarray(points, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    face = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])  # twice the area, along the normal
    normals = np.zeros_like(p)
    for k in range(3):
        np.add.at(normals, t[:, k], face)
    length = np.linalg.norm(normals, axis=1)
    return np.divide(normals, length[:, None], out=np.zeros_like(normals), where=length[:, None] > 0)


def normal_equations(A: sp.csr_matrix, samples: np.ndarray, normals: np.ndarray, fair: sp.spmatrix,
                     current: np.ndarray, plane, point):
    """N (3V, 3V) csr_matrix, symmetric positive definite, and b (3V,): the round's normal equations.

    Parameters
    ----------
    A : (m, V) csr_matrix, basis rows times stencil
    samples : (m, 3) float, the scan points; normals : (m, 3) float, their unit normals
    fair : (V, V) sparse, symmetric positive semi-definite, the fairness form with its weight in
        (``fairness / V  L^T L`` of ``umbrella_laplacian``, or ``fairness / P  K`` of ``thin_plate``), applied to
        each coordinate
    current : (V, 3) float, the control points now (the damping's anchor)
    plane, point : float or (m,) float, the weights of ``FitOptions`` (a weight per sample: the scan's rim
        vertices pull harder, ``iterate.sample_point_weights``)
    """
    m, n_vertices = A.shape
    plane_weight = np.broadcast_to(np.asarray(plane, dtype=np.float64), (m,))
    point_weight = np.broadcast_to(np.asarray(point, dtype=np.float64), (m,))
    # block (c, d) of N's data part: A^T diag(plane n_c n_d + point [c = d]) A / m (six products, A has
    # about ten entries a row), placed at rows 3 a + c, columns 3 b + d
    blocks = {}
    AT = A.T.tocsr()
    row_of_entry = np.repeat(np.arange(m), np.diff(A.indptr))
    for c in range(3):
        for d in range(c, 3):
            weight = (plane_weight / m) * normals[:, c] * normals[:, d] + (point_weight / m if c == d else 0.0)
            scaled = sp.csr_matrix((A.data * weight[row_of_entry], A.indices, A.indptr), shape=A.shape)
            blocks[c, d] = (AT @ scaled).tocoo()
    fair = sp.coo_matrix(fair)
    rows, cols, vals = [], [], []
    for c in range(3):
        for d in range(3):
            block = blocks[min(c, d), max(c, d)]
            block_rows, block_cols = (block.row, block.col) if c <= d else (block.col, block.row)
            rows += [3 * block_rows + c, 3 * fair.row + c] if c == d else [3 * block_rows + c]
            cols += [3 * block_cols + d, 3 * fair.col + d] if c == d else [3 * block_cols + d]
            vals += [block.data, fair.data] if c == d else [block.data]
    N = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(3 * n_vertices, 3 * n_vertices))
    offset = np.einsum("ij,ij->i", normals, samples)
    b = (AT @ (normals * (plane_weight * offset / m)[:, None]) + AT @ (samples * (point_weight / m)[:, None])).ravel()
    damping = DAMPING * float(N.diagonal().mean())
    N = (N + damping * sp.identity(3 * n_vertices, format="csr")).tocsr()
    b = b + damping * np.asarray(current, dtype=np.float64).ravel()
    return N, b
