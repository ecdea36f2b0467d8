"""The in-memory result of reading a polygon mesh file, and the checks its readers share.

Everything that changes the mesh after reading (welding, repeated faces, valence-2 vertices, sheets, crease
sectors) is the input preparation's (``c1surf.prepare``), which takes a MeshFile and returns another.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...arrays import unique_integers
from ...mesh.creases.tags import SharpTags
from ...mesh.weld import collapse_repeated_corners
from ..errors import MeshInputError

__all__ = ["MeshFile", "collapse_repeated_corners", "collapse_repeated_corners_or_refuse", "refuse_repeated_vertex",
           "find_repeated_vertex"]


@dataclass(eq=False)  # eq on numpy fields would be ambiguous
class MeshFile:
    """A polygon mesh exactly as stored in a file (never triangulated).

    Faces are kept in a flat, "CSR"-like layout so that meshes with mixed
    face sizes need no padding: face ``i`` is
    ``face_vertices[offs[i]:offs[i + 1]]`` with ``offs = face_offsets()``.

    Attributes
    ----------
    path : str
        The file the mesh was read from.
    points : ndarray, shape (V, 3), float64
        Vertex positions, in file order.  Vertices not used by any face
        are kept (indices stay as in the file).
    face_sizes : ndarray, shape (F,), int64
        Number of vertices of each face, in file order.
    face_vertices : ndarray, shape (sum(face_sizes),), int64
        0-based vertex indices of all faces, concatenated in file order.
    face_lines : ndarray, shape (F,), int64, or None
        1-based source line of each face (text formats), else None.
    vertex_weights : ndarray, shape (V,), float64, or None
        OBJ ``v x y z w`` fourth value (1.0 where absent) or PLY vertex
        property ``weight``.
    vertex_normals : ndarray, shape (V, 3), float64, or None
        PLY ``nx ny nz``; OBJ ``vn`` referenced through ``f v//vn`` or
        ``f v/vt/vn`` (first reference of a vertex wins; NaN for vertices
        never referenced with a normal).
    vertex_uvs : ndarray, shape (V, 2), float64, or None
        PLY ``u v`` / ``s t`` / ``texture_u texture_v``; OBJ ``vt``
        referenced through ``f v/vt`` (first reference wins; NaN where
        absent).
    face_attributes : dict of str to ndarray, shape (F,)
        Extra scalar per-face properties (PLY), e.g. ``blend``.
    vertex_attributes : dict of str to ndarray, shape (V,)
        Extra scalar per-vertex properties, e.g. ``red green blue``.
    face_groups : ndarray, shape (F,), int64, or None
        Index into ``group_names`` of each face (OBJ ``g``/``o``); None
        when the file names no groups.
    group_names : list of str
        Group names in order of first use by a face.
    tags : SharpTags
        Sharp-feature tags (OBJ ``t`` lines, PLY ``edge`` creases and vertex
        ``corner``/``sharpness``), read and checked; ``prepare.features.sharp_features``
        turns them into the construction's ``SharpFeatures``. Empty when the file has none.
    collapsed_corners : int
        Repeated corners (``f a b c c``) the reader dropped.
    weld : prepare.mesh_edits.WeldReport or None
        What welding changed (``prepare.mesh_edits.weld_mesh_file``); None for a mesh as read.
    dissolved_vertices : ndarray, shape (k,), int64
        Interior valence-2 vertices taken out of their faces (``prepare.mesh_edits.dissolve_mesh_file``).
    repeated_faces : int
        Faces dropped as later copies of another face (``prepare.mesh_edits.drop_repeated_faces``).
    non_manifold_edges : ndarray, shape (k, 2), int64, or None
        Edges in more than two faces, cut into sheets with vertex copies appended to ``points``
        (``prepare.sheets.split_surface_sheets``, ``mesh.creases.non_manifold``).
    non_manifold_seams : int
        Of those, the edges the sheets meet along (C0 seams); the others only touch.
    sector_merge : tuple (merged faces, polygons, seam vertices (k,) int, crease edges merged away (d, 2) int) or None
        Crease sectors merged into polygons for exact C0 creases (``prepare.mesh_edits.merge_sector_faces``,
        ``mesh.creases.sectors``); None when nothing was merged.
    reader_notes : list of str
        One line each on input the reader ignored or dropped (OBJ ``l``/``p``
        records, ``vt``/``vn`` indices that name no record, degenerate PLY
        strip triangles), printed by the CLI as ``c1surf: note:`` lines
        (``prepare.notes.repair_notes``).
    """

    path: str
    points: np.ndarray
    face_sizes: np.ndarray
    face_vertices: np.ndarray
    face_lines: np.ndarray | None = None
    vertex_weights: np.ndarray | None = None
    vertex_normals: np.ndarray | None = None
    vertex_uvs: np.ndarray | None = None
    face_attributes: dict[str, np.ndarray] = field(default_factory=dict)
    vertex_attributes: dict[str, np.ndarray] = field(default_factory=dict)
    face_groups: np.ndarray | None = None
    collapsed_corners: int = 0
    group_names: list[str] = field(default_factory=list)
    tags: SharpTags = field(default_factory=SharpTags)
    weld: object = None
    reader_notes: list[str] = field(default_factory=list)
    dissolved_vertices: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    repeated_faces: int = 0
    sector_merge: tuple | None = None
    non_manifold_edges: np.ndarray | None = None
    non_manifold_seams: int = 0

    @property
    def n_vertices(self) -> int:
        """Number of vertices V (including unused ones)."""
        return int(self.points.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of faces F."""
        return int(self.face_sizes.shape[0])

    def face_offsets(self) -> np.ndarray:
        """Start of each face in ``face_vertices``, plus the total.

        Returns
        -------
        ndarray, shape (F + 1,), int64
            ``offs[0] == 0``, ``offs[-1] == len(face_vertices)``.
        """
        offs = np.zeros(len(self.face_sizes) + 1, dtype=np.int64)
        np.cumsum(self.face_sizes, out=offs[1:])
        return offs


