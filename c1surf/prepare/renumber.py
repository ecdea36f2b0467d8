"""Per-face and per-vertex construction data (``SurfaceData``) carried through the edits of ``mesh_edits``:
blend ratios follow the faces kept, sharp features are renumbered, and what an edit loses is named in a note."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..construction.features import SharpFeatures
from ..mesh.halfedges import mesh_edge_keys
from ..mesh.weld import coincident_representatives
from .extension_data import SurfaceData
from .mesh_edits import dissolve_mesh_file, drop_repeated_faces, weld_mesh_file

__all__ = ["weld_surface_input", "drop_repeated_surface_faces", "dissolve_surface_input", "faces_kept"]


def weld_surface_input(mesh, data: SurfaceData | None, tolerance: float | None):
    """Weld ``mesh`` (``mesh_edits.weld_mesh_file``) without merging vertices whose construction data differ.

    Parameters
    ----------
    mesh : MeshFile
    data : SurfaceData of ``mesh`` or None; its vertex keys keep apart vertices with different
        texture coordinates or colours (``--attributes``), weights, normals or blend ratios
    tolerance : float, relative to the bounding-box diagonal (0: equal positions), or None: no welding

    Returns
    -------
    (MeshFile, SurfaceData or None): per-face data follows the faces welding keeps
    """
    if tolerance is None:
        return mesh, data
    keys = None if data is None else data.vertex_keys()
    welded, kept = weld_mesh_file(mesh, tolerance, keys)
    if data is not None and data.face_blend is not None:
        data = replace(data, face_blend=data.face_blend[kept])
    if data is not None and data.features is not None and (welded.weld.welded_vertices or welded.weld.dropped_faces):
        data = _welded_features(data, mesh, welded, kept, coincident_representatives(mesh.points, mesh.face_vertices,
                                                                                     tolerance, keys))
    return welded, data


def drop_repeated_surface_faces(mesh, data: SurfaceData | None):
    """Drop faces that repeat an earlier one (``mesh_edits.drop_repeated_faces``); per-face data and holes follow."""
    dropped, kept = drop_repeated_faces(mesh)
    if dropped is mesh:
        return mesh, data
    return dropped, faces_kept(data, kept)


def faces_kept(data: SurfaceData | None, kept: np.ndarray) -> SurfaceData | None:
    """``data`` for the faces ``kept`` (F,) bool: per-face blend ratios and hole faces follow them."""
    if data is None:
        return None
    if data.face_blend is not None:
        data = replace(data, face_blend=data.face_blend[kept])
    f = data.features
    if f is not None and f.hole_faces.size:
        holes = f.hole_faces[kept[f.hole_faces]]
        f = replace(f, hole_faces=(np.cumsum(kept) - 1)[holes])
        data = replace(data, features=None if f.is_empty() else f)
    return data


def dissolve_surface_input(mesh, data: SurfaceData | None, keep: np.ndarray | None = None):
    """Dissolve the interior valence-2 vertices of ``mesh`` (``mesh_edits.dissolve_mesh_file``); ``data`` follows.

    Per-face data follows the faces kept; a crease on either edge of a dissolved vertex
    becomes a crease of the edge that replaces them (the larger sharpness); a hole on a
    dropped face and a corner on a dissolved vertex are named in a note.
    """
    dissolved, kept = dissolve_mesh_file(mesh, keep)
    if dissolved is mesh:
        return mesh, data
    if data is not None and data.face_blend is not None:
        data = replace(data, face_blend=data.face_blend[kept])
    if data is not None and data.features is not None:
        data = _dissolved_features(data, mesh, dissolved, kept)
    return dissolved, data


def _dissolved_features(data: SurfaceData, mesh, dissolved, kept: np.ndarray) -> SurfaceData:
    """``data``'s sharp features on the mesh without its dissolved vertices (``dissolve_surface_input``)."""
    f = data.features
    gone = np.zeros(mesh.n_vertices, dtype=bool)
    gone[np.setdiff1d(dissolved.dissolved_vertices, mesh.dissolved_vertices)] = True  # this pass's
    edges, sharpness = f.crease_edges, f.crease_sharpness
    touched = gone[edges].any(axis=1)
    # a dissolved vertex's two edges a - v - b: replace each creased one by a - b
    ends = _chain_ends(mesh, gone, edges[touched])
    edges = np.concatenate([edges[~touched], ends])
    sharpness = np.concatenate([sharpness[~touched], sharpness[touched]])
    valid = (edges >= 0).all(axis=1)
    corners = ~gone[f.corner_vertices]
    holes = f.hole_faces[kept[f.hole_faces]]
    features = replace(f, crease_edges=edges[valid], crease_sharpness=sharpness[valid],
                       corner_vertices=f.corner_vertices[corners], corner_sharpness=f.corner_sharpness[corners],
                       hole_faces=(np.cumsum(kept) - 1)[holes])
    notes = list(data.feature_notes)
    lost = int((~corners).sum()), int(f.hole_faces.size - holes.size)
    if any(lost):
        notes.append(f"{mesh.path}: {lost[0]} corners on dissolved valence-2 vertices and {lost[1]} holes on "
                     "faces they left with two corners are not used")
    return replace(data, features=None if features.is_empty() else features, feature_notes=notes)


