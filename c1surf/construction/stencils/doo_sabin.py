"""Step A1: where Doo-Sabin puts the new points, as a sparse matrix or a factored map.

The point of corner ``h`` (fine vertex h, see ``refine.doo_sabin``) is
``(1 - a) V + a S`` with ``V = origin[h]``, ``S`` the centroid of ``face[h]``
and ``a`` the ratio of that face (paper, A1), or of that corner when ratios
are given per corner (per-vertex blend ratios, ``stencils.blend``).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...arrays import unique_integers
from ...mesh.halfedges import HalfEdgeMesh
from ...parallel import for_each_range

if TYPE_CHECKING:  # scipy.sparse is imported where a matrix is made: the usual conversion needs none (0.2 s)
    from scipy.sparse import csr_matrix


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
    from scipy.sparse import csr_matrix

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
    for n in unique_integers(sizes):
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


def doo_sabin_rows(mesh: HalfEdgeMesh, ratio: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``doo_sabin_matrix(mesh, ratio, per_corner=True) @ points``, the same bits, without the matrix (faces of
    more than ``LARGE_FACE`` sides: from their centroid, O(n) a face, the same values to round-off).

    scipy's product starts every row from zero and adds its entries in their
    order, weight times point: here too, face size by face size, with the
    weights made as the matrix makes them. So the first step needs no
    scipy.sparse (0.2 s to import) until its matrix is asked for.

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices and H half-edges
    ratio : (H,) float, the ratio of every corner
    points : (V, d) float

    Returns
    -------
    (H, d) float
    """
    x = np.asarray(points, dtype=np.float64)
    flat = x.reshape(x.shape[0], -1)
    planes = np.ascontiguousarray(flat.T)  # (d, V): one coordinate at a time, contiguous (4x faster than rows)
    out = np.empty((mesh.n_halfedges, flat.shape[1]))
    ratio = np.asarray(ratio, dtype=np.float64)
    for n in unique_integers(mesh.face_sizes):
        faces = np.flatnonzero(mesh.face_sizes == n)
        if n > LARGE_FACE:  # the matrix's n^2 products per face: its centroid once instead (not the matrix's bits)
            _large_rows(mesh, ratio, flat, faces, int(n), out)
            continue
        for start in range(0, faces.size, _ROWS_BLOCK):  # by blocks of faces: each face's rows alone, the same bits
            _rows_block(mesh, ratio, planes, faces[start : start + _ROWS_BLOCK], int(n), out)
    return out.reshape((mesh.n_halfedges,) + x.shape[1:])


LARGE_FACE = 64
"""Faces of more sides: ``doo_sabin_rows`` forms their centroid once (O(n) a face; the matrix's n^2 products give
the other faces' bits), and a step with such a face keeps applying its factored map (its matrix would hold n^2
entries a face: ``reuse`` does not make it)."""


def _large_rows(mesh: HalfEdgeMesh, ratio: np.ndarray, flat: np.ndarray, faces: np.ndarray, n: int,
                out: np.ndarray) -> None:
    """Write the rows (H, d) ``out`` of the n-sided ``faces`` (k,): ``(1 - a) x[origin] + a centroid``, from ``flat`` (V, d)."""
    rows = (mesh.face_offsets[faces][:, None] + np.arange(n)).ravel()
    corners = np.take(flat, mesh.origin[rows], axis=0).reshape(faces.size, n, -1)
    centroid = corners.mean(axis=1, keepdims=True)
    a = ratio[rows].reshape(faces.size, n, 1)
    out[rows] = ((1.0 - a) * corners + a * centroid).reshape(rows.size, -1)


def doo_sabin_augmented(mesh: HalfEdgeMesh, ratio: np.ndarray):
    """``doo_sabin_matrix(mesh, ratio, per_corner=True)`` with the centroids of its large faces as columns of their own:
    O(n) entries per n-sided face where the matrix has n^2 (not its bits: its entries are added in another order).

    Returns
    -------
    step : (H, V + L) csr_matrix on [points; centroids]: row h is ``(1 - a) x[origin] + a centroid``, the centroid a
        column V + l for the l-th face of more than ``LARGE_FACE`` sides, ``a / n`` on each corner for the others
    centroids : (L, V) csr_matrix, the large faces' centroids (n entries of 1 / n)
    Then the matrix is ``step[:, :V] + step[:, V:] @ centroids``; row operations on the step (creases, A1a)
    apply to ``step`` as to the matrix (``construction.stages.CentroidStage``).
    """
    from scipy.sparse import coo_matrix

    ratio = np.broadcast_to(np.asarray(ratio, dtype=np.float64), (mesh.n_halfedges,))
    sizes, offsets, n_vertices, n_halfedges = mesh.face_sizes, mesh.face_offsets, mesh.n_vertices, mesh.n_halfedges
    large = np.flatnonzero(sizes > LARGE_FACE)
    slot = centroid_columns(mesh) - n_vertices
    slot[slot < 0] = -1
    face = np.repeat(np.arange(sizes.size), sizes)
    rows, cols, vals = [np.arange(n_halfedges)], [mesh.origin], [1.0 - ratio]  # every corner's own point
    in_large = np.flatnonzero(slot[face] >= 0)
    rows.append(in_large)
    cols.append(n_vertices + slot[face[in_large]])
    vals.append(ratio[in_large])
    for n in unique_integers(sizes[sizes <= LARGE_FACE]):
        corners = offsets[np.flatnonzero(sizes == n)][:, None] + np.arange(n)  # (k, n) half-edges
        rows.append(np.repeat(corners, n, axis=1).ravel())
        cols.append(np.tile(mesh.origin[corners], (1, n)).ravel())
        vals.append(np.repeat(ratio[corners] / n, n, axis=1).ravel())
    step = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n_halfedges, n_vertices + large.size)).tocsr()
    step.sum_duplicates()
    return step, large_face_centroids(mesh)