def collapse_repeated_corners_or_refuse(face_sizes, face_vertices, path, line_of_face):
    """``collapse_repeated_corners``, refusing a face left with fewer than 3 vertices.

    Parameters
    ----------
    line_of_face : callable, face index -> 1-based line (or None) for the error

    Returns
    -------
    face_sizes, face_vertices, keep, collapsed : as ``collapse_repeated_corners``, plus the count dropped
    """
    sizes, vertices, keep = collapse_repeated_corners(face_sizes, face_vertices)
    collapsed = int(keep.size - keep.sum())
    if collapsed and np.any(sizes < 3):
        f = int(np.argmax(sizes < 3))
        raise MeshInputError(path, "face has fewer than 3 distinct vertices: a polygon needs at least 3 (remove this face)", line_of_face(f))
    return sizes, vertices, keep, collapsed


def refuse_repeated_vertex(face_sizes, face_vertices, path, line_of_face, face_name, vertex_base: int = 0) -> None:
    """Refuse the first face (in file order) that visits a vertex twice, in the file's own numbering.

    Parameters
    ----------
    line_of_face : callable, face index -> 1-based line (or None) for the error
    face_name : callable, face index -> how the message names it ("face", "face 7")
    vertex_base : 1 where the file numbers vertices from 1 (OBJ)
    """
    repeat = find_repeated_vertex(face_sizes, face_vertices)
    if repeat is not None:
        face, vertex, first, second = repeat
        raise MeshInputError(
            path, f"{face_name(face)} visits vertex {vertex + vertex_base} twice (corners {first + 1} and {second + 1}): "
            "a polygon must not repeat a vertex; remove the duplicate or split the face", line_of_face(face))


def find_repeated_vertex(face_sizes: np.ndarray, face_vertices: np.ndarray):
    """Find the first face (in file order) that visits a vertex twice.

    Parameters
    ----------
    face_sizes : ndarray, shape (F,), int
    face_vertices : ndarray, shape (sum(face_sizes),), int

    Returns
    -------
    tuple (face, vertex, first_pos, second_pos) or None
        ``face`` index, the repeated ``vertex`` value, and its first two
        0-based positions within the face; None if no face repeats one.
    """
    face_sizes = np.asarray(face_sizes)
    if face_sizes.size == 0:
        return None
    offs = np.zeros(len(face_sizes) + 1, dtype=np.int64)
    np.cumsum(face_sizes, out=offs[1:])
    bad_faces = []
    # One (n_k, k) block per distinct size: a row-wise sort is far cheaper
    # than a global lexsort, and real meshes have only a few sizes.
    for k in unique_integers(face_sizes):
        if k < 2:
            continue
        rows = np.flatnonzero(face_sizes == k)
        block = face_vertices[offs[rows][:, None] + np.arange(k)]
        block.sort(axis=1)
        dup = (block[:, 1:] == block[:, :-1]).any(axis=1)
        if dup.any():
            bad_faces.append(rows[np.argmax(dup)])
    if not bad_faces:
        return None
    face = int(min(bad_faces))
    verts = face_vertices[offs[face]:offs[face + 1]]
    seen = {}
    for pos, v in enumerate(verts.tolist()):  # one small face only
        if v in seen:
            return face, v, seen[v], pos
        seen[v] = pos
    raise AssertionError("unreachable: duplicate not found again")
