"""Open meshes: a ghost layer of quads outside every boundary edge.

The paper gives no boundary rule. c1surf closes each boundary loop with one
ring of ghost quads: boundary half-edge a -> b of a real face gets the ghost
quad (b, a, a', b'), where the ghost vertex a' = 2 a - m(a) reflects through a
the mean m(a) of a's neighbours along interior edges (for a corner, a vertex
in one face only: see ``ghost_points_matrix``). Every real boundary vertex
then has a full fan, and the construction runs as for a closed mesh. Only the
patches of refined vertices that lie in real faces are kept.

Why reflection: refinement commutes with the point reflection x -> 2a - x, so
along a straight run of a regular boundary the refined mesh stays point
symmetric about each boundary vertex, and the cut between real and ghost
patches is exactly the quadratic B-spline of the boundary polygon. A corner
vertex (one face) gets valence 3, a triangular hole whose real patch keeps a
visible corner; the interior is untouched, so it stays G1.

The layer itself is integers (``add_ghost_layer``). The one rule that reads
geometry, convex or reflex corner, takes the points as an explicit argument
(``reflex_corners``), so a caller whose points move classifies again.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..arrays import unique_integers
from .halfedges import HalfEdgeMesh, build_halfedges


@dataclass(frozen=True)
class GhostLayer:
    """A mesh closed up by ghost quads (integers only).

    Attributes
    ----------
    open_mesh : HalfEdgeMesh with V vertices, the mesh before closing
    mesh : HalfEdgeMesh with V + G vertices and F + B faces (ghost faces last)
    real_face : (F + B,) bool
    boundary_vertices : (G,) int, sorted; boundary vertex k has ghost vertex V + k
    ghost : (V,) int, ghost vertex of each boundary vertex, -1 elsewhere
    corners : (k,) int, sorted boundary vertices in a single face (no interior edge)
    corner_halfedges : (k,) int, the one half-edge of ``open_mesh`` leaving each corner
    """

    open_mesh: HalfEdgeMesh
    mesh: HalfEdgeMesh
    real_face: np.ndarray
    boundary_vertices: np.ndarray
    ghost: np.ndarray
    corners: np.ndarray
    corner_halfedges: np.ndarray


def add_ghost_layer(mesh: HalfEdgeMesh) -> GhostLayer:
    """Close every boundary loop of ``mesh`` with a ring of ghost quads.

    Parameters
    ----------
    mesh : HalfEdgeMesh, oriented, every vertex one fan (``repair.prepare_topology``)
    """
    n = mesh.n_vertices
    boundary = np.flatnonzero(mesh.twin < 0)  # half-edges a -> b with no face across
    a, b = mesh.origin[boundary], mesh.dest[boundary]
    boundary_vertices = unique_integers(a)
    ghost = np.full(n, -1, dtype=np.int64)
    ghost[boundary_vertices] = n + np.arange(boundary_vertices.size)
    quads = np.stack([b, a, ghost[a], ghost[b]], axis=1)
    face_sizes = np.concatenate([mesh.face_sizes, np.full(boundary.size, 4)])
    face_vertices = np.concatenate([mesh.origin, quads.ravel()])
    ghosted = build_halfedges(face_sizes, face_vertices, n + boundary_vertices.size)
    real_face = np.r_[np.ones(mesh.n_faces, bool), np.zeros(boundary.size, bool)]
    corners = boundary_vertices[_interior_neighbour_count(mesh)[boundary_vertices] == 0]
    leaving = np.flatnonzero(np.isin(mesh.origin, corners))  # one half-edge leaves each corner
    corner_halfedges = leaving[np.argsort(mesh.origin[leaving], kind="stable")]
    return GhostLayer(mesh, ghosted, real_face, boundary_vertices, ghost, corners, corner_halfedges)


def _interior_neighbour_count(mesh: HalfEdgeMesh) -> np.ndarray:
    """(V,) int: neighbours of each vertex along interior edges (each interior edge once per direction)."""
    return np.bincount(mesh.origin[mesh.twin >= 0], minlength=mesh.n_vertices)


def reflex_corners(layer: GhostLayer, points: np.ndarray) -> np.ndarray:
    """(k,) bool: is each single-face corner of ``layer`` reflex within its face?

    The turn x -> a -> y at corner a (x before, y after it in the face) is
    compared with the face's Newell normal. Only the corners' faces are read.

    Parameters
    ----------
    layer : GhostLayer
    points : (V, 3) float, positions of the open mesh's vertices
    """
    mesh, h = layer.open_mesh, layer.corner_halfedges
    if h.size == 0:
        return np.zeros(0, dtype=bool)
    a, y, x = points[mesh.origin[h]], points[mesh.dest[h]], points[mesh.origin[mesh.prev[h]]]
    faces, slot = np.unique(mesh.face[h], return_inverse=True)
    sizes = mesh.face_sizes[faces]
    first = np.repeat(mesh.face_offsets[faces] - np.cumsum(sizes) + sizes, sizes)
    members = first + np.arange(sizes.sum())  # the half-edges of those faces, face by face
    corner_points = points[mesh.origin[members]]
    newell = np.cross(corner_points, points[mesh.origin[mesh.next[members]]])  # sums to twice the area vector
    normal = np.zeros((faces.size, 3))
    np.add.at(normal, np.repeat(np.arange(faces.size), sizes), newell)
    turn = np.einsum("ij,ij->i", np.cross(a - x, y - a), normal[slot.ravel()])
    return turn < 0


def ghost_points_matrix(layer: GhostLayer, reflex: np.ndarray):
    """(V + G, V) matrix: real points unchanged, ghost a' = 2 a - m(a).

    m(a) is the mean of the neighbours of a along interior edges. A vertex in a
    single face (a corner) has none: at a convex corner m(a) is the face's
    centroid; at a reflex one (which the centroid rule would push into the
    face) a' = x + y - a completes the parallelogram of its two neighbours
    into the notch.

    Parameters
    ----------
    layer : GhostLayer
    reflex : (k,) bool, which of ``layer.corners`` are reflex (``reflex_corners``)
    """
    return ghost_points_parts(layer, reflex)[0]


def ghost_points_parts(layer: GhostLayer, reflex: np.ndarray, large: int | None = None):
    """``ghost_points_matrix`` with the faces of more than ``large`` sides in O(n) entries.

    A convex corner reflects its face's centroid: n entries a corner, n^2 for a face of n such corners (a
    polygon cut out along C0 creases). A face of more than ``large`` sides instead has its centroid as a
    point of its own (a row of ``centroids``), which its corners' ghosts read once.

    Returns
    -------
    matrix : (V + G, V + L) csr_matrix on [points; the L centroids]
    centroids : (L, V) csr_matrix or None (no such face: ``matrix`` is ``ghost_points_matrix``'s)
    """
    from scipy.sparse import csr_matrix  # open meshes only: a closed mesh's conversion imports no scipy.sparse

    mesh, ghost, boundary_vertices = layer.open_mesh, layer.ghost, layer.boundary_vertices
    n, g = mesh.n_vertices, boundary_vertices.size
    interior = mesh.twin >= 0
    src, dst = mesh.origin[interior], mesh.dest[interior]
    keep = ghost[src] >= 0
    src, dst = src[keep], dst[keep]
    count = _interior_neighbour_count(mesh)
    rows = [np.arange(n), ghost[boundary_vertices], ghost[src]]
    cols = [np.arange(n), boundary_vertices, dst]
    vals = [np.ones(n), np.full(g, 2.0), -1.0 / count[src]]
    h = layer.corner_halfedges[reflex]
    if h.size:  # 2 a - m(a) = x + y - a: m(a) = 3 a - x - y
        rows += [ghost[mesh.origin[h]]] * 3
        cols += [mesh.origin[h], mesh.dest[h], mesh.origin[mesh.prev[h]]]
        vals += [np.full(h.size, -3.0), np.ones(h.size), np.ones(h.size)]
    h = layer.corner_halfedges[~reflex]
    n_large, centroids = 0, None
    if h.size and large is not None and mesh.face_sizes.max() > large:  # large faces: a centroid point each
        big = mesh.face_sizes > large
        column = np.where(big, n + np.cumsum(big) - 1, -1)
        n_large = int(big.sum())
        own = column[mesh.face[h]] >= 0
        rows.append(ghost[mesh.origin[h[own]]])
        cols.append(column[mesh.face[h[own]]])
        vals.append(np.full(int(own.sum()), -1.0))
        corners = np.flatnonzero(big[mesh.face])
        centroids = csr_matrix((1.0 / mesh.face_sizes[mesh.face[corners]], (column[mesh.face[corners]] - n,
                                                                            mesh.origin[corners])), shape=(n_large, n))
        h = h[~own]
    if h.size:  # a convex corner lies in one face: reflect that face's centroid
        face = mesh.face[h]
        width = int(mesh.face_sizes[face].max())  # these corners' faces only (not a wider mesh's largest face)
        members = mesh.face_offsets[face][:, None] + np.arange(width)[None, :]
        valid = np.arange(width)[None, :] < mesh.face_sizes[face][:, None]
        rows.append(np.broadcast_to(ghost[mesh.origin[h]][:, None], members.shape)[valid])
        cols.append(mesh.origin[np.where(valid, members, 0)][valid])
        vals.append(np.broadcast_to((-1.0 / mesh.face_sizes[face])[:, None], members.shape)[valid])
    matrix = csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                        shape=(n + g, n + n_large))
    matrix.sum_duplicates()
    return matrix, centroids
