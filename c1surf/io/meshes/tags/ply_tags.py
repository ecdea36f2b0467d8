"""Sharp-feature tags of a PLY file: an ``edge`` element with ``vertex1 vertex2 crease``, vertex ``corner``/``sharpness``."""

from __future__ import annotations

import numpy as np

from ...errors import MeshInputError
from .record import SharpTags

__all__ = ["ply_tags"]

CORNER_NAMES = ("corner", "sharpness")  # per-vertex sharpness, the first present is read


def ply_tags(path: str, vertex_data: np.ndarray, edge_data: np.ndarray | None, line_of) -> SharpTags:
    """The tags of a PLY file (not yet checked against the mesh: see ``check_tags``).

    Parameters
    ----------
    path : str
        The file, for error messages.
    vertex_data : structured ndarray, shape (V,)
        The ``vertex`` element's rows; a ``corner`` (else ``sharpness``) property > 0 tags a corner.
    edge_data : structured ndarray, shape (E,), or None
        The ``edge`` element's rows, or None when there is none; read only when it has ``vertex1``,
        ``vertex2`` and ``crease``, and then every edge with crease > 0 is a crease.
    line_of : callable (element name, row) -> 1-based line or None (binary)

    Returns
    -------
    SharpTags
        Sharpness as written (no rescaling); lines as ``line_of`` gives them.
    """
    tags = SharpTags()
    names = set(edge_data.dtype.names or ()) if edge_data is not None else set()
    if {"vertex1", "vertex2", "crease"} <= names:
        crease = _column(path, edge_data, "crease", "edge", line_of)
        rows = np.flatnonzero(crease != 0)  # NaN kept: check_tags refuses it with its line
        ends = np.stack([_column(path, edge_data, n, "edge", line_of)[rows] for n in ("vertex1", "vertex2")], axis=1)
        whole = ends == np.round(ends)
        if not whole.all():
            row = int(rows[np.argmax(~whole.all(axis=1))])
            raise MeshInputError(path, f"edge {row} has a vertex index that is not a whole number: declare "
                                 "vertex1 and vertex2 as integers", line_of("edge", row))
        tags.crease_edges, tags.crease_sharpness = ends.astype(np.int64), crease[rows]
        tags.crease_lines = _lines(line_of, "edge", rows)
    name = next((n for n in CORNER_NAMES if n in (vertex_data.dtype.names or ())), None)
    if name is not None:
        corner = _column(path, vertex_data, name, "vertex", line_of)
        rows = np.flatnonzero(corner != 0)
        tags.corner_vertices, tags.corner_sharpness = rows.astype(np.int64), corner[rows]
        tags.corner_lines = _lines(line_of, "vertex", rows)
    return tags


def _column(path: str, data: np.ndarray, name: str, element: str, line_of) -> np.ndarray:
    """One scalar property as float64, shape (N,); refuses a list property."""
    col = data[name]
    if col.dtype == object:
        raise MeshInputError(path, f"'{element}' property '{name}' is a list, expected a single number: fix the "
                             "header", line_of(element, 0) if len(col) else None)
    return np.array(col, dtype=np.float64)


def _lines(line_of, element: str, rows: np.ndarray):
    """(R,) int64 lines of ``rows`` of ``element``, or None for a binary file."""
    if rows.size == 0 or line_of(element, 0) is None:
        return None
    return np.array([line_of(element, r) for r in rows.tolist()], dtype=np.int64)