def _chain_ends(mesh, gone: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(k, 2) int, sorted rows: for each edge with a dissolved end, the kept ends a, b of its run a - v.. - b."""
    sizes = np.asarray(mesh.face_sizes, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    face = np.repeat(np.arange(sizes.size), sizes)
    local = np.arange(offsets[-1]) - offsets[face]
    following = offsets[face] + (local + 1) % sizes[face]
    before = offsets[face] + (local - 1) % sizes[face]
    fv = np.asarray(mesh.face_vertices, dtype=np.int64)
    ahead, back = following.copy(), before.copy()  # the next and previous kept corner of every corner
    for _ in range(int(sizes.max(initial=0))):  # a run is shorter than its face
        ahead = np.where(gone[fv[ahead]], following[ahead], ahead)
        back = np.where(gone[fv[back]], before[back], back)
    run = np.zeros((mesh.n_vertices, 2), dtype=np.int64)
    corners = np.flatnonzero(gone[fv])
    run[fv[corners]] = np.sort(np.stack([fv[back[corners]], fv[ahead[corners]]], axis=1), axis=1)
    dissolved_end = np.where(gone[edges[:, 1]], edges[:, 1], edges[:, 0])
    return run[dissolved_end]


def _welded_features(data: SurfaceData, mesh, welded, kept: np.ndarray, representative: np.ndarray):
    """``data`` with its sharp features renumbered for the welded mesh, and a note on any that welding lost.

    Crease and corner vertices move to the vertex they were welded into; hole faces follow
    the faces welding keeps. A crease pair that is no edge of the welded mesh any more
    (welding kept its position as several vertices) and a hole on a dropped face are named.
    """
    f = data.features
    new_face = np.cumsum(kept) - 1
    holes = f.hole_faces[kept[f.hole_faces]]
    edges = representative[f.crease_edges]
    n = welded.n_vertices
    present = np.isin(np.minimum(*edges.T) * n + np.maximum(*edges.T),
                      mesh_edge_keys(welded.face_sizes, welded.face_vertices, n))
    features = SharpFeatures(edges[present], f.crease_sharpness[present], representative[f.corner_vertices],
                             f.corner_sharpness, new_face[holes])
    notes = list(data.feature_notes)
    lost = int((~present).sum()) + int(f.hole_faces.size - holes.size)
    if lost:
        notes.append(f"{mesh.path}: welding left {int((~present).sum())} crease edges and "
                     f"{int(f.hole_faces.size - holes.size)} hole faces without their edge or face: they are not used")
    return replace(data, features=None if features.is_empty() else features, feature_notes=notes)
