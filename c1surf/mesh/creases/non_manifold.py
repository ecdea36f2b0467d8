"""Non-manifold edges cut into manifold sheets that meet along one C0 crease (integers only).

The paper needs at most two faces on an edge. Where more meet (a fin standing on a plate, the pages
of a book, ``catmark_fan``), c1surf gives every *sheet* its own copy of the edge: the faces around a
vertex are grouped into fans across the edges they share with exactly one other face, and every fan
but the first at a vertex on a non-manifold edge gets a copy of the vertex (same position, a new
number). Each sheet is then an open manifold mesh whose boundary runs along the non-manifold edges.
Where every sheet holds the edge in two faces (two closed surfaces that share an edge's vertices) the
sheets only touch there and stay apart. Otherwise the caller makes the edge an infinitely sharp crease
of every sheet (``SheetSplit.seams``): the C0 crease cuts and mirrors
a boundary that a crease reaches (``sheets``), so every sheet's boundary curve there is the same
curve of the edge polyline alone, and the sheets meet along it exactly.

So that every sheet builds the same curve, a vertex of the non-manifold polyline is a corner in all
sheets where it is one in any: where the polyline ends or branches, and where a sheet has one face
at it (a boundary vertex in one face is a corner of the boundary curve).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..halfedges import build_halfedges, component_roots


@dataclass(frozen=True)
class SheetSplit:
    """What ``split_non_manifold_edges`` did.

    face_vertices : (H,) int, the faces' corners with the copies (face sizes unchanged)
    vertex_source : (V',) int, the vertex each vertex copies (``arange(V)`` first, then the copies')
    edges : (k, 2) int, the non-manifold edges (input numbering, smaller vertex first)
    seams : (s, 2) int, of those, the edges some sheet holds in one face (its boundary): creases of every
        sheet; the others are held by every sheet in two faces, sheets that only touch there
    corners : (c,) int, input vertices that are corners of the sheets' common curves
    """

    face_vertices: np.ndarray
    vertex_source: np.ndarray
    edges: np.ndarray
    seams: np.ndarray
    corners: np.ndarray


def _edge_in_three_faces(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> bool:
    """Whether some edge (unordered vertex pair of consecutive corners) is a side of three or more faces: the sorted
    keys of the sides hold a key three times in a row (0.07 s of half-edges and np.unique on the 180,000-quad torus
    before, 0.02 s now)."""
    if face_vertices.size == 0:
        return False
    if face_sizes.min() < 1:
        return True  # no such faces reach here (the reader refuses them); if one did, the full test decides
    nxt = np.arange(1, face_vertices.size + 1)
    ends = np.cumsum(face_sizes)
    nxt[ends - 1] = ends - face_sizes  # a face's last corner goes back to its first
    a, b = face_vertices, face_vertices[nxt]
    key = np.minimum(a, b) * n_vertices + np.maximum(a, b)
    key.sort()
    return bool(np.any(key[2:] == key[:-2]))


def split_non_manifold_edges(face_sizes, face_vertices, n_vertices: int) -> SheetSplit | None:
    """Give every sheet at a non-manifold edge its own vertices there (module docstring).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    n_vertices : int

    Returns
    -------
    SheetSplit, or None when no edge is in more than two faces.
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    if not _edge_in_three_faces(face_sizes, face_vertices, n_vertices):
        return None  # every mesh without such edges stops here (one sort), before the half-edges and the tests below
    mesh = build_halfedges(face_sizes, face_vertices, n_vertices)
    a, b = mesh.origin, mesh.dest
    key = np.minimum(a, b) * n_vertices + np.maximum(a, b)
    unique, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    per_half = counts[inverse.ravel()]
    if _repeated_vertex_sets(face_sizes, face_vertices):
        return None  # a face listed twice (with both orientations) is no sheet: the repair refuses it by its lines
    # corners (half-edge h: the corner at origin[h] in face[h]) joined across edges in exactly two faces,
    # whichever way the two run (orientation is repaired later)
    two = np.flatnonzero(per_half == 2)
    order = two[np.argsort(key[two], kind="stable")]
    h1, h2 = order[0::2], order[1::2]
    opposite = a[h1] == b[h2]
    first = np.r_[h1, mesh.next[h1]]
    second = np.r_[np.where(opposite, mesh.next[h2], h2), np.where(opposite, h2, mesh.next[h2])]
    fan = component_roots(mesh.n_halfedges, first, second)
    on_edge = np.zeros(n_vertices, dtype=bool)
    bad = per_half > 2
    on_edge[a[bad]] = True
    on_edge[b[bad]] = True
    # every fan at such a vertex after its first gets a copy
    corners = np.flatnonzero(on_edge[a])
    fans, first_corner = np.unique(fan[corners], return_index=True)
    owner = a[corners][first_corner]
    rank = np.zeros(fans.size, dtype=np.int64)
    by_vertex = np.lexsort((fans, owner))
    start = np.r_[True, owner[by_vertex][1:] != owner[by_vertex][:-1]]
    position = np.arange(fans.size) - np.maximum.accumulate(np.where(start, np.arange(fans.size), 0))
    rank[by_vertex] = position
    copies = rank > 0
    new_id = np.where(copies, n_vertices + np.cumsum(copies) - 1, owner)
    fan_slot = np.searchsorted(fans, fan[corners])
    vertices = face_vertices.copy()
    vertices[corners] = new_id[fan_slot]
    source = np.r_[np.arange(n_vertices), owner[copies]]
    edges = np.stack([unique[counts > 2] // n_vertices, unique[counts > 2] % n_vertices], axis=1)
    seams = edges[_held_once(face_sizes, vertices, source, edges, n_vertices)]
    return SheetSplit(vertices, source, edges, seams, _sheet_corners(face_sizes, vertices, source, seams, n_vertices))


def _held_once(face_sizes, vertices, source, edges, n_vertices: int) -> np.ndarray:
    """(k,) bool: the non-manifold ``edges`` (input numbering) of which some copy lies in one face only."""
    split = build_halfedges(face_sizes, vertices, source.size)
    lone = split.twin < 0
    a, b = source[split.origin[lone]], source[split.dest[lone]]
    return np.isin(edges[:, 0] * n_vertices + edges[:, 1], np.minimum(a, b) * n_vertices + np.maximum(a, b))


def _repeated_vertex_sets(face_sizes: np.ndarray, face_vertices: np.ndarray) -> bool:
    """True when two faces have the same vertices (in any order): one face listed twice."""
    offsets = np.r_[0, np.cumsum(face_sizes)]
    for k in np.unique(face_sizes):  # one sort per face size
        rows = np.sort(face_vertices[offsets[:-1][face_sizes == k][:, None] + np.arange(k)], axis=1)
        if np.unique(rows, axis=0).shape[0] < rows.shape[0]:
            return True
    return False


def _sheet_corners(face_sizes, vertices, source, edges, n_vertices: int) -> np.ndarray:
    """(c,) int: vertices of the non-manifold polylines that are corners of the common curve: ends and
    branch points of the polylines (not on 2 of their edges), and vertices a sheet holds in one face."""
    degree = np.bincount(edges.ravel(), minlength=n_vertices)
    on_line = degree > 0
    faces_at = np.bincount(vertices, minlength=source.size)  # faces at every vertex copy
    lone = np.zeros(n_vertices, dtype=bool)
    lone[source[faces_at == 1]] = True
    return np.flatnonzero(on_line & ((degree != 2) | lone))


__all__ = ["SheetSplit", "split_non_manifold_edges"]
