"""Open meshes: a ghost layer of quads outside every boundary edge.

The paper gives no boundary rule. c1surf closes each boundary loop with one
ring of ghost quads: boundary half-edge a -> b of a real face gets the ghost
quad (b, a, a', b'), where the ghost vertex a' = 2 a - m(a) reflects through a
the mean m(a) of a's neighbours along interior edges (for a corner, a vertex
in one face only: the centroid of that face). Every real boundary vertex
then has a full fan, and the construction runs as for a closed mesh. Only the
patches of refined vertices that lie in real faces are kept.

Why reflection: refinement commutes with the point reflection x -> 2a - x, so
along a straight run of a regular boundary the refined mesh stays point
symmetric about each boundary vertex, and the cut between real and ghost
patches is exactly the quadratic B-spline of the boundary polygon. A corner
vertex (one face) gets valence 3, a triangular hole whose real patch keeps a
visible corner; the interior is untouched, so it stays G1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix

from .halfedges import HalfEdgeMesh, build_halfedges


@dataclass(frozen=True)
class GhostLayer:
    """A mesh closed up by ghost quads, and how to place its ghost points.

    mesh : HalfEdgeMesh with V + G vertices and F + B faces (ghost faces last)
    real_face : (F + B,) bool
    points_matrix : (V + G, V) csr_matrix, ghosted points = points_matrix @ points
    """

    mesh: HalfEdgeMesh
    real_face: np.ndarray
    points_matrix: csr_matrix


def add_ghost_layer(mesh: HalfEdgeMesh, points: np.ndarray) -> GhostLayer:
    """Close every boundary loop of ``mesh`` with a ring of ghost quads.

    Parameters
    ----------
    mesh : HalfEdgeMesh, oriented, every vertex one fan (``repair.prepare_topology``)
    points : (V, 3) float, used once to tell convex from reflex single-face corners
    """
    n = mesh.n_vertices
    boundary = np.flatnonzero(mesh.twin < 0)  # half-edges a -> b with no face across
    a, b = mesh.origin[boundary], mesh.dest[boundary]
    boundary_vertices = np.unique(a)
    ghost = np.full(n, -1, dtype=np.int64)
    ghost[boundary_vertices] = n + np.arange(boundary_vertices.size)
    quads = np.stack([b, a, ghost[a], ghost[b]], axis=1)
    face_sizes = np.concatenate([mesh.face_sizes, np.full(boundary.size, 4)])
    face_vertices = np.concatenate([mesh.origin, quads.ravel()])
    ghosted = build_halfedges(face_sizes, face_vertices, n + boundary_vertices.size)
    real_face = np.r_[np.ones(mesh.n_faces, bool), np.zeros(boundary.size, bool)]
    return GhostLayer(ghosted, real_face, ghost_points_matrix(mesh, boundary_vertices, ghost, points))


def ghost_points_matrix(mesh: HalfEdgeMesh, boundary_vertices: np.ndarray, ghost: np.ndarray, points: np.ndarray) -> csr_matrix:
    """(V + G, V) matrix: real points unchanged, ghost a' = 2 a - m(a).

    m(a) is the mean of the neighbours of a along interior edges. A vertex in a
    single face (a corner) has none: at a convex corner m(a) is the face's
    centroid; at a reflex one (which the centroid rule would push into the
    face) a' = x + y - a completes the parallelogram of its two neighbours
    into the notch. Convex or reflex is decided once, from ``points``; the
    matrix is then fixed, so ``update_points`` stays a sparse product.
    """
    n = mesh.n_vertices
    g = boundary_vertices.size
    interior = mesh.twin >= 0
    # neighbours along interior edges: each interior edge appears once per direction
    src, dst = mesh.origin[interior], mesh.dest[interior]
    is_boundary_vertex = ghost >= 0
    keep = is_boundary_vertex[src]
    src, dst = src[keep], dst[keep]
    count = np.bincount(src, minlength=n)
    rows = [np.arange(n), ghost[boundary_vertices], ghost[src]]
    cols = [np.arange(n), boundary_vertices, dst]
    vals = [np.ones(n), np.full(g, 2.0), -1.0 / count[src]]
    corners = boundary_vertices[count[boundary_vertices] == 0]
    reflex = corners[reflex_corner(mesh, corners, points)]
    corners = np.setdiff1d(corners, reflex)
    if reflex.size:
        h = np.flatnonzero(np.isin(mesh.origin, reflex))  # the one half-edge leaving each
        rows += [ghost[reflex]] * 3
        cols += [mesh.origin[h], mesh.dest[h], mesh.origin[mesh.prev[h]]]
        vals += [np.full(reflex.size, -1.0), np.ones(reflex.size), np.ones(reflex.size)]
    if corners.size:
        # a convex corner lies in one face: reflect that face's centroid
        h = np.flatnonzero(np.isin(mesh.origin, corners))
        face = mesh.face[h]
        members = mesh.face_offsets[face][:, None] + np.arange(mesh.face_sizes.max())[None, :]
        valid = np.arange(mesh.face_sizes.max())[None, :] < mesh.face_sizes[face][:, None]
        rows.append(np.broadcast_to(ghost[mesh.origin[h]][:, None], members.shape)[valid])
        cols.append(mesh.origin[np.where(valid, members, 0)][valid])
        vals.append(np.broadcast_to((-1.0 / mesh.face_sizes[face])[:, None], members.shape)[valid])
    matrix = csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n + g, n))
    matrix.sum_duplicates()
    return matrix


def reflex_corner(mesh: HalfEdgeMesh, corners: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(k,) bool: is each single-face corner vertex reflex within its face?

    The turn x -> a -> y is compared with the face's (Newell) normal.
    """
    if corners.size == 0:
        return np.zeros(0, dtype=bool)
    h = np.flatnonzero(np.isin(mesh.origin, corners))
    order = np.argsort(mesh.origin[h])
    h = h[order][np.searchsorted(mesh.origin[h][order], corners)]
    a, y, x = points[mesh.origin[h]], points[mesh.dest[h]], points[mesh.origin[mesh.prev[h]]]
    corner_points = points[mesh.origin]
    nxt = corner_points[mesh.next]
    newell = np.cross(corner_points, nxt)  # sum over a face of p_k x p_k+1 is twice its area vector
    normal = np.zeros((mesh.n_faces, 3))
    np.add.at(normal, mesh.face, newell)
    turn = np.einsum("ij,ij->i", np.cross(a - x, y - a), normal[mesh.face[h]])
    return turn < 0
