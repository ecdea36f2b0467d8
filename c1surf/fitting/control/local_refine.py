"""Refining a control mesh where the fit misses the tolerance, and finding those faces.

``refine_control_faces`` splits each selected n-gon into n quads (its centroid joined to its edges'
midpoints); a face beside it gains the midpoint of the edge they share, so it has one corner more
(a quad becomes a pentagon, which the construction takes like any polygon). Crease edges that are
split stay creases in both halves. The new points are centroids and midpoints of the old ones; the
fit moves them next.

Measured (fish, 964 faces, one Doo-Sabin step, 3,856 patches): splitting 1 %, 5 %, 20 % of the faces
gives 991, 1,108, 1,540 faces but 16,000, 18,448, 27,080 patches, because pentagons side by side
need the second Doo-Sabin step everywhere (``refine.fewer_steps``); a new remesh at 2,004 faces has
8,016 patches (one step). So for ``--tolerance`` a larger remesh (``next_face_count``) is the
cheaper refinement, unless the surface already needs two steps.

``patch_control_faces`` says which control faces each patch of a ``Surface`` comes from (its
input face; both faces of its input edge; every face at its input vertex), so deviations measured
at footpoints on patches become per-face deviations (``face_deviation``). ``nearest_control_faces``
is the geometric fallback for points without a patch: the face whose centroid is nearest.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix

from ...construction.refine.doo_sabin import FACE_FROM_EDGE, FACE_FROM_FACE, FACE_FROM_VERTEX
from .cleanup import edge_keys
from .control_mesh import ControlMesh

__all__ = ["refine_control_faces", "patch_control_faces", "face_deviation", "faces_over_tolerance",
           "nearest_control_faces", "next_face_count"]


def refine_control_faces(mesh: ControlMesh, selected) -> ControlMesh:
    """Split the selected faces into quads; their neighbours gain the shared edges' midpoints.

    Parameters
    ----------
    mesh : ControlMesh
    selected : (F,) bool or (k,) int, the faces to split

    Returns
    -------
    ControlMesh: the faces not selected first (in order, some with more corners), then the
    selected faces' quads (n per n-gon, face by face); vertices: the old ones, then one per split
    edge, then one per split face. Notes and report are carried over.
    """
    sizes, vertices, points = mesh.face_sizes, mesh.face_vertices, mesh.points
    n_vertices = points.shape[0]
    chosen = np.zeros(sizes.size, dtype=bool)
    chosen[np.asarray(selected)] = True
    if not chosen.any():
        return mesh
    a, b, key, face = edge_keys(sizes, vertices, n_vertices)
    split_keys = np.unique(key[chosen[face]])
    is_split = np.isin(key, split_keys)
    midpoint = n_vertices + np.searchsorted(split_keys, key)  # valid where is_split
    centre = n_vertices + split_keys.size + np.cumsum(chosen) - 1  # valid for chosen faces
    new_points = np.concatenate([
        points,
        0.5 * (points[split_keys // n_vertices] + points[split_keys % n_vertices]),
        _centroids(sizes, vertices, points)[chosen],
    ])
    # faces kept: every corner, then the midpoint of its edge where that is split
    corner = ~chosen[face]
    doubled = corner & is_split
    out = np.zeros(np.count_nonzero(corner) + np.count_nonzero(doubled), dtype=np.int64)
    slot = np.cumsum(corner.astype(np.int64) + doubled) - 1  # last slot of every kept corner
    out[slot[doubled] - 1] = vertices[doubled]
    out[slot[doubled]] = midpoint[doubled]
    plain = corner & ~is_split
    out[slot[plain]] = vertices[plain]
    kept_sizes = sizes[~chosen] + np.bincount(face[doubled], minlength=sizes.size)[~chosen]
    # selected faces: the quad (v_i, m_i, c, m_{i-1}) at every corner i
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    h = np.flatnonzero(chosen[face])
    previous = offsets[face[h]] + (h - offsets[face[h]] - 1) % sizes[face[h]]
    quads = np.stack([vertices[h], midpoint[h], centre[face[h]], midpoint[previous]], axis=1)
    crease_edges = _split_creases(mesh.crease_edges, split_keys, n_vertices)
    report = dict(mesh.report, faces=int(kept_sizes.size + h.size), refined_faces=int(np.count_nonzero(chosen)))
    return ControlMesh(np.r_[kept_sizes, np.full(h.size, 4)], np.r_[out, quads.ravel()], new_points, crease_edges,
                       list(mesh.notes), report)


def _centroids(sizes, vertices, points) -> np.ndarray:
    """(F, 3) float: the mean of each face's corners."""
    face = np.repeat(np.arange(sizes.size), sizes)
    total = np.zeros((sizes.size, 3))
    np.add.at(total, face, points[vertices])
    return total / sizes[:, None]


