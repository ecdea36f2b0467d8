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
is linear in the points (it mixes the coordinates, so it is applied as a
function, not a sparse row operator). Needs alpha > 0 (alpha = 0 gives a
singular point at S, without tangent plane).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix, identity

from ..refine.doo_sabin import FACE_FROM_VERTEX, RefinedFaces
from ...mesh.halfedges import HalfEdgeMesh


def vertex_interpolation_step(step1: csr_matrix, coarse: HalfEdgeMesh, faces1: RefinedFaces) -> csr_matrix:
    """First Doo-Sabin step followed by A1a's move: every V-cell gets its vertex as centroid.

    Parameters
    ----------
    step1 : (H, V) csr_matrix, the first refinement step (``doo_sabin_matrix``)
    coarse : HalfEdgeMesh with V vertices and H half-edges
    faces1 : RefinedFaces of ``coarse``

    Returns
    -------
    (H, V) csr_matrix ``(I - G) step1 + E``
    """
    offsets = np.concatenate([[0], np.cumsum(faces1.face_sizes)])
    rows, cols, vals = [], [], []
    sel_rows = []
    for n in np.unique(faces1.face_sizes[faces1.kind == FACE_FROM_VERTEX]):
        cells = np.flatnonzero((faces1.kind == FACE_FROM_VERTEX) & (faces1.face_sizes == n))
        corners = faces1.face_vertices[offsets[cells][:, None] + np.arange(n)]  # (k, n) once-refined vertices
        rows.append(np.repeat(corners, n, axis=1).ravel())
        cols.append(np.tile(corners, (1, n)).ravel())
        vals.append(np.full(corners.size * n, 1.0 / n))
        sel_rows.append(corners.ravel())
    h = coarse.n_halfedges
    if not rows:
        return step1
    average = csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(h, h))
    moved = np.concatenate(sel_rows)
    pick = csr_matrix((np.ones(moved.size), (moved, coarse.origin[moved])), shape=(h, coarse.n_vertices))
    out = ((identity(h, format="csr") - average) @ step1 + pick).tocsr()
    out.sum_duplicates()
    out.eliminate_zeros()
    return out


@dataclass(frozen=True)
class _CellGroup:
    """Cells of one size n whose tangent plane at the centre is prescribed."""

    n: int
    C: np.ndarray  # (k, n) refined vertices, cell corners in order
    B1: np.ndarray | None  # (k, n) or None (quad cells and corner-only rules)
    B2: np.ndarray | None
    normals: np.ndarray  # (k, 3) unit
    u: float  # weight of B_{l,2} + B_{l+1,1} in the tangent datum q_l
    w: float  # weight of C_l + C_{l+1}; 0 means q_l = C_l (quad cells)


class NormalConstraint:
    """Move cell corners along given normals so the surface's normal at the cell centre is n.

    Built once per topology; ``apply(x)`` works on refined points (columns: 3
    positions, then any extra columns, then the homogeneous weight when
    ``rational``).
    """

    def __init__(self, groups: list[_CellGroup], rational: bool):
        self.groups = groups
        self.rational = rational

    def apply(self, x: np.ndarray) -> np.ndarray:
        x = np.array(x, dtype=np.float64, copy=True)
        for g in self.groups:
            theta = 2 * np.pi / g.n
            phase = np.exp(1j * theta * np.arange(g.n))  # e^{i theta l}
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
            factor = 1.0 if g.w == 0.0 else g.w * (1 + np.exp(-1j * theta))
            T = -Y / factor
            t = (2.0 / g.n) * np.real(T[:, None] * np.conj(phase)[None, :])  # (k, n), a pure first mode
            x[g.C, :3] += t[..., None] * g.normals[:, None, :]
        return x


def normal_constraint(refined: HalfEdgeMesh, faces1: RefinedFaces, normals: np.ndarray, tangent_rule: str, parametric_triangles: bool, rational: bool) -> NormalConstraint | None:
    """The ``NormalConstraint`` for the coarse vertices that have a normal.

    Parameters
    ----------
    refined : the twice-refined HalfEdgeMesh (its F-cell g is made from once-refined cell g)
    faces1 : RefinedFaces of the first step
    normals : (V, 3) float per coarse vertex, NaN rows where none is given
    tangent_rule : "symmetric" or "corners" (A3 / A3a)
    parametric_triangles : 3-sided holes use section 1.3.4 (tangents from the C_i only)
    rational : points carry a homogeneous weight as last column
    """
    normals = np.asarray(normals, dtype=np.float64)
    vertex_cells = np.flatnonzero(faces1.kind == FACE_FROM_VERTEX)
    given = np.all(np.isfinite(normals[faces1.parent[vertex_cells]]), axis=1)
    cells = vertex_cells[given]
    if cells.size == 0:
        return None
    groups = []
    for n in np.unique(refined.face_sizes[cells]):
        mine = cells[refined.face_sizes[cells] == n]
        h = refined.face_offsets[mine][:, None] + np.arange(n)
        nv = normals[faces1.parent[mine]]
        length = np.linalg.norm(nv, axis=1, keepdims=True)
        if np.any(length == 0):
            raise ValueError("a vertex normal has length zero")
        nv = nv / length
        C = refined.origin[h]
        if n == 4:
            groups.append(_CellGroup(4, C, None, None, nv, 0.0, 0.0))
            continue
        if n == 3 and parametric_triangles:
            groups.append(_CellGroup(3, C, None, None, nv, 0.0, 0.0))
            continue
        c = np.cos(2 * np.pi / n)
        a = c / (1 - c)
        if tangent_rule == "corners":
            groups.append(_CellGroup(int(n), C, None, None, nv, 0.0, 0.5))
            continue
        t = refined.twin[h]
        to_b2 = refined.next[t]
        back = refined.twin[to_b2]
        B1 = refined.origin[refined.next[refined.next[back]]]
        B2 = refined.dest[to_b2]
        groups.append(_CellGroup(int(n), C, B1, B2, nv, 1.0 / 12 - a / 6, 5.0 / 12 + a / 6))
    return NormalConstraint(groups, rational)
