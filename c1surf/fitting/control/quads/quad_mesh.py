"""A pure-quad mesh made for local operations: topology built once, then changed in place, one edit at a time.

``QuadMesh`` holds plain arrays: ``quads`` (F, 4) int64 counter-clockwise, ``alive`` (F,) bool (an operation that
removes faces leaves dead slots; no slot is ever added), ``points`` (V, 3) float64, and the vertex-to-face table
``vertex_faces`` (V, cap) int64 with ``counts`` (V,) int64 (a vertex without faces is gone). The table is built
once by sorting (``from_quads``); the compiled operations (``operations``) update the rows they touch. The face
across an edge and a vertex's rim status are read from it (``links``) in the time of a vertex's valence.
``arrays()`` returns the live faces and used points, renumbered.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["QuadMesh", "MIN_CAPACITY"]

MIN_CAPACITY = 24  # faces a vertex may hold at most (at least twice the start's largest valence)


@dataclass
class QuadMesh:
    """A pure-quad mesh for local operations (module docstring)."""

    quads: np.ndarray
    alive: np.ndarray
    points: np.ndarray
    vertex_faces: np.ndarray
    counts: np.ndarray

    @classmethod
    def from_quads(cls, quads: np.ndarray, points: np.ndarray) -> "QuadMesh":
        """The mesh of ``quads`` (F, 4) int over ``points`` (V, 3) float; the table sorted once."""
        quads = np.ascontiguousarray(quads, dtype=np.int64).reshape(-1, 4)
        points = np.array(points, dtype=np.float64, order="C").reshape(-1, 3)
        vertex = quads.ravel()
        counts = np.bincount(vertex, minlength=points.shape[0]).astype(np.int64)
        cap = max(MIN_CAPACITY, 2 * int(counts.max(initial=0)))
        order = np.argsort(vertex, kind="stable")
        start = np.concatenate([[0], np.cumsum(counts)[:-1]])
        slot = np.arange(vertex.size) - start[vertex[order]]
        table = np.full((points.shape[0], cap), -1, dtype=np.int64)
        table[vertex[order], slot] = order // 4
        return cls(quads.copy(), np.ones(quads.shape[0], dtype=bool), points, table, counts)

    @property
    def n_faces(self) -> int:
        """The live faces."""
        return int(self.alive.sum())

    def live_quads(self) -> np.ndarray:
        """(F', 4) int64: the live faces in the old vertex numbering."""
        return self.quads[self.alive]

    def arrays(self):
        """(quads (F', 4) int64, points (V', 3) float64): the live faces over the used points, renumbered."""
        quads = self.live_quads()
        used = np.zeros(self.points.shape[0], dtype=bool)
        used[quads] = True
        rank = np.cumsum(used) - 1
        return rank[quads], self.points[used].copy()

    def state(self):
        """The arrays the compiled operations take, in their order: quads, alive, vertex_faces, counts, points."""
        return self.quads, self.alive, self.vertex_faces, self.counts, self.points