def large_face_centroids(mesh: HalfEdgeMesh):
    """(L, V) csr_matrix: the centroid of each of the L faces of more than ``LARGE_FACE`` sides (n entries of 1 / n)."""
    from scipy.sparse import csr_matrix

    slot = centroid_columns(mesh) - mesh.n_vertices
    face = np.repeat(np.arange(mesh.n_faces), mesh.face_sizes)
    corners = np.flatnonzero(slot[face] >= 0)
    return csr_matrix((1.0 / mesh.face_sizes[face[corners]], (slot[face[corners]], mesh.origin[corners])),
                      shape=(int((slot >= 0).sum()), mesh.n_vertices))


def centroid_columns(mesh: HalfEdgeMesh) -> np.ndarray:
    """(F,) int64: V + l for the l-th face of more than ``LARGE_FACE`` sides, -1 for the others
    (the columns of ``doo_sabin_augmented``)."""
    large = mesh.face_sizes > LARGE_FACE
    return np.where(large, mesh.n_vertices + np.cumsum(large) - 1, -1).astype(np.int64)


def has_large_face(mesh: HalfEdgeMesh) -> bool:
    """Whether some face of ``mesh`` has more than ``LARGE_FACE`` sides."""
    return bool(mesh.n_faces) and int(mesh.face_sizes.max()) > LARGE_FACE


_ROWS_BLOCK = 1 << 16  # faces per block of ``doo_sabin_rows``: its temporaries were 0.9 GB for the 4,000,000-quad torus


def _rows_block(mesh: HalfEdgeMesh, ratio: np.ndarray, planes: np.ndarray, faces: np.ndarray, n: int,
                out: np.ndarray) -> None:
    """Write the rows (H, d) ``out`` of ``doo_sabin_rows`` of the n-sided ``faces`` (k,), from ``planes`` (d, V)."""
    k, d = faces.size, planes.shape[0]
    rows = mesh.face_offsets[faces][:, None] + np.arange(n)  # (k, n): row i of a face is its corner i
    run = faces[-1] - faces[0] + 1 == k  # their rows are one slice of the output
    target = out[rows[0, 0] : rows[-1, -1] + 1].reshape(k, n, d) if run else np.empty((k, n, d))
    corners = np.ascontiguousarray(mesh.origin[rows].T)  # (n, k): every row has its face's corners, in order
    a = np.ascontiguousarray(ratio[rows].T)
    off_diagonal = a / n  # the matrix's weights: a / n, and a / n + (1 - a) at the row's own corner
    diagonal = off_diagonal + (1.0 - a)
    gathered, product, total = np.empty((n, k)), np.empty(k), np.empty(k)
    for c in range(d):
        for j in range(n):
            np.take(planes[c], corners[j], out=gathered[j])
        for i in range(n):
            total[:] = 0.0  # scipy's product starts each row from zero and adds the entries in order
            for j in range(n):
                total += np.multiply(diagonal[i] if i == j else off_diagonal[i], gathered[j], out=product)
            target[:, i, c] = total
    if not run:
        out[rows.ravel()] = target.reshape(-1, d)


def compact_ratio(ratio) -> np.ndarray:
    """(H,) float64 ``ratio``, or, when every entry has the same bits, one value broadcast to (H,) (read-only,
    no memory: the ratios of a quad mesh's second step are 0.5 GB for the 4,000,000-quad torus)."""
    ratio = np.asarray(ratio, dtype=np.float64)
    if ratio.ndim == 1 and ratio.size > 1 and ratio.strides[0] != 0:  # (a broadcast value is one already)
        bits = ratio.view(np.int64)
        if np.all(bits == bits[0]):  # bits, not values: 0.0 and -0.0 stay apart
            return np.broadcast_to(ratio[:1].copy(), ratio.shape)
    return ratio


