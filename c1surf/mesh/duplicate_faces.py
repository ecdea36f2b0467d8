"""Faces listed twice: the same cycle of vertices again.

A repeated face (an STL facet written twice, a face exported once per
material) puts three or four faces on each of its edges, which the
construction refuses; the later copy carries no information, so c1surf drops
it and says so. A face listed with both orientations is dropped the same way
when the two copies make a closed pillow of their own (a two-sided card: every
edge of theirs in just those two faces). Otherwise the reversed copy is part of
the surface (a thin tent along an edge, whose apex is a valence-2 vertex that
``valence_two`` dissolves) and both stay.
"""
from __future__ import annotations

import numpy as np

from ..arrays import unique_integers


def repeated_faces(face_sizes: np.ndarray, face_vertices: np.ndarray) -> np.ndarray:
    """(F,) bool: later copies of a face's cycle (up to rotation), or of its reversal where the two make a pillow.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int

    Returns
    -------
    (F,) bool, True for the faces to drop (file order: the first copy stays)
    """
    sizes = np.asarray(face_sizes, dtype=np.int64)
    vertices = np.asarray(face_vertices, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    repeated = np.zeros(sizes.size, dtype=bool)
    if not _may_repeat(sizes, vertices, offsets):  # the usual mesh: its sorts below are skipped
        return repeated
    on_edge = _faces_per_edge(sizes, vertices, offsets)
    for n in unique_integers(sizes):  # one array per face size: (k, n) cycles
        faces = np.flatnonzero(sizes == n)
        cycles = vertices[offsets[faces][:, None] + np.arange(n)]
        forward, backward = _least_rotation(cycles), _least_rotation(cycles[:, ::-1])
        repeated[faces[_later_copies(forward)]] = True  # the same orientation: always a copy
        flipped = _lexicographic_less_equal(backward, forward)
        canonical = np.where(flipped[:, None], backward, forward)
        copy = _later_copies(canonical) & ~repeated[faces]
        # a reversed copy goes only where the two faces are all there is on each of its edges
        pillow = copy & (on_edge[offsets[faces][:, None] + np.arange(n)] == 2).all(axis=1)
        repeated[faces[pillow]] = True
    return repeated


def _may_repeat(sizes: np.ndarray, vertices: np.ndarray, offsets: np.ndarray) -> bool:
    """False when no two faces have the same vertices (in any order): then no face repeats another.

    Two such faces have the same size, smallest and largest vertex, and sum and sum of squares of
    their vertices, so the same hash of these; different faces rarely do. One sort of the hashes
    (4 ms for 180,000 faces) then stands for the three sorts of ``repeated_faces``' rows (110 ms).
    """
    if sizes.size < 2:
        return False
    if not np.all(sizes > 0):
        return True  # empty faces: let the sorts decide
    starts = offsets[:-1]
    v = vertices.astype(np.uint64)
    with np.errstate(over="ignore"):  # a hash: wrapping around is fine
        key = sizes.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
        parts = (np.minimum.reduceat(v, starts), np.maximum.reduceat(v, starts), np.add.reduceat(v, starts),
                 np.add.reduceat(v * v, starts))
        for part, odd in zip(parts, (0xBF58476D1CE4E5B9, 0x94D049BB133111EB, 0xD6E8FEB86659FD93, 0xA5CB9243F9C4A1A7)):
            key = (key ^ part) * np.uint64(odd)
    key.sort()
    return bool(np.any(key[1:] == key[:-1]))


def _later_copies(rows: np.ndarray) -> np.ndarray:
    """(k,) bool: rows equal to an earlier row."""
    _, first = np.unique(rows, axis=0, return_index=True)
    later = np.ones(rows.shape[0], dtype=bool)
    later[first] = False  # np.unique gives the first occurrence of every row
    return later


def _faces_per_edge(sizes: np.ndarray, vertices: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(H,) int: for every corner, the number of corners on its edge (corner -> next corner), both directions."""
    face = np.repeat(np.arange(sizes.size), sizes)
    following = vertices[offsets[face] + (np.arange(vertices.size) - offsets[face] + 1) % sizes[face]]
    n = int(vertices.max(initial=0)) + 1
    key = np.minimum(vertices, following) * n + np.maximum(vertices, following)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    return counts[inverse]


def _least_rotation(cycles: np.ndarray) -> np.ndarray:
    """(k, n): each row rotated to start at its smallest vertex (a face visits a vertex once)."""
    start = np.argmin(cycles, axis=1)
    n = cycles.shape[1]
    return np.take_along_axis(cycles, (start[:, None] + np.arange(n)) % n, axis=1)


def _lexicographic_less_equal(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(k,) bool: row a[i] <= row b[i] in lexicographic order."""
    differ = a != b
    first = np.argmax(differ, axis=1)
    rows = np.arange(a.shape[0])
    return ~differ.any(axis=1) | (a[rows, first] < b[rows, first])


__all__ = ["repeated_faces"]
