"""Extension A1a: a surface through the input vertices, optionally with given normals there.

**Positions** (the paper's A1a). After the first refinement the points C_i
made at input vertex S (the corners of S's V-cell) move by ``S - mean(C_i)``.
The V-cell then has centroid S, the second step keeps centroids, and the
twice-refined cell made from it has centroid S as well: for valence n != 4
that cell is a hole whose bicubic patches meet at its centroid (P_33 = S with
beta = 0); for valence 4 it is a quad, and the centroid of a quad is the
common corner of the four biquadratic patches around it (A2). Either way the
surface passes through S. The move is linear in the points: the first step
becomes ``(I - G) M1 + E`` (G averages over each V-cell, E picks the vertex).

**Normals** ("similarly one can interpolate normals", A1a). The tangent plane
at S is spanned by the first Fourier mode of the tangent data around the cell:
for a quad cell (valence 4) the corners C_l themselves, for a hole the
coefficients P_31,l (A3, which also involve the B points) or
(C_l + C_{l+1}) / 2 (A3a). So c1surf moves, after the second step and the
perturbation, the cell's corners C_l along the normal n by amounts t_l that
are a pure first Fourier mode chosen to cancel that mode's component along n.
A pure first mode sums to zero, so the centroid (S) stays; the C_l are no
input to the perturbation, so G1 is untouched; and for fixed normals the move
is linear in the points. It mixes the coordinates, so its matrix acts on the
flattened points (``NormalConstraint.matrix``), not row by row; on rational
surfaces it is linear for fixed weights. Needs alpha > 0 (alpha = 0 gives a
singular point at S, without tangent plane).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...arrays import unique_integers
from ...mesh.halfedges import HalfEdgeMesh
from ..refine.doo_sabin import FACE_FROM_VERTEX, RefinedFaces
from ..refine.holes import cell_neighbourhood


def vertex_interpolation_step(step1, coarse: HalfEdgeMesh, faces1: RefinedFaces, only: np.ndarray | None = None):
    """First Doo-Sabin step followed by A1a's move: every V-cell gets its vertex as centroid.

    Parameters
    ----------
    step1 : (H, V) csr_matrix, the first refinement step (``doo_sabin_matrix``)
    coarse : HalfEdgeMesh with V vertices and H half-edges
    faces1 : RefinedFaces of ``coarse``
    only : (V,) bool or None, the vertices to interpolate (None: all; sharp corners use it,
        ``stages.first_step_stage``)

    Returns
    -------
    (H, V) csr_matrix ``(I - G) step1 + E``
    """
    return vertex_interpolation_parts(step1, coarse, faces1, only)[0]


def vertex_interpolation_parts(step1, coarse: HalfEdgeMesh, faces1: RefinedFaces, only: np.ndarray | None = None,
                               large: int | None = None):
    """``vertex_interpolation_step`` with the V-cells of more than ``large`` sides kept in O(n) entries.

    G averages the rows of each V-cell's corners: n^2 entries for an n-sided cell in ``(I - G) step1``.
    A cell of more than ``large`` sides instead gets the mean of its corners' rows as a point of its own
    (a row of ``means``), and its corners take minus that point.

    Returns
    -------
    out : (H, C + M) csr_matrix on [points (the C columns of ``step1``); the M means]
    means : (M, C) csr_matrix or None (no such cell; then ``out`` is ``vertex_interpolation_step``'s)
    """
    from scipy.sparse import csr_matrix, hstack, identity  # A1a only: the usual conversion imports no scipy.sparse

    offsets = np.concatenate([[0], np.cumsum(faces1.face_sizes)])
    rows, cols, vals = [], [], []
    sel_rows = []
    big_rows, big_cells, big_vals, n_big = [], [], [], 0
    chosen = faces1.kind == FACE_FROM_VERTEX
    if only is not None:
        chosen &= only[np.where(chosen, faces1.parent, 0)]
    for n in unique_integers(faces1.face_sizes[chosen]):
        cells = np.flatnonzero(chosen & (faces1.face_sizes == n))
        corners = faces1.face_vertices[offsets[cells][:, None] + np.arange(n)]  # (k, n) once-refined vertices
        sel_rows.append(corners.ravel())
        if large is not None and n > large:
            big_rows.append(corners.ravel())
            big_cells.append(np.repeat(n_big + np.arange(cells.size), n))
            n_big += cells.size
            big_vals.append(np.full(corners.size, 1.0 / n))
            continue
        rows.append(np.repeat(corners, n, axis=1).ravel())
        cols.append(np.tile(corners, (1, n)).ravel())
        vals.append(np.full(corners.size * n, 1.0 / n))
    h = coarse.n_halfedges
    if not sel_rows:
        return step1, None
    average = csr_matrix((np.concatenate(vals or [np.zeros(0)]), (np.concatenate(rows or [np.zeros(0, int)]),
                                                                   np.concatenate(cols or [np.zeros(0, int)]))),
                         shape=(h, h))
    moved = np.concatenate(sel_rows)
    # (columns: the step's: V, or V + L with the large faces' centroids, ``doo_sabin.doo_sabin_augmented``)
    pick = csr_matrix((np.ones(moved.size), (moved, coarse.origin[moved])), shape=(h, step1.shape[1]))
    out = ((identity(h, format="csr") - average) @ step1 + pick).tocsr()
    means = None
    if big_rows:
        big_rows, big_cells, big_vals = (np.concatenate(x) for x in (big_rows, big_cells, big_vals))
        means = (csr_matrix((big_vals, (big_cells, big_rows)), shape=(n_big, h)) @ step1).tocsr()
        spread = csr_matrix((-np.ones(big_rows.size), (big_rows, big_cells)), shape=(h, n_big))
        out = hstack([out, spread], format="csr")
    out.sum_duplicates()
    out.eliminate_zeros()
    return out, means


@dataclass(frozen=True)
class _CellGroup:
    """Cells of one size n whose tangent plane at the centre is prescribed."""

    n: int
    C: np.ndarray  # (k, n) refined vertices, cell corners in order
    B1: np.ndarray | None  # (k, n) or None (the tangent datum does not use the B points)
    B2: np.ndarray | None
    normals: np.ndarray  # (k, 3) unit
    u: float  # weight of B_{l,2} + B_{l+1,1} in the tangent datum q_l
    w: float  # weight of C_l + C_{l+1}; 0 means q_l = C_l

    def phases(self) -> np.ndarray:
        """(n,) complex, e^{i theta l}: the first Fourier mode around the cell."""
        theta = 2 * np.pi / self.n
        return np.exp(1j * theta * np.arange(self.n))

    def factor(self) -> complex:
        """First Fourier coefficient of q per unit first mode of the corners' moves."""
        theta = 2 * np.pi / self.n
        return 1.0 if self.w == 0.0 else self.w * (1 + np.exp(-1j * theta))

    def local_points(self) -> np.ndarray:
        """(k, m) int: the points q reads, [C] or [C, B1, B2]."""
        return self.C if self.u == 0.0 else np.concatenate([self.C, self.B1, self.B2], axis=1)

    def datum_weights(self) -> np.ndarray:
        """(n, m) float: q_l as weights on ``local_points``."""
        n, l = self.n, np.arange(self.n)
        Q = np.zeros((n, n if self.u == 0.0 else 3 * n))
        if self.w == 0.0:
            Q[l, l] = 1.0
            return Q
        Q[l, l] += self.w
        Q[l, (l + 1) % n] += self.w
        if self.u != 0.0:
            Q[l, 2 * n + l] += self.u  # B_{l,2}
            Q[l, n + (l + 1) % n] += self.u  # B_{l+1,1}
        return Q


class NormalConstraint:
    """A1a's vertex normals as a stage (``construction.stages.Stage``) on the refined points.

    Moves cell corners along given normals so the surface's normal at the cell
    centre is n. Built once per topology; ``apply(x)`` works on refined points
    (columns: 3 positions, then any extra columns, then the homogeneous weight
    when ``rational``). It mixes the coordinates (``mixes_coordinates``), so its
    matrix acts on flattened points.
    """

    mixes_coordinates = True

    def __init__(self, groups: list[_CellGroup], rational: bool, n_points: int, name: str = "vertex_normals"):
        self.name = name
        self.groups = groups
        self.rational = rational
        self.n_points = n_points
        self.shape = (n_points, n_points)
        self._matrices = {}

    def apply(self, x: np.ndarray) -> np.ndarray:
        """(N, D) refined points with the cell corners moved (a copy)."""
        x = np.array(x, dtype=np.float64, copy=True)
        for g in self.groups:
            phase = g.phases()
            if g.w == 0.0:
                q = x[g.C]  # (k, n, d)
            else:
                q = g.w * (x[g.C] + x[np.roll(g.C, -1, axis=1)])
                if g.u != 0.0:
                    q = q + g.u * (x[g.B2] + x[np.roll(g.B1, -1, axis=1)])
            depth = np.einsum("kld,kd->kl", q[..., :3], g.normals)
            if self.rational:
                centre = x[g.C].mean(axis=1)
                s = centre[:, :3] / centre[:, -1:]
                depth = depth - np.einsum("kd,kd->k", s, g.normals)[:, None] * q[..., -1]
            Y = depth @ phase  # (k,) first Fourier mode of the depths
            T = -Y / g.factor()
            t = (2.0 / g.n) * np.real(T[:, None] * np.conj(phase)[None, :])  # (k, n), a pure first mode
            x[g.C, :3] += t[..., None] * g.normals[:, None, :]
        return x

    def matrix(self, columns: int = 3, weights: np.ndarray | None = None):
        """(N columns, N columns) csr_matrix M with ``apply(x).ravel() == M @ x.ravel()``.

        Parameters
        ----------
        columns : int, the columns of x (3 positions first)
        weights : (N,) float, x's last column (the homogeneous weights), needed when
            ``rational``: the map is linear for fixed weights. Matrices without
            weights are built once and kept.
        """
        if self.rational and weights is None:
            raise ValueError("a rational surface's normal constraint is linear for fixed weights: pass them")
        if not self.rational and columns in self._matrices:
            return self._matrices[columns]
        from scipy.sparse import identity

        size = self.n_points * columns
        matrix = identity(size, format="csr")
        for g in self.groups:
            matrix = matrix + _moves_matrix(g, columns, weights, size)
        if not self.rational:
            self._matrices[columns] = matrix
        return matrix


def _moves_matrix(g: _CellGroup, columns: int, weights: np.ndarray | None, size: int):
    """The corners' moves of one cell group as a sparse matrix on the flattened points.

    With q = Q x[local] the tangent datum, depth_m = n . q_m (minus (n . s) q_m,w with
    s the centre over its weight, rational), and the moves t = coef @ depth along n,
    where coef[l, m] = (2 / n) Re(-e^{i theta (m - l)} / factor) (see ``apply``).
    """
    from scipy.sparse import csr_matrix

    phase = g.phases()
    coef = (2.0 / g.n) * np.real(-(np.conj(phase)[:, None] * phase[None, :]) / g.factor())  # (n, n)
    local, Q = g.local_points(), g.datum_weights()  # (k, m), (n, m)
    R = np.broadcast_to(Q, (local.shape[0],) + Q.shape)
    if weights is not None:  # - (n . s) q_w with s = mean(x[C])[:3] / mean(x[C])_w: linear in x for fixed weights
        q_weight = np.einsum("mj,kj->km", Q, weights[local])
        centre_weight = weights[g.C].mean(axis=1)
        on_corner = np.zeros(local.shape[1])
        on_corner[: g.n] = 1.0 / g.n
        R = R - (q_weight / centre_weight[:, None])[:, :, None] * on_corner[None, None, :]
    M = np.einsum("lm,kmj->klj", coef, R)  # (k, n, m): t_l per unit of n . x[local_j]
    xyz = np.arange(3)
    rows = g.C[:, :, None, None, None] * columns + xyz[None, None, :, None, None]
    cols = local[:, None, None, :, None] * columns + xyz[None, None, None, None, :]
    vals = g.normals[:, None, :, None, None] * M[:, :, None, :, None] * g.normals[:, None, None, None, :]
    rows, cols, vals = (a.ravel() for a in np.broadcast_arrays(rows, cols, vals))
    return csr_matrix((vals, (rows, cols)), shape=(size, size))


def normal_constraint(refined: HalfEdgeMesh, faces1: RefinedFaces, normals: np.ndarray, tangent_datum, rational: bool) -> NormalConstraint | None:
    """The ``NormalConstraint`` for the coarse vertices that have a normal.

    Parameters
    ----------
    refined : the twice-refined HalfEdgeMesh (its F-cell g is made from once-refined cell g)
    faces1 : RefinedFaces of the first step
    normals : (V, 3) float per coarse vertex, NaN rows where none is given
    tangent_datum : callable n -> (u, w), the tangent datum of n-sided holes (``HoleRules.tangent_datum``)
    rational : points carry a homogeneous weight as last column
    """
    normals = np.asarray(normals, dtype=np.float64)
    vertex_cells = np.flatnonzero(faces1.kind == FACE_FROM_VERTEX)
    given = np.all(np.isfinite(normals[faces1.parent[vertex_cells]]), axis=1)
    cells = vertex_cells[given]
    if cells.size == 0:
        return None
    groups = []
    for n in unique_integers(refined.face_sizes[cells]):
        mine = cells[refined.face_sizes[cells] == n]
        h = refined.face_offsets[mine][:, None] + np.arange(n)
        nv = normals[faces1.parent[mine]]
        length = np.linalg.norm(nv, axis=1, keepdims=True)
        if np.any(length == 0):
            raise ValueError("a vertex normal has length zero")
        nv = nv / length
        u, w = (0.0, 0.0) if n == 4 else tangent_datum(int(n))  # a quad cell's corners are its tangent datum
        B1 = B2 = None
        if u != 0.0:
            _, B1, B2, _, _, _ = cell_neighbourhood(refined, h)
        groups.append(_CellGroup(int(n), refined.origin[h], B1, B2, nv, u, w))
    return NormalConstraint(groups, rational, refined.n_vertices)
