"""The thin-plate energy of a surface of Bezier patches, exactly, as a quadratic form in its control points.

For one tensor-product Bezier patch S(u, v) = sum_ij c_ij B_i(u) B_j(v) of degree n (n = 2: the biquadratic
patches, 3: the bicubic hole patches) the parametric thin-plate energy

    E(S) = integral over [0, 1]^2 of |S_uu|^2 + 2 |S_uv|^2 + |S_vv|^2 du dv

is c^T G c per coordinate, with c the ((n + 1)^2,) coefficients (row-major: c[(n + 1) i + j] = c_ij, i along
u, the layout of ``Surface.stencil()``) and G the constant Gram matrix

    G = K2 (x) M0 + 2 K1 (x) K1 + M0 (x) K2,      Kr = Dr^T M_{n-r} Dr

where M_k is the Bernstein mass matrix of degree k (integral of B_a^k B_b^k = C(k, a) C(k, b) / ((2k + 1)
C(2k, a + b))) and Dr the r-th difference operator (Bernstein coefficients of degree n to those of the r-th
derivative, degree n - r: n! / (n - r)! times the forward differences). Every entry is a rational number,
computed once in exact fractions (``gram_matrix``).

Through the stencil (patch coefficients = S @ control points, ``Surface.stencil()``, (R, V)) the energy of the
whole surface is X^T K X per coordinate with K = S^T blockdiag(w_p G_p) S (``thin_plate_matrix``, sparse
(V, V), built by sparse products: never a dense matrix of the mesh's size); ``thin_plate_energy`` applies the
same form to patch arrays directly (the per-patch sum, no stencil).

Per-patch weights w_p: the parametric energy of a patch that spans a piece of surface of size h with
curvature k is about h^4 k^2 (S_uu ~ h^2 k) while the geometric thin-plate energy (the integral of k^2 over
the area) is about h^2 k^2: a patch's parametric energy is its geometric one times its area. ``patch_weights``
gives w_p = (mean patch area) / (area of patch p), which makes the sum the geometric energy times the mean
patch area: the same as the unweighted sum on a uniform mesh, scale-aware on an adaptive one.
"""
from __future__ import annotations

from fractions import Fraction
from functools import lru_cache
from math import comb

import numpy as np
import scipy.sparse as sp

__all__ = ["gram_matrix", "thin_plate_matrix", "thin_plate_energy", "patch_areas", "patch_weights"]


def _mass(k: int) -> list:
    """(k + 1, k + 1) Fractions: the integrals over [0, 1] of B_a^k B_b^k."""
    return [[Fraction(comb(k, a) * comb(k, b), (2 * k + 1) * comb(2 * k, a + b)) for b in range(k + 1)]
            for a in range(k + 1)]


def _difference(n: int, r: int) -> list:
    """(n - r + 1, n + 1) Fractions D: the Bernstein coefficients of the r-th derivative are D @ c."""
    scale = Fraction(1)
    for k in range(r):
        scale *= n - k
    return [[scale * (-1) ** (r - (b - a)) * comb(r, b - a) if 0 <= b - a <= r else Fraction(0)
             for b in range(n + 1)] for a in range(n - r + 1)]


def _product(a: list, b: list) -> list:
    return [[sum((a[i][k] * b[k][j] for k in range(len(b))), Fraction(0)) for j in range(len(b[0]))]
            for i in range(len(a))]


def _transpose(a: list) -> list:
    return [list(row) for row in zip(*a)]


def _derivative_gram(n: int, r: int) -> list:
    """(n + 1, n + 1) Fractions: integral over [0, 1] of (d^r/du^r B_a^n)(d^r/du^r B_b^n)."""
    D = _difference(n, r)
    return _product(_transpose(D), _product(_mass(n - r), D))


@lru_cache(maxsize=None)
def gram_matrix(degree: int) -> np.ndarray:
    """((degree + 1)^2, (degree + 1)^2) float G, symmetric positive semi-definite: c^T G c is the thin-plate
    energy of a patch of ``degree`` (2 or 3) with coefficients c (row-major, i along u); exact fractions rounded
    once to float. Its null space is the bilinear patches' (the affine ones and c_11 u v)."""
    if degree < 2:
        raise ValueError(f"the thin-plate energy needs patches of degree >= 2, got {degree}")
    K0, K1, K2 = (_derivative_gram(degree, r) for r in range(3))
    size = degree + 1
    G = np.zeros((size * size, size * size))
    for i in range(size):
        for j in range(size):
            for k in range(size):
                for m in range(size):
                    value = K2[i][k] * K0[j][m] + 2 * K1[i][k] * K1[j][m] + K0[i][k] * K2[j][m]
                    G[size * i + j, size * k + m] = float(value)
    G.setflags(write=False)
    return G


