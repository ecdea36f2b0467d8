"""Errors the construction raises for input it cannot handle."""
from __future__ import annotations

import numpy as np


class TopologyError(ValueError):
    """The mesh's connectivity violates a precondition of the construction.

    Attributes
    ----------
    message : str
        one line: what is wrong and what to do.
    faces : (k,) int
        indices of the input faces involved (for OBJ line numbers), possibly empty.

    vertices : (m,) int
        vertex indices (0-based) that ``message`` refers to as ``{0}``, ``{1}``...

    Use ``describe(vertex_base=1)`` to print vertex numbers as an OBJ file counts them.
    """

    def __init__(self, message: str, faces=(), vertices=()):
        self.template = message
        self.faces = np.asarray(faces, dtype=np.int64).ravel()
        self.vertices = [int(v) for v in np.asarray(vertices, dtype=np.int64).ravel()]
        self.message = self.describe(0)
        super().__init__(self.message)

    def describe(self, vertex_base: int = 0) -> str:
        """The message with vertex numbers counted from ``vertex_base``."""
        return self.template.format(*(v + vertex_base for v in self.vertices))
