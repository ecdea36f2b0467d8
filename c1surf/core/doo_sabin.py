"""Step A1: Doo-Sabin refinement, as topology plus a sparse averaging matrix.

One refinement makes a new point for every corner of every face, that is for
every half-edge ``h`` of the coarse mesh (the corner at ``origin[h]`` in
``face[h]``), so fine vertex ``h`` *is* coarse half-edge ``h``. The new faces are

- an F-face per coarse face (same size, its corners in order),
- an E-face per coarse interior edge (a quad),
- a V-face per coarse vertex (as many sides as the vertex has faces).

The point of corner ``h`` is ``(1 - a) V + a S`` with ``V = origin[h]``, ``S``
the centroid of ``face[h]`` and ``a`` the ratio of that face (paper, A1), or
of that corner when ratios are given per corner (per-vertex blend ratios,
``core.blend``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix

from .topology import HalfEdgeMesh, outgoing_rings

FACE_FROM_FACE, FACE_FROM_EDGE, FACE_FROM_VERTEX = 0, 1, 2


@dataclass(frozen=True)
class RefinedFaces:
    """Faces of a refined mesh and where each came from.

    Attributes
    ----------
    face_sizes : (F',) int64
    face_vertices : (sum(face_sizes),) int64, indices of fine vertices (= coarse half-edges)
    kind : (F',) int8, FACE_FROM_FACE / FACE_FROM_EDGE / FACE_FROM_VERTEX
    parent : (F',) int64, coarse face, coarse half-edge (one of the edge's two) or coarse vertex
    """

    face_sizes: np.ndarray
    face_vertices: np.ndarray
    kind: np.ndarray
    parent: np.ndarray


def refine_doo_sabin(mesh: HalfEdgeMesh) -> RefinedFaces:
    """Faces of one Doo-Sabin (dual quad quadrisection) step of a closed mesh.

    Parameters
    ----------
    mesh : HalfEdgeMesh, closed and manifold (every twin defined)

    Returns
    -------
    RefinedFaces, consistently oriented with the coarse faces.
    """
    h = np.arange(mesh.n_halfedges, dtype=np.int64)
    # F-faces: the corners of each face, in order.
    f_sizes = mesh.face_sizes
    f_vertices = h
    # E-faces: for the edge of h (a -> b in face f) and its twin t (b -> a in
    # face g), the quad (corner b in f, corner a in f, corner a in g, corner b in g).
    rep = h[h < mesh.twin]
    t = mesh.twin[rep]
    e_vertices = np.stack([mesh.next[rep], rep, mesh.next[t], t], axis=1).ravel()
    e_sizes = np.full(rep.size, 4, dtype=np.int64)
    # V-faces: the corners around each vertex in rotation order.
    vertices, v_sizes, ring = outgoing_rings(mesh)
    return RefinedFaces(
        face_sizes=np.concatenate([f_sizes, e_sizes, v_sizes]).astype(np.int64),
        face_vertices=np.concatenate([f_vertices, e_vertices, ring]).astype(np.int64),
        kind=np.concatenate(
            [
                np.full(f_sizes.size, FACE_FROM_FACE, np.int8),
                np.full(rep.size, FACE_FROM_EDGE, np.int8),
                np.full(vertices.size, FACE_FROM_VERTEX, np.int8),
            ]
        ),
        parent=np.concatenate([np.arange(f_sizes.size), rep, vertices]).astype(np.int64),
    )


def doo_sabin_matrix(mesh: HalfEdgeMesh, ratio: np.ndarray, per_corner: bool = False) -> csr_matrix:
    """Sparse averaging matrix of one Doo-Sabin step.

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices and H half-edges
    ratio : (F,) float, the ratio ``a`` of each coarse face; or, with
        ``per_corner``, (H,) float, the ratio of each corner (half-edge), so
        corners of one face may differ (per-vertex blend ratios)
    per_corner : bool

    Returns
    -------
    (H, V) csr_matrix M: fine points = M @ coarse points.
    """
    ratio = np.asarray(ratio, dtype=np.float64)
    corner_ratio = ratio if per_corner else ratio[mesh.face]
    # Row h holds the n vertices of its face (a/n each) and 1 - a more at its own
    # corner; written straight into CSR arrays, faces grouped by size.
    indptr = np.concatenate([[0], np.cumsum(mesh.face_sizes[mesh.face])])
    indices = np.empty(indptr[-1], dtype=np.int64)
    data = np.empty(indptr[-1])
    for n, faces, halfedges in mesh.faces_by_size():
        start = indptr[halfedges][..., None] + np.arange(n)  # (Fn, n rows, n entries)
        indices[start] = mesh.origin[halfedges][:, None, :]
        weights = np.broadcast_to((corner_ratio[halfedges] / n)[..., None], start.shape).copy()
        weights[:, np.arange(n), np.arange(n)] += 1.0 - corner_ratio[halfedges]  # row i's own corner is entry i
        data[start] = weights
    return csr_matrix((data, indices, indptr), shape=(mesh.n_halfedges, mesh.n_vertices))


def second_step_ratio(face_sizes: np.ndarray, blend: np.ndarray) -> np.ndarray:
    """Ratio of the second refinement step, ``alpha_f (1 - cos(2 pi / n))`` (A1).

    Parameters
    ----------
    face_sizes : (F,) int, sizes of the once-refined faces
    blend : (F,) float, their blend ratios alpha_f

    Returns
    -------
    (F,) float
    """
    return blend * (1.0 - np.cos(2.0 * np.pi / face_sizes))