def _block_diagonal(n_quad: int, n_cubic: int, weights: np.ndarray | None) -> sp.csr_matrix:
    """(R, R) csr_matrix blockdiag(w_p G_p), R = 9 Nq + 16 Nc (the stencil's row layout)."""
    w = np.ones(n_quad + n_cubic) if weights is None else np.asarray(weights, dtype=np.float64)
    if w.shape != (n_quad + n_cubic,):
        raise ValueError(f"expected {n_quad + n_cubic} patch weights, got shape {w.shape}")
    blocks = [sp.kron(sp.diags(w[:n_quad]), sp.csr_matrix(gram_matrix(2))),
              sp.kron(sp.diags(w[n_quad:]), sp.csr_matrix(gram_matrix(3)))]
    return sp.block_diag([b for b, n in zip(blocks, (n_quad, n_cubic)) if n > 0], format="csr")


def thin_plate_matrix(stencil: sp.spmatrix, n_quad: int, n_cubic: int,
                      weights: np.ndarray | None = None) -> sp.csr_matrix:
    """(V, V) csr_matrix K = S^T blockdiag(w_p G_p) S, symmetric positive semi-definite: sum over the
    coordinates of X[:, c]^T K X[:, c] is the surface's (weighted) thin-plate energy at control points X (V, d).

    Parameters
    ----------
    stencil : (R, V) sparse, ``Surface.stencil()`` (R = 9 Nq + 16 Nc: biquadratic rows first)
    n_quad, n_cubic : int, Nq and Nc
    weights : (Nq + Nc,) float or None (all 1), a weight per patch (``patch_weights``)
    """
    S = sp.csr_matrix(stencil)
    if S.shape[0] != 9 * n_quad + 16 * n_cubic:
        raise ValueError(f"the stencil has {S.shape[0]} rows, {n_quad} biquadratic and {n_cubic} bicubic patches "
                         f"need {9 * n_quad + 16 * n_cubic}")
    K = (S.T @ (_block_diagonal(n_quad, n_cubic, weights) @ S)).tocsr()
    return ((K + K.T) * 0.5).tocsr()  # symmetric to the last bit (the products round differently)


def thin_plate_energy(biquadratic: np.ndarray, bicubic: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """(Nq + Nc,) float: each patch's thin-plate energy (times its weight), summed over the coordinates.

    Parameters
    ----------
    biquadratic : (Nq, 3, 3, d) float; bicubic : (Nc, 4, 4, d) float (the surface's patch arrays)
    weights : (Nq + Nc,) float or None
    """
    energies = []
    for coefficients, degree in ((biquadratic, 2), (bicubic, 3)):
        c = np.asarray(coefficients, dtype=np.float64)
        c = c.reshape(c.shape[0], (degree + 1) ** 2, c.shape[-1])
        energies.append(np.einsum("pad,ab,pbd->p", c, gram_matrix(degree), c, optimize=True))
    energy = np.concatenate(energies)
    return energy if weights is None else energy * np.asarray(weights, dtype=np.float64)


def patch_areas(biquadratic: np.ndarray, bicubic: np.ndarray) -> np.ndarray:
    """(Nq + Nc,) float: each patch's area estimated from its corner coefficients (half the cross product of
    the diagonals of the corner quadrilateral; exact for a planar bilinear patch)."""
    areas = []
    for c in (np.asarray(biquadratic, dtype=np.float64), np.asarray(bicubic, dtype=np.float64)):
        a, b, d, e = c[:, 0, 0, :3], c[:, -1, 0, :3], c[:, -1, -1, :3], c[:, 0, -1, :3]
        areas.append(0.5 * np.linalg.norm(np.cross(d - a, e - b), axis=1))
    return np.concatenate(areas)


def patch_weights(biquadratic: np.ndarray, bicubic: np.ndarray) -> np.ndarray:
    """(Nq + Nc,) float w_p = mean area / area_p (module docstring): the thin-plate sum then approximates the
    geometric energy (the integral of the squared curvature over the area) times the mean patch area. A patch
    of (nearly) zero area gets at most 1,000, not infinity."""
    area = patch_areas(biquadratic, bicubic)
    mean = float(area.mean()) if area.size else 1.0
    floor = 1e-3 * mean
    return mean / np.maximum(area, floor if mean > 0 else 1.0)

