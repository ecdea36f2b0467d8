"""The sharp-feature tags read from a mesh file, and their checks against the mesh.

``tags.features`` turns them into the construction's ``SharpFeatures`` (creases,
corners, holes) and names in a note every tag that is not honoured.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ....arrays import unique_integers
from ...errors import MeshInputError

__all__ = ["SharpTags", "check_tags", "mesh_edge_keys"]


def _ints(n: int = 0) -> np.ndarray:
    return np.zeros(n, dtype=np.int64)


@dataclass(eq=False)  # eq on numpy fields would be ambiguous
class SharpTags:
    """Creases, corners, holes and other tags as written in a mesh file (indices from 0).

    Attributes
    ----------
    crease_edges : ndarray, shape (E, 2), int64
        Vertex pairs of the crease edges (an OBJ chain ``t crease k/1/0`` gives k - 1 rows).
    crease_sharpness : ndarray, shape (E,), float64
        Sharpness of each crease edge as written (OpenSubdiv: 0 smooth, >= 10 infinitely sharp).
    crease_lines : ndarray, shape (E,), int64, or None
        1-based line of each crease edge's tag (text files), else None.
    corner_vertices : ndarray, shape (C,), int64
    corner_sharpness : ndarray, shape (C,), float64
    corner_lines : ndarray, shape (C,), int64, or None
    hole_faces : ndarray, shape (H,), int64
        Faces tagged as holes, in file order of the faces.
    hole_lines : ndarray, shape (H,), int64, or None
    interpolate_boundary : int or None
        OpenSubdiv ``interpolateboundary`` mode (0 none, 1 edges and corners, 2 edges only), None when absent.
    other : list of (str, int or None)
        Name and line of every other tag (``creasemethod``, ``vertexedit``, ...), kept by name.
    """

    crease_edges: np.ndarray = field(default_factory=lambda: _ints(0).reshape(0, 2))
    crease_sharpness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    crease_lines: np.ndarray | None = None
    corner_vertices: np.ndarray = field(default_factory=_ints)
    corner_sharpness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    corner_lines: np.ndarray | None = None
    hole_faces: np.ndarray = field(default_factory=_ints)
    hole_lines: np.ndarray | None = None
    interpolate_boundary: int | None = None
    other: list = field(default_factory=list)

    def is_empty(self) -> bool:
        """True when the file carries no tag at all."""
        return not (len(self.crease_edges) or len(self.corner_vertices) or len(self.hole_faces)
                    or self.interpolate_boundary is not None or self.other)

    def summary(self) -> str:
        """Every tag kind read, with counts, e.g. ``crease (12 edges), corner (3 vertices), interpolateboundary 1``.

        Other tags are named, with the number of their lines; "" when there are no tags.
        """
        parts = []
        for name, count, unit in (("crease", len(self.crease_edges), "edge"),
                                  ("corner", len(self.corner_vertices), "vertex"),
                                  ("hole", len(self.hole_faces), "face")):
            if count:
                units = "vertices" if unit == "vertex" and count != 1 else unit + ("s" if count != 1 else "")
                parts.append(f"{name} ({count} {units})")
        if self.interpolate_boundary is not None:
            parts.append(f"interpolateboundary {self.interpolate_boundary}")
        counts: dict[str, int] = {}
        for name, _ in self.other:
            counts[name] = counts.get(name, 0) + 1
        parts.extend(f"{name} ({n} tag{'s' if n != 1 else ''})" for name, n in counts.items())
        return ", ".join(parts)


def mesh_edge_keys(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> np.ndarray:
    """Sorted unique keys ``min * V + max`` of the mesh's undirected edges.

    Parameters
    ----------
    face_sizes : ndarray, shape (F,), int
    face_vertices : ndarray, shape (sum(face_sizes),), int
    n_vertices : int, V

    Returns
    -------
    ndarray, shape (number of edges,), int64
    """
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    offs = np.zeros(len(face_sizes) + 1, dtype=np.int64)
    np.cumsum(face_sizes, out=offs[1:])
    nxt = np.arange(1, face_vertices.size + 1)
    nonempty = np.asarray(face_sizes) > 0
    nxt[offs[1:][nonempty] - 1] = offs[:-1][nonempty]
    a, b = face_vertices, face_vertices[nxt] if face_vertices.size else face_vertices
    return unique_integers(np.minimum(a, b) * n_vertices + np.maximum(a, b))


def check_tags(tags: SharpTags, face_sizes, face_vertices, n_vertices: int, path: str) -> None:
    """Refuse the first tag (in file order of its kind) naming a vertex or face that is not there.

    Checks, in this order: crease and corner vertices in 0 .. V - 1, crease pairs that are
    edges of the mesh, hole faces in 0 .. F - 1, sharpness finite and >= 0.

    Parameters
    ----------
    tags : SharpTags
    face_sizes : ndarray, shape (F,), int
    face_vertices : ndarray, shape (sum(face_sizes),), int
    n_vertices : int, V

    Raises
    ------
    MeshInputError
        ``FILE:LINE: what and why`` (no line for a binary file).
    """
    n_faces = len(face_sizes)
    _refuse(path, tags.crease_lines, ((tags.crease_edges < 0) | (tags.crease_edges >= n_vertices)).any(axis=1),
            lambda i: f"crease names vertex {_outside(tags.crease_edges[i], n_vertices)} but the file has "
                      f"{n_vertices} vertices (tags count from 0: valid 0..{n_vertices - 1}): fix the index")
    _refuse(path, tags.corner_lines, (tags.corner_vertices < 0) | (tags.corner_vertices >= n_vertices),
            lambda i: f"corner names vertex {int(tags.corner_vertices[i])} but the file has {n_vertices} vertices "
                      f"(tags count from 0: valid 0..{n_vertices - 1}): fix the index")
    if len(tags.crease_edges):
        keys = np.minimum(*tags.crease_edges.T) * n_vertices + np.maximum(*tags.crease_edges.T)
        edges = mesh_edge_keys(face_sizes, face_vertices, n_vertices)
        _refuse(path, tags.crease_lines, ~np.isin(keys, edges),
                lambda i: f"crease pair {int(tags.crease_edges[i, 0])} {int(tags.crease_edges[i, 1])} is not an edge "
                          "of the mesh (no face has these two vertices next to each other; tags count vertices "
                          "from 0): fix the tag")
    _refuse(path, tags.hole_lines, (tags.hole_faces < 0) | (tags.hole_faces >= n_faces),
            lambda i: f"hole names face {int(tags.hole_faces[i])} but the file has {n_faces} faces "
                      f"(tags count from 0: valid 0..{n_faces - 1}): fix the index")
    for what, values, lines in (("crease", tags.crease_sharpness, tags.crease_lines),
                                ("corner", tags.corner_sharpness, tags.corner_lines)):
        _refuse(path, lines, ~np.isfinite(values) | (values < 0),
                lambda i, what=what, values=values: f"{what} sharpness {values[i]:g} is not a number >= 0 "
                                                    "(0 smooth, 10 or more infinitely sharp): fix the value")


def _outside(pair, n_vertices: int) -> int:
    """The first vertex of ``pair`` outside 0 .. n_vertices - 1."""
    return int(next(v for v in pair if not 0 <= v < n_vertices))


def _refuse(path: str, lines, bad: np.ndarray, message) -> None:
    """Raise ``message(i)`` at the first ``i`` where ``bad`` holds, with its line when known."""
    if bad.any():
        i = int(np.argmax(bad))
        raise MeshInputError(path, message(i), None if lines is None else int(lines[i]))
