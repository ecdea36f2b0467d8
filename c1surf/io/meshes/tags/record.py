"""The sharp-feature tags read from a mesh file, and their checks against the mesh.

``prepare.features`` turns them into the construction's ``SharpFeatures`` (creases,
corners, holes) and names in a note every tag that is not honoured.
"""

from __future__ import annotations

import numpy as np

from ....mesh.creases.tags import SharpTags
from ....mesh.halfedges import mesh_edge_keys
from ...errors import MeshInputError

__all__ = ["SharpTags", "check_tags", "mesh_edge_keys"]  # the first and last re-exported from mesh


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
