"""Edits of a MeshFile that keep its per-face and per-vertex data in step: welding, repeated faces,
interior valence-2 vertices, merged crease sectors (the integer work is ``mesh/``'s; the MeshFile fields follow here).

Each returns the edited mesh (``dataclasses.replace`` of the one given, with the report field set) and which
faces it kept, so that ``prepare.renumber`` can carry the construction's per-face data along.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import MeshInputError
from ..mesh.creases.sectors import merge_crease_sectors
from ..mesh.duplicate_faces import repeated_faces
from ..mesh.valence_two import dissolve_valence_two
from ..mesh.weld import weld_vertices

__all__ = ["WeldReport", "weld_mesh_file", "drop_repeated_faces", "dissolve_mesh_file", "merge_sector_faces"]


@dataclass(frozen=True)
class WeldReport:
    """What welding changed in a MeshFile (``c1surf: note:`` lines).

    tolerance : float, relative to the bounding-box diagonal; 0 for equal positions
    welded_vertices : int, used vertices merged into another one at their position
    unwelded_vertices : int, positions kept as several vertices so that no edge lies in more than two faces
    dropped_faces : int, faces welding left with fewer than 3 corners
    """

    tolerance: float = 0.0
    welded_vertices: int = 0
    unwelded_vertices: int = 0
    dropped_faces: int = 0


def drop_repeated_faces(mesh: MeshFile):
    """The mesh without faces that repeat an earlier face (``mesh.duplicate_faces.repeated_faces``).

    Returns
    -------
    mesh : MeshFile with ``repeated_faces`` set (per-face data of the dropped faces removed)
    kept_faces : (F,) bool
    """
    repeated = repeated_faces(mesh.face_sizes, mesh.face_vertices)
    kept = ~repeated
    if not repeated.any():
        return mesh, kept
    return _keep_faces(mesh, kept, mesh.face_vertices[np.repeat(kept, mesh.face_sizes)], mesh.face_sizes[kept],
                       repeated_faces=int(repeated.sum())), kept


def _keep_faces(mesh, kept: np.ndarray, face_vertices: np.ndarray, face_sizes: np.ndarray, **fields):
    """``mesh`` with new faces, the per-face data of the faces ``kept`` (F,) bool, and ``fields`` set."""
    per_face = {name: None if values is None else values[kept]
                for name, values in (("face_lines", mesh.face_lines), ("face_groups", mesh.face_groups))}
    return replace(mesh, face_sizes=face_sizes, face_vertices=face_vertices, **per_face,
                   face_attributes={k: v[kept] for k, v in mesh.face_attributes.items()}, **fields)


def dissolve_mesh_file(mesh, keep: np.ndarray | None = None):
    """The mesh with its interior valence-2 vertices dissolved (``mesh.valence_two.dissolve_valence_two``).

    Returns
    -------
    mesh : MeshFile with ``dissolved_vertices`` set (per-face data of dropped faces removed)
    kept_faces : (F,) bool, which faces remain

    Raises
    ------
    MeshInputError when no face is left (back-to-back face pairs)
    """
    sizes, vertices, kept, dissolved = dissolve_valence_two(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices,
                                                            keep=keep)
    if dissolved.size == 0:
        return mesh, kept
    if sizes.size == 0:
        raise MeshInputError(mesh.path, f"every vertex is an interior vertex of valence 2 ({dissolved.size}): the faces "
                             "are back-to-back pairs (each face listed with both orientations), which enclose nothing "
                             "to smooth")
    dissolved = np.union1d(mesh.dissolved_vertices, dissolved)  # a second pass (after merging sectors) adds its own
    return _keep_faces(mesh, kept, vertices, sizes, dissolved_vertices=dissolved), kept


def merge_sector_faces(mesh, sharp_edges: np.ndarray, tagged_corners: np.ndarray,
                       face_keys: np.ndarray | None = None, protected_edges: np.ndarray | None = None):
    """The mesh with the faces of too large crease sectors merged (``mesh.creases.sectors.merge_crease_sectors``).

    Returns
    -------
    mesh : MeshFile with ``sector_merge`` set (per-face data of the merged polygons: their lowest face's)
    kept_faces : (F,) bool, which faces remain (None: nothing was merged)
    """
    merge = merge_crease_sectors(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices, sharp_edges, tagged_corners,
                                 face_keys, protected_edges)
    if merge is None:
        return mesh, None
    report = (merge.merged_faces, merge.polygons, merge.vertices, merge.lost_creases)
    return _keep_faces(mesh, merge.kept, merge.face_vertices, merge.face_sizes, sector_merge=report), merge.kept


def weld_mesh_file(mesh, tolerance: float = 0.0, keys: np.ndarray | None = None):
    """The mesh with its coincident vertices welded (``mesh.weld.weld_vertices``).

    Points and per-vertex data are kept as read: faces refer to the lowest-numbered
    vertex of each welded position, so vertex numbers stay the file's (and so do the
    vertex numbers of ``tags``; their face numbers do not follow dropped faces). Texture
    coordinates, normals and colours are per vertex in a MeshFile: a welded
    vertex has those of its representative, unless ``keys`` keeps the vertices
    whose data differ apart.

    Parameters
    ----------
    mesh : MeshFile
    tolerance : float >= 0, relative to the bounding-box diagonal (0: equal positions)
    keys : (V, k) float or None, per-vertex data that must be equal to weld

    Returns
    -------
    mesh : MeshFile, with ``weld`` set (per-face data of dropped faces removed)
    kept_faces : (F,) bool, which faces of the input remain
    """
    sizes, vertices, kept, report = weld_vertices(mesh.points, mesh.face_sizes, mesh.face_vertices, tolerance, keys)
    per_face = {name: None if values is None else values[kept]
                for name, values in (("face_lines", mesh.face_lines), ("face_groups", mesh.face_groups))}
    welded = replace(mesh, face_sizes=sizes, face_vertices=vertices, **per_face,
                     face_attributes={k: v[kept] for k, v in mesh.face_attributes.items()},
                     weld=WeldReport(tolerance=float(tolerance), **report))
    return welded, kept