class FirstDooSabinStep:
    """The first Doo-Sabin step as a stage (``construction.stages.Stage``): ``doo_sabin_matrix``'s map, applied
    by ``doo_sabin_rows`` until the matrix is asked for (``matrix``, ``reuse``), then by the matrix.

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices and H half-edges
    ratio : (H,) float, the ratio of every corner
    name : str, the stage's name
    """

    mixes_coordinates = False

    def __init__(self, mesh: HalfEdgeMesh, ratio: np.ndarray, name: str = "doo_sabin_1"):
        self.name, self.mesh = name, mesh
        self.ratio = compact_ratio(ratio)
        self.shape = (mesh.n_halfedges, mesh.n_vertices)
        self._matrix = None

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(H, d) fine points from (V, d) coarse ``points``."""
        return self._matrix @ points if self._matrix is not None else doo_sabin_rows(self.mesh, self.ratio, points)

    def reuse(self) -> None:
        """Applied again (``Surface.update_points``): the matrix from now on (not with a face of more than
        ``LARGE_FACE`` sides: n^2 entries a face)."""
        if not has_large_face(self.mesh):
            self.matrix()

    def matrix(self) -> csr_matrix:
        """(H, V) csr_matrix, built on the first call and kept."""
        if self._matrix is None:
            self._matrix = doo_sabin_matrix(self.mesh, self.ratio, per_corner=True)
        return self._matrix


def doo_sabin_factored(mesh: HalfEdgeMesh, ratio: np.ndarray, points: np.ndarray) -> np.ndarray:
    """One Doo-Sabin step applied from the mesh's own arrays: ``(1 - a) x[origin] + a centroid(face)``.

    The map of ``doo_sabin_matrix(mesh, ratio, per_corner=True)`` without its
    matrix (n entries per fine point): faces by blocks that stay in cache, on the
    thread pool.

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices and H half-edges
    ratio : (H,) float, the ratio of every corner
    points : (V, ...) float

    Returns
    -------
    (H, ...) float
    """
    x = np.asarray(points, dtype=np.float64)
    flat = np.ascontiguousarray(x.reshape(x.shape[0], -1))
    offsets, sizes = mesh.face_offsets, mesh.face_sizes
    out = np.empty((mesh.n_halfedges, flat.shape[1]))

    def faces(first: int, last: int) -> None:  # faces first:last, by blocks that stay in cache
        for f0 in range(first, last, 1 << 14):
            f1 = min(last, f0 + (1 << 14))
            h0, h1 = offsets[f0], offsets[f1]
            corners = np.take(flat, mesh.origin[h0:h1], axis=0, mode="clip")  # x at every corner, face by face
            centroids = np.add.reduceat(corners, offsets[f0:f1] - h0, axis=0)
            centroids /= sizes[f0:f1, None]
            block = out[h0:h1]
            np.multiply(corners, (1.0 - ratio[h0:h1])[:, None], out=block)
            # each corner's face among these (``mesh.face[h0:h1] - f0``, without the mesh's whole ``face``)
            local = np.repeat(np.arange(f1 - f0), sizes[f0:f1])
            block += ratio[h0:h1, None] * np.take(centroids, local, axis=0, mode="clip")

    for_each_range(mesh.n_faces, faces, minimum=1 << 14)
    return out.reshape((mesh.n_halfedges,) + x.shape[1:])


class DooSabinStep:
    """A Doo-Sabin step as a stage (``construction.stages.Stage``), always applied factored.

    The factored map (``doo_sabin_factored``) is cheapest to set up and needs no memory beyond its output; its
    matrix (n entries per fine point, ~0.5 s to build at 180,000 input quads) is made only when asked for
    (``matrix()``: ``Surface.stencil()``). ``apply`` runs the factored map in every case, so a Surface built
    afresh and one moved by ``update_points`` apply the very same operations and agree bit for bit (the matrix
    sums the same products in another order: the last bits differ).

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices and H half-edges
    ratio : (H,) float, the ratio of every corner
    name : str, the stage's name
    correction : (H, V) csr_matrix or None, added to the smooth step (creases and
        corners, ``stencils.creases.crease_correction``); or (H, V + L) on the points and
        ``centroids`` (L, V) csr_matrix, the centroids of the L faces of more than ``LARGE_FACE``
        sides (``centroid_columns``: O(n) entries a face where the correction has n^2)
    """

    mixes_coordinates = False

    def __init__(self, mesh: HalfEdgeMesh, ratio: np.ndarray, name: str = "doo_sabin_2", correction=None,
                 centroids=None):
        self.name = name
        self.mesh = mesh
        self.ratio = compact_ratio(ratio)
        self.correction, self.centroids = correction, centroids
        self.shape = (mesh.n_halfedges, mesh.n_vertices)
        self._matrix = None

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(H, d) fine points from (V, d) coarse ``points``: the factored map (also once the matrix is made)."""
        out = doo_sabin_factored(self.mesh, self.ratio, points)
        if self.correction is not None:
            out += self.correction @ (points if self.centroids is None else
                                      np.concatenate([points, self.centroids @ points]))
        return out

    def matrix(self) -> csr_matrix:
        """(H, V) csr_matrix, built on the first call and kept (for ``Surface.stencil()``; ``apply`` stays factored)."""
        if self._matrix is None:
            self._matrix = doo_sabin_matrix(self.mesh, self.ratio, per_corner=True)
            if self.correction is not None:
                correction, v = self.correction, self.mesh.n_vertices
                if self.centroids is not None:
                    correction = correction[:, :v] + correction[:, v:] @ self.centroids
                self._matrix = (self._matrix + correction).tocsr()
        return self._matrix