def _split_creases(crease_edges: np.ndarray, split_keys: np.ndarray, n_vertices: int) -> np.ndarray:
    """(k', 2) int: crease edges, each split one replaced by its two halves through its midpoint."""
    if crease_edges.shape[0] == 0:
        return crease_edges
    lo, hi = crease_edges.min(axis=1), crease_edges.max(axis=1)
    key = lo * n_vertices + hi
    slot = np.clip(np.searchsorted(split_keys, key), 0, max(split_keys.size - 1, 0))
    split = split_keys[slot] == key if split_keys.size else np.zeros(key.size, dtype=bool)
    middle = n_vertices + slot[split]
    halves = np.concatenate([np.stack([lo[split], middle], axis=1), np.stack([middle, hi[split]], axis=1)])
    return np.concatenate([np.stack([lo[~split], hi[~split]], axis=1), halves]).astype(np.int64)


def patch_control_faces(surface, face_sizes, face_vertices) -> csr_matrix:
    """(P, F) sparse 0/1 matrix: the control faces each patch of ``surface`` comes from.

    Parameters
    ----------
    surface : construction.surface.Surface built on the control mesh (its input numbering)
    face_sizes, face_vertices : the control mesh's faces

    A patch from a face belongs to that face; from an edge, to the faces on the edge; from a vertex,
    to the faces at the vertex.
    """
    sizes = np.asarray(face_sizes, dtype=np.int64)
    vertices = np.asarray(face_vertices, dtype=np.int64)
    n_faces = sizes.size
    n_vertices = int(vertices.max(initial=-1)) + 1
    face = np.repeat(np.arange(n_faces), sizes)
    at_vertex = csr_matrix((np.ones(vertices.size), (vertices, face)), shape=(n_vertices, n_faces))
    at_vertex.data[:] = 1.0  # a face visits a vertex once; duplicates summed would be > 1
    kind, index, edge = surface.patch_sources()
    n = kind.size
    rows = np.arange(n)
    from_face = kind == FACE_FROM_FACE
    parts = [csr_matrix((np.ones(np.count_nonzero(from_face)), (rows[from_face], index[from_face])),
                        shape=(n, n_faces))]
    from_vertex = kind == FACE_FROM_VERTEX
    pick = csr_matrix((np.ones(np.count_nonzero(from_vertex)), (rows[from_vertex], index[from_vertex])),
                      shape=(n, n_vertices))
    parts.append(pick @ at_vertex)
    from_edge = kind == FACE_FROM_EDGE
    if from_edge.any():
        ends = [csr_matrix((np.ones(np.count_nonzero(from_edge)), (rows[from_edge], edge[from_edge, k])),
                           shape=(n, n_vertices)) @ at_vertex for k in (0, 1)]
        parts.append(ends[0].multiply(ends[1]))
    result = (parts[0] + parts[1] + (parts[2] if len(parts) > 2 else 0)).tocsr()
    result.data[:] = 1.0
    return result


def face_deviation(patch_faces: csr_matrix, patch: np.ndarray, deviation: np.ndarray) -> np.ndarray:
    """(F,) float: the largest deviation of the samples on each control face's patches (0 where none).

    Parameters
    ----------
    patch_faces : (P, F) from ``patch_control_faces``
    patch : (m,) int, the patch of every sample's footpoint
    deviation : (m,) float >= 0
    """
    worst = np.zeros(patch_faces.shape[0])
    np.maximum.at(worst, np.asarray(patch), np.asarray(deviation, dtype=np.float64))
    coo = patch_faces.tocoo()
    out = np.zeros(patch_faces.shape[1])
    np.maximum.at(out, coo.col, worst[coo.row])
    return out


def faces_over_tolerance(per_face: np.ndarray, tolerance: float, n_faces: int, face_cap: int) -> np.ndarray:
    """(k,) int: faces whose deviation exceeds ``tolerance``, worst first, as many as the cap allows.

    Splitting an n-gon adds n - 1 faces (4-gons: 3), so at most (face_cap - n_faces) // 3 faces are
    chosen; an empty result with faces still over the tolerance means the cap is reached.
    """
    over = np.flatnonzero(per_face > tolerance)
    room = max(0, (int(face_cap) - int(n_faces)) // 3)
    return over[np.argsort(-per_face[over], kind="stable")][:room]


def nearest_control_faces(mesh: ControlMesh, query: np.ndarray) -> np.ndarray:
    """(q,) int: the control face whose centroid is nearest each query point (approximate)."""
    from scipy.spatial import cKDTree

    centre = _centroids(mesh.face_sizes, mesh.face_vertices, mesh.points)
    return cKDTree(centre).query(np.asarray(query, dtype=np.float64))[1]


def next_face_count(faces: int, worst_over_tolerance: float, face_cap: int, order: float = 3.0) -> int:
    """The face count of the next, larger remesh when the deviation is ``worst_over_tolerance`` times the tolerance.

    The distance of a fitted surface of degree 2 falls like h^order with the face size h, and the face
    count grows like h^-2, so faces * ratio^(2 / order); at least 1.25 times as many, at most ``face_cap``.
    """
    ratio = max(float(worst_over_tolerance), 1.0)
    return int(min(face_cap, max(np.ceil(1.25 * faces), np.ceil(faces * ratio ** (2.0 / order)))))
