"""Solvers of the normal equations N x = b (symmetric positive definite, sparse, 3V unknowns).

Measured (issue 29) on spot's scan split once (46,126 vertices) against spot's control mesh split into
quads once and twice (734 and 2,930 vertices, one refinement step), 10 rounds, on a loaded 2-core
machine (load average ~10, so the seconds are high, the ratios meaningful):

=========================  ===========  ===========
solver, 10 solves           V = 734      V = 2,930
=========================  ===========  ===========
SuperLU (MMD on A^T + A)    8.6 s        37-45 s for one solve
cholespy (CHOLMOD)          1.4 s        12.8 s
CG, warm start, Jacobi      1.1 s        5.9 s
=========================  ===========  ===========

One solve of the V = 2,930 system at rtol 1e-12: Jacobi CG 0.43-0.58 s (295 iterations), CG
preconditioned by the Cholesky factor of the mean coordinate block kron(M, I3) 0.53-0.55 s (103
iterations): the fill of a factorisation of this 2-ring-coupled, 3-coordinate system costs more
than the iterations it saves. So "auto" is conjugate gradients with the Jacobi preconditioner,
warm-started at the current control points (scipy only); "cholesky" (needs ``cholespy``, not a
dependency) and "superlu" stay for comparison and as exact references.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["solve", "available_solver", "CG_TOLERANCE"]

CG_TOLERANCE = 1e-12  # relative residual: the fitted points to about 1e-10 of the model's size


def available_solver(name: str) -> str:
    """The solver ``name`` resolves to ("auto": "cg")."""
    return "cg" if name == "auto" else name


def solve(N: sp.csr_matrix, b: np.ndarray, start: np.ndarray, method: str = "auto") -> np.ndarray:
    """x with N x = b.

    Parameters
    ----------
    N : (n, n) sparse, symmetric positive definite; b : (n,) float
    start : (n,) float, the warm start of "cg" (the current control points, raveled)
    method : "auto", "cg", "cholesky" (``cholespy``) or "superlu"

    Returns
    -------
    (n,) float (NaN where a factorisation broke down: the caller checks)
    """
    method = available_solver(method)
    if method == "cg":
        from scipy.sparse.linalg import cg

        diagonal = N.diagonal()
        x, _ = cg(N, b, x0=start, rtol=CG_TOLERANCE, atol=0.0, maxiter=20 * N.shape[0],
                  M=sp.diags(1.0 / diagonal))
        return x
    if method == "cholesky":
        try:
            from cholespy import CholeskySolverD, MatrixType
        except ImportError:
            raise ValueError("the 'cholesky' solver needs the cholespy package (pip install cholespy)") from None
        csr = sp.csr_matrix(N)
        solver = CholeskySolverD(csr.shape[0], csr.indptr.astype(np.int32), csr.indices.astype(np.int32),
                                 np.ascontiguousarray(csr.data, dtype=np.float64), MatrixType.CSR)
        x = np.zeros(csr.shape[0])
        solver.solve(np.ascontiguousarray(b, dtype=np.float64), x)
        return x
    if method == "superlu":
        from scipy.sparse.linalg import splu

        return splu(sp.csc_matrix(N), permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True}).solve(b)
    raise ValueError(f"unknown solver {method!r}")
