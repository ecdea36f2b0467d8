"""Feature edges by dihedral angle, for meshes that carry no crease tags (``--crease-angle``).

Geometry on plain arrays, read once: the edges found become creases, which are
topology from then on (moving the points later does not re-detect them).
"""
from __future__ import annotations

import numpy as np


def face_normals(face_sizes: np.ndarray, face_vertices: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(F, 3) float: unit Newell normals of polygon faces (zero rows for degenerate faces).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    points : (V, 3) float
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(face_sizes)])
    face = np.repeat(np.arange(face_sizes.size), face_sizes)
    local = np.arange(offsets[-1]) - offsets[face]
    following = offsets[face] + (local + 1) % face_sizes[face]
    p = points[face_vertices, :3]
    newell = np.zeros((face_sizes.size, 3))
    np.add.at(newell, face, np.cross(p, points[face_vertices[following], :3]))
    length = np.linalg.norm(newell, axis=1, keepdims=True)
    return np.divide(newell, length, out=np.zeros_like(newell), where=length > 0)


def feature_edges(face_sizes: np.ndarray, face_vertices: np.ndarray, points: np.ndarray, angle_degrees: float) -> np.ndarray:
    """Edges whose two faces meet at a dihedral angle above ``angle_degrees``.

    The angle is between the two faces' normals, oriented along the edge (two faces
    that run along it the same way, an inconsistently oriented pair, count as
    oriented); edges in one face or in more than two are never features.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    points : (V, 3) float
    angle_degrees : float in [0, 180)

    Returns
    -------
    (E, 2) int64, sorted vertex pairs (smaller first), in increasing order
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(face_sizes)])
    face = np.repeat(np.arange(face_sizes.size), face_sizes)
    local = np.arange(offsets[-1]) - offsets[face]
    a = face_vertices
    b = face_vertices[offsets[face] + (local + 1) % face_sizes[face]]
    n_vertices = int(max(a.max(initial=0), b.max(initial=0))) + 1
    key = np.minimum(a, b) * n_vertices + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    unique, start, count = np.unique(key[order], return_index=True, return_counts=True)
    pair = count == 2
    h1, h2 = order[start[pair]], order[start[pair] + 1]
    normals = face_normals(face_sizes, face_vertices, points)
    sign = np.where(a[h1] == a[h2], -1.0, 1.0)  # same direction: one face is flipped
    cosine = sign * np.einsum("ij,ij->i", normals[face[h1]], normals[face[h2]])
    sharp = cosine < np.cos(np.radians(angle_degrees))
    keys = unique[pair][sharp]
    return np.stack([keys // n_vertices, keys % n_vertices], axis=1)


__all__ = ["face_normals", "feature_edges"]
