"""Interior vertices of valence 2: dissolved into the edge they split.

An interior vertex v in just two faces makes a 2-sided cell after refinement,
which A3 cannot fill (c = cos(2 pi / 2) = -1). Such a vertex splits an edge
a - v - b that its two faces share: c1surf takes v out of both faces, so they
share the edge a - b instead. A face that would keep fewer than three corners
(a triangle a, v, b) is dropped, and its third edge b - a is then the edge the
other face shares with the face beyond it: orientation and manifoldness are
kept. Runs of such vertices (a - v1 - v2 - b) go at once; a vertex that
becomes valence 2 by the removal goes in the next round.

What moves (measured in tests/mesh/test_valence_two.py and the corpus test):
v's position no longer enters the surface, and the faces that lost v have a
new centroid, which the surface interpolates instead of the old one; every
other face and vertex keeps its part in the construction. The rule is
integers only: positions are untouched, v stays in the point list unused.
"""
from __future__ import annotations

import numpy as np

from ..arrays import unique_integers
from .halfedges import build_halfedges


def valence_two_vertices(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> np.ndarray:
    """(k,) int: interior vertices in exactly two faces (each interior edge of theirs in two faces).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    n_vertices : int
    """
    corners = np.bincount(np.asarray(face_vertices), minlength=n_vertices)
    if not np.any(corners == 2):  # the usual mesh: no vertex has two corners, so no half-edges are needed
        return np.zeros(0, dtype=np.intp)
    mesh = build_halfedges(face_sizes, face_vertices, n_vertices)
    on_boundary = np.zeros(n_vertices, dtype=bool)
    open_edge = mesh.twin < 0
    on_boundary[mesh.origin[open_edge]] = True
    on_boundary[mesh.dest[open_edge]] = True
    faces_at = np.bincount(unique_integers(mesh.face * n_vertices + mesh.origin) % n_vertices, minlength=n_vertices)
    return np.flatnonzero((corners == 2) & (faces_at == 2) & ~on_boundary)


def dissolve_valence_two(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int, rounds: int = 8,
                         keep: np.ndarray | None = None):
    """Take every interior valence-2 vertex out of its two faces (module docstring).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    n_vertices : int
    rounds : int, how many times to look again for vertices the removal left in two faces
    keep : (V,) bool or None, vertices never dissolved (the C0 seams' after merging crease sectors: a seam
        vertex in two faces has four in its sheets)

    Returns
    -------
    face_sizes : (F',) int64
    face_vertices : (sum(face_sizes'),) int64
    kept_faces : (F,) bool, the input faces that remain (in order)
    dissolved : (k,) int64, sorted, the vertices taken out
    """
    sizes = np.asarray(face_sizes, dtype=np.int64)
    vertices = np.asarray(face_vertices, dtype=np.int64)
    kept = np.ones(sizes.size, dtype=bool)
    dissolved = []
    for _ in range(rounds):
        if sizes.size == 0:
            break
        two = valence_two_vertices(sizes, vertices, n_vertices)
        if keep is not None:
            two = two[~keep[two]]
        if two.size == 0:
            break
        dissolved.append(two)
        remove = np.zeros(n_vertices, dtype=bool)
        remove[two] = True
        face = np.repeat(np.arange(sizes.size), sizes)
        keep_corner = ~remove[vertices]
        new_sizes = np.bincount(face[keep_corner], minlength=sizes.size)
        survive = new_sizes >= 3
        vertices = vertices[keep_corner & survive[face]]
        sizes = new_sizes[survive]
        kept[np.flatnonzero(kept)[~survive]] = False
    found = np.unique(np.concatenate(dissolved)) if dissolved else np.zeros(0, dtype=np.int64)
    return sizes, vertices, kept, found


__all__ = ["valence_two_vertices", "dissolve_valence_two"]
