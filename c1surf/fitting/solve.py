"""Solvers of the normal equations N x = b (symmetric positive definite, sparse, 3V unknowns).

Measured on spot (180-face control mesh, 2 refinements, 69k-vertex scan) and fish (see the
commit message and ``iterate``): the sparse Cholesky factorisation of ``cholespy`` (CHOLMOD's
supernodal code, pip wheels) is the fastest and exact; SuperLU (scipy) with the symmetric
ordering is exact and the fallback when cholespy is missing; warm-started conjugate gradients
(Jacobi preconditioner, from the current points) needs no factorisation but many iterations on the
ill-conditioned systems of fine control meshes.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["solve", "available_solver"]


CG_TOLERANCE = 1e-12


def _coordinate_preconditioner(N: sp.csr_matrix):
    """kron(M, I_3)^-1 as a LinearOperator, M the mean of N's three (V, V) coordinate blocks, factored once
    (cholespy; without it the diagonal of N): the point-to-plane coupling is all it leaves to the iterations,
    and M has a ninth of N's entries and far less fill."""
    from scipy.sparse.linalg import LinearOperator

    n = N.shape[0]
    try:
        from cholespy import CholeskySolverD, MatrixType
    except ImportError:
        inverse = 1.0 / N.diagonal()
        return LinearOperator((n, n), matvec=lambda r: inverse * r.ravel())
    M = ((N[0::3, 0::3] + N[1::3, 1::3] + N[2::3, 2::3]) / 3).tocsr()
    factor = CholeskySolverD(M.shape[0], M.indptr.astype(np.int32), M.indices.astype(np.int32),
                             np.ascontiguousarray(M.data, dtype=np.float64), MatrixType.CSR)

    def apply(r):
        out = np.zeros((M.shape[0], 3))
        factor.solve(np.array(r, dtype=np.float64).reshape(-1, 3), out)
        return out.ravel()

    return LinearOperator((n, n), matvec=apply)


def available_solver(name: str) -> str:
    """The solver ``name`` ("auto": cholesky when cholespy imports, else superlu) resolves to."""
    if name != "auto":
        return name
    try:
        import cholespy  # noqa: F401
    except ImportError:
        return "superlu"
    return "cholesky"


def solve(N: sp.csr_matrix, b: np.ndarray, start: np.ndarray, method: str = "auto") -> np.ndarray:
    """x with N x = b.

    Parameters
    ----------
    N : (n, n) sparse, symmetric positive definite; b : (n,) float
    start : (n,) float, the warm start of "cg"
    method : "auto", "cholesky", "superlu" or "cg"

    Returns
    -------
    (n,) float
    """
    method = available_solver(method)
    if method == "cholesky":
        from cholespy import CholeskySolverD, MatrixType

        csr = sp.csr_matrix(N)
        solver = CholeskySolverD(csr.shape[0], csr.indptr.astype(np.int32), csr.indices.astype(np.int32),
                                 np.ascontiguousarray(csr.data, dtype=np.float64), MatrixType.CSR)
        x = np.zeros(csr.shape[0])
        solver.solve(np.ascontiguousarray(b, dtype=np.float64), x)
        return x
    if method == "superlu":
        from scipy.sparse.linalg import splu

        return splu(sp.csc_matrix(N), permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True}).solve(b)
    if method == "cg":
        from scipy.sparse.linalg import LinearOperator, cg

        x, info = cg(N, b, x0=start, rtol=CG_TOLERANCE, atol=0.0, maxiter=20 * N.shape[0],
                     M=_coordinate_preconditioner(N))
        return x
    raise ValueError(f"unknown solver {method!r}")
