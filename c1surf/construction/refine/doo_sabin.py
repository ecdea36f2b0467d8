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
from scipy.sparse import csr_matrix, issparse

from ...parallel import for_each_range
from ...mesh.halfedges import HalfEdgeMesh, face_cycles, outgoing_rings

FACE_FROM_FACE, FACE_FROM_EDGE, FACE_FROM_VERTEX = 0, 1, 2


@dataclass(frozen=True)
class RefinedFaces:
    """Faces of a refined mesh and where each came from.

    Attributes
    ----------
    face_sizes : (F',) int64
    face_vertices : (sum(face_sizes),) int (int32 when it fits), indices of fine vertices (= coarse half-edges)
    kind : (F',) int8, FACE_FROM_FACE / FACE_FROM_EDGE / FACE_FROM_VERTEX
    parent : (F',) int64, coarse face, coarse half-edge (one of the edge's two) or coarse vertex
    """

    face_sizes: np.ndarray
    face_vertices: np.ndarray
    kind: np.ndarray
    parent: np.ndarray


def refined_index_type(mesh: HalfEdgeMesh):
    """int32 if every index of the once-refined ``mesh`` fits (fine half-edges <= 4 H + 4 V), else int64."""
    return np.int32 if 4 * (mesh.n_halfedges + mesh.n_vertices) < 2**31 else np.int64


def refine_doo_sabin(mesh: HalfEdgeMesh) -> RefinedFaces:
    """Faces of one Doo-Sabin (dual quad quadrisection) step of a closed mesh.

    Parameters
    ----------
    mesh : HalfEdgeMesh, closed and manifold (every twin defined)

    Returns
    -------
    RefinedFaces, consistently oriented with the coarse faces.
    """
    # fine vertices are coarse half-edges, and the fine mesh has about 4 times as
    # many half-edges: int32 whenever that fits
    index = refined_index_type(mesh)
    h = np.arange(mesh.n_halfedges, dtype=index)
    # F-faces: the corners of each face, in order.
    f_sizes = mesh.face_sizes
    f_vertices = h
    # E-faces: for the edge of h (a -> b in face f) and its twin t (b -> a in
    # face g), the quad (corner b in f, corner a in f, corner a in g, corner b in g).
    rep = h[h < mesh.twin]
    t = mesh.twin[rep]
    e_vertices = np.stack([mesh.next[rep], rep, mesh.next[t], t], axis=1).astype(index, copy=False).ravel()
    e_sizes = np.full(rep.size, 4, dtype=np.int64)
    # V-faces: the corners around each vertex in rotation order.
    vertices, v_sizes, ring = outgoing_rings(mesh)
    return RefinedFaces(
        face_sizes=np.concatenate([f_sizes, e_sizes, v_sizes]).astype(np.int64, copy=False),
        face_vertices=np.concatenate([f_vertices, e_vertices, ring.astype(index, copy=False)]),
        kind=np.concatenate(
            [
                np.full(f_sizes.size, FACE_FROM_FACE, np.int8),
                np.full(rep.size, FACE_FROM_EDGE, np.int8),
                np.full(vertices.size, FACE_FROM_VERTEX, np.int8),
            ]
        ),
        parent=np.concatenate([np.arange(f_sizes.size), rep, vertices]).astype(np.int64, copy=False),
    )


