"""Step A1's perturbation of the B points of even holes with n > 4, as a sparse matrix."""
from __future__ import annotations

import numpy as np

from ...arrays import unique_integers
from ...mesh.halfedges import HalfEdgeMesh
from ..refine.holes import HoleGroup


def perturbation_matrix(mesh: HalfEdgeMesh, holes: list[HoleGroup]):
    """Step A1's perturbation of the B points of even holes with n > 4.

    Each such hole needs the alternating sum r . B = sum_ij (-1)^(i+j) B_ij to
    vanish. The paper corrects each hole alone; holes can share B points
    (NOTES, item 4), so this takes the least-norm joint correction
    dB = -A^+ (A B), which is the paper's rule for an isolated hole.

    Returns
    -------
    (V, V) csr_matrix ``I - A^T (A A^T)^-1 A``, or None when no hole needs it.
    Its entries: (2n)^2 for an isolated n-sided hole (``PerturbationStep`` applies it in O(n)).
    """
    parts = perturbation_parts(mesh, holes)
    if parts is None:
        return None
    from scipy.sparse import identity

    constraints, inverse_gram = parts
    return (identity(mesh.n_vertices, format="csr") - constraints.T @ (inverse_gram @ constraints)).tocsr()


def perturbation_parts(mesh: HalfEdgeMesh, holes: list[HoleGroup]):
    """(A (m, V) csr_matrix, (A A^T)^-1 (m, m) csr_matrix) of ``perturbation_matrix``, or None when no hole needs it.

    A has a row of 2n entries per even hole (n > 4); A A^T is made of tiny blocks (``block_diagonal_inverse``).
    """
    rows, cols, vals = [], [], []
    count = 0
    for g in holes:
        if g.n % 2 or g.n <= 4 or g.dart:  # a dart's hole needs none (construction.stencils.holes.dart)
            continue
        k = g.cells.size
        sign = np.where(np.arange(g.n) % 2 == 0, 1.0, -1.0)
        hole = count + np.arange(k)[:, None]
        rows += [np.broadcast_to(hole, (k, g.n)).ravel()] * 2
        cols += [g.B1.ravel(), g.B2.ravel()]
        vals += [np.broadcast_to(sign, (k, g.n)).ravel(), np.broadcast_to(-sign, (k, g.n)).ravel()]
        count += k
    if count == 0:
        return None
    from scipy.sparse import coo_matrix  # even holes only

    constraints = coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(count, mesh.n_vertices)
    ).tocsr()
    constraints.sum_duplicates()
    return constraints, block_diagonal_inverse((constraints @ constraints.T).tocoo())


class PerturbationStep:
    """Step A1's perturbation as a stage (``construction.stages.Stage``), factored:
    ``x - A^T ((A A^T)^-1 (A x))``, O(n) per n-sided hole where ``perturbation_matrix`` holds (2n)^2 entries.

    The stages use it when some even hole has many sides (``stages.perturbation_stage``); its matrix is made
    when asked for (``Surface.stencil``). Parameters: the (A, (A A^T)^-1) of ``perturbation_parts``, and
    ``left`` (V, V) csr_matrix or None: the map is then ``x - left A^T (G (A x))`` (C0 creases: ghost partners
    move opposite to their real points, ``creases.mirror_perturbation_left``).
    """

    name = "perturbation"
    mixes_coordinates = False

    def __init__(self, constraints, inverse_gram, left=None):
        self.constraints, self.inverse_gram, self.left = constraints, inverse_gram, left
        self.shape = (constraints.shape[1], constraints.shape[1])
        self._matrix = None

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(V, d) perturbed points from (V, d) ``points``."""
        correction = self.constraints.T @ (self.inverse_gram @ (self.constraints @ points))
        return points - (correction if self.left is None else self.left @ correction)

    def matrix(self):
        """(V, V) csr_matrix, ``perturbation_matrix``'s (mirrored: ``creases.mirror_perturbation``'s), built on
        the first call and kept."""
        if self._matrix is None:
            from scipy.sparse import identity

            delta = self.constraints.T @ (self.inverse_gram @ self.constraints)
            delta = delta if self.left is None else self.left @ delta
            self._matrix = (identity(self.shape[0], format="csr") - delta).tocsr()
        return self._matrix


def block_diagonal_inverse(matrix):
    """Inverse of a sparse symmetric matrix made of small diagonal blocks.

    Even holes couple only where they share B points, so A A^T splits into
    tiny blocks (almost all 1 x 1). Blocks of one size are inverted together.

    Parameters
    ----------
    matrix : (m, m) coo_matrix

    Returns
    -------
    (m, m) csr_matrix
    """
    from scipy.sparse import csr_matrix  # only for even holes (0.4 s to import)
    from scipy.sparse.csgraph import connected_components

    m = matrix.shape[0]
    _, label = connected_components(matrix, directed=False)
    order = np.argsort(label, kind="stable")
    sizes = np.bincount(label)
    start = np.concatenate([[0], np.cumsum(sizes)])
    position = np.empty(m, dtype=np.int64)
    position[order] = np.arange(m) - start[label[order]]
    rows, cols, vals = [], [], []
    for size in unique_integers(sizes):
        components = np.flatnonzero(sizes == size)
        slot = np.full(sizes.size, -1)
        slot[components] = np.arange(components.size)
        blocks = np.zeros((components.size, size, size))
        keep = sizes[label[matrix.row]] == size
        r, c = matrix.row[keep], matrix.col[keep]
        np.add.at(blocks, (slot[label[r]], position[r], position[c]), matrix.data[keep])
        inverse = np.linalg.inv(blocks)
        members = order[start[components][:, None] + np.arange(size)]  # (k, size) global indices
        rows.append(np.repeat(members, size, axis=1).ravel())
        cols.append(np.tile(members, (1, size)).ravel())
        vals.append(inverse.ravel())
    return csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, m))