def refined_halfedges(mesh: HalfEdgeMesh, faces: RefinedFaces) -> HalfEdgeMesh:
    """Half-edges of the refined mesh by index arithmetic (no sort, no search).

    Every fine half-edge has its twin at a known place, so this gives exactly
    ``build_halfedges(faces.face_sizes, faces.face_vertices, mesh.n_halfedges)``
    at a fraction of the cost (the twice-refined mesh has 16 times the coarse
    half-edges). With H coarse half-edges, E interior edges and fine faces in
    ``refine_doo_sabin``'s order, the fine half-edges are

    - F-face of ``face[h]``: h -> next[h] at position h; twin in the E-face of h's edge;
    - E-face k of ``rep`` (twin ``t``): next[rep] -> rep, rep -> next[t],
      next[t] -> t, t -> next[rep] at H + 4k + 0..3; twins in the F-faces and
      in the V-faces of the edge's two end vertices;
    - V-face of a vertex: h -> rotate(h) at H + 4E + (h's place in the ring);
      twin in the E-face of ``prev[h]``'s edge.

    Boundary half-edges (the coarse edge or vertex has no E- or V-face) get -1.

    Parameters
    ----------
    mesh : HalfEdgeMesh, the coarse mesh ``faces`` was refined from
    faces : RefinedFaces, ``refine_doo_sabin(mesh)``

    Returns
    -------
    HalfEdgeMesh with ``mesh.n_halfedges`` vertices
    """
    n_half = mesh.n_halfedges
    edge_faces = faces.kind == FACE_FROM_EDGE
    rep = faces.parent[edge_faces]
    n_edges = rep.size
    t = mesh.twin[rep]
    ring_start = n_half + 4 * n_edges
    ring = faces.face_vertices[ring_start:]
    # where each coarse half-edge's own fine half-edges are: its edge's E-face and its ring slot
    edge_of = np.full(n_half, -1, dtype=np.int64)
    edge_of[rep] = edge_of[t] = np.arange(n_edges)
    is_rep = np.zeros(n_half, dtype=bool)
    is_rep[rep] = True
    ring_slot = np.full(n_half, -1, dtype=np.int64)
    ring_slot[ring] = np.arange(ring_start, ring_start + ring.size)

    index = faces.face_vertices.dtype
    offsets, face, nxt, prv = face_cycles(faces.face_sizes, index)
    twin = np.full(offsets[-1], -1, dtype=index)
    h = np.arange(n_half)
    inner = edge_of >= 0
    twin[h[inner]] = n_half + 4 * edge_of[inner] + np.where(is_rep[inner], 0, 2)
    e_twin = twin[n_half:ring_start].reshape(n_edges, 4)
    e_twin[:, 0], e_twin[:, 2] = rep, t
    e_twin[:, 1], e_twin[:, 3] = ring_slot[mesh.next[t]], ring_slot[mesh.next[rep]]
    before = mesh.prev[ring]
    twin[ring_start:] = n_half + 4 * edge_of[before] + np.where(is_rep[before], 3, 1)
    return HalfEdgeMesh(int(n_half), faces.face_sizes, offsets, faces.face_vertices, face, nxt, prv, twin)


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
    # corner. Face f's n rows fill one n x n block of entries, so blocks start at
    # the running sum of n^2; written straight into CSR arrays, faces grouped by size.
    sizes = mesh.face_sizes
    block = np.zeros(sizes.size + 1, dtype=np.int64)
    np.cumsum(sizes * sizes, out=block[1:])
    index = np.int32 if max(block[-1], mesh.n_vertices) < 2**31 else np.int64
    indptr = np.empty(mesh.n_halfedges + 1, dtype=index)
    indices = np.empty(block[-1], dtype=index)
    data = np.empty(block[-1])
    indptr[-1] = block[-1]
    offsets = mesh.face_offsets
    for n in np.unique(sizes):
        faces = np.flatnonzero(sizes == n)
        # faces of one size usually form one run (F-, E- and V-faces of a refined mesh):
        # then their half-edges and entries are slices, else index arrays
        if faces[-1] - faces[0] + 1 == faces.size:
            rows = slice(offsets[faces[0]], offsets[faces[-1] + 1])
            entries = slice(block[faces[0]], block[faces[-1] + 1])
            indptr[rows] = np.arange(block[faces[0]], block[faces[-1] + 1], n)
        else:
            rows = (offsets[faces][:, None] + np.arange(n)).ravel()
            entries = (block[faces][:, None] + np.arange(n * n)).ravel()
            indptr[rows] = (block[faces][:, None] + n * np.arange(n)).ravel()
        corners = mesh.origin[rows].reshape(-1, 1, n)
        indices[entries] = np.broadcast_to(corners, (corners.shape[0], n, n)).ravel()
        a = corner_ratio[rows].reshape(-1, n)
        weights = np.empty((a.shape[0], n, n))
        weights[:] = (a / n)[..., None]
        weights[:, np.arange(n), np.arange(n)] += 1.0 - a  # row i's own corner is entry i
        data[entries] = weights.ravel()
    return csr_matrix((data, indices, indptr), shape=(mesh.n_halfedges, mesh.n_vertices))


class DooSabinStep:
    """One Doo-Sabin step kept factored: ``fine = (1 - a) x[origin] + a centroid(face)``.

    The same linear map as ``doo_sabin_matrix(mesh, ratio, per_corner=True)``,
    applied from the mesh's own arrays: no matrix with n entries per fine
    point is built or stored (for the second step that matrix is the largest
    object of the construction). ``step @ points`` applies it, ``tocsr()``
    gives the matrix, and ``matrix @ step`` / ``step @ matrix`` compose it
    with sparse matrices like any operator of ``Surface.operators``.

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices and H half-edges
    ratio : (H,) float, the ratio of every corner
    """

    def __init__(self, mesh: HalfEdgeMesh, ratio: np.ndarray):
        self.mesh = mesh
        self.ratio = np.asarray(ratio, dtype=np.float64)
        self.shape = (mesh.n_halfedges, mesh.n_vertices)
        self._applied = 0
        self._matrix = None

    def __matmul__(self, x):
        if issparse(x):
            return self.tocsr() @ x
        # The factored form is cheapest to set up, the matrix ~3x faster to apply:
        # a surface built once uses the first, ``update_points`` called again
        # and again (animation, optimisation) builds and keeps the second.
        self._applied += 1
        if self._matrix is None and self._applied > 2:
            self._matrix = self.tocsr()
        if self._matrix is not None:
            return self._matrix @ x
        x = np.asarray(x, dtype=np.float64)
        flat = np.ascontiguousarray(x.reshape(x.shape[0], -1))
        mesh, ratio = self.mesh, self.ratio
        offsets = mesh.face_offsets
        out = np.empty((mesh.n_halfedges, flat.shape[1]))

        def faces(first: int, last: int) -> None:  # faces first:last, by blocks that stay in cache
            for f0 in range(first, last, 1 << 14):
                f1 = min(last, f0 + (1 << 14))
                h0, h1 = offsets[f0], offsets[f1]
                corners = np.take(flat, mesh.origin[h0:h1], axis=0, mode="clip")  # x at every corner, face by face
                centroids = np.add.reduceat(corners, offsets[f0:f1] - h0, axis=0)
                centroids /= mesh.face_sizes[f0:f1, None]
                block = out[h0:h1]
                np.multiply(corners, (1.0 - ratio[h0:h1])[:, None], out=block)
                block += ratio[h0:h1, None] * np.take(centroids, mesh.face[h0:h1] - f0, axis=0, mode="clip")

        for_each_range(mesh.n_faces, faces, minimum=1 << 14)
        return out.reshape((mesh.n_halfedges,) + x.shape[1:])

    def __rmatmul__(self, other):
        return other @ self.tocsr()

    def tocsr(self) -> csr_matrix:
        if self._matrix is not None:
            return self._matrix
        return doo_sabin_matrix(self.mesh, self.ratio, per_corner=True)
