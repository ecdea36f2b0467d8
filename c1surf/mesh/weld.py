"""Welding: one vertex for the corners at one position, without gluing surfaces that only touch.

STL stores every triangle with its own three vertices, and game assets split
vertices along texture and normal seams, so the file's surface falls apart into
pieces along edges whose two sides are separate vertices at the same position.
``weld_vertices`` redirects every corner to one representative vertex of its
position (the lowest-numbered one, so the file's numbering and all per-vertex
data stay valid), drops the zero-length edges and the faces that welding
collapses, and then undoes the welds that would glue two surfaces along an
edge: where an edge would lie in more than two faces, or a face would visit a
vertex twice, the corners at its welded vertices are regrouped into the fans
of faces that meet across ordinary (two-face) edges. Two surfaces that share
a single vertex stay welded there: that is a pinch, and the topology repair
(``repair.split_pinched_vertices``) splits it again.

Everything is integers and sorting on plain arrays: no Python loop over
vertices or faces.
"""
from __future__ import annotations

import numpy as np

from ..arrays import unique_integers

__all__ = ["weld_vertices", "coincident_representatives", "collapse_repeated_corners", "overshared_vertices",
           "regroup_by_fans"]


def weld_vertices(points: np.ndarray, face_sizes: np.ndarray, face_vertices: np.ndarray, tolerance: float = 0.0,
                  keys: np.ndarray | None = None):
    """Weld the vertices of a polygon mesh by position, keeping edges manifold.

    Parameters
    ----------
    points : (V, 3) float, vertex positions
    face_sizes : (F,) int
    face_vertices : (H,) int, H = sum(face_sizes), 0-based
    tolerance : float >= 0, largest distance welded, relative to the bounding-box
        diagonal of the used vertices; 0 welds equal positions only
    keys : (V, k) float or None, per-vertex data that must also be equal for two
        vertices to weld (NaN equals NaN)

    Returns
    -------
    face_sizes : (F',) int, the faces kept, in order
    face_vertices : (H',) int, their corners, in the input's vertex numbering
    kept_faces : (F,) bool, which input faces remain (welding drops faces left with fewer than 3 corners)
    report : dict of int: ``welded_vertices`` (used vertices now used no more, merged into
        another), ``unwelded_vertices`` (positions kept as several vertices so as not to glue
        surfaces along an edge) and ``dropped_faces``
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    representative = coincident_representatives(points, face_vertices, tolerance, keys)
    sizes, welded, keep_corner = collapse_repeated_corners(face_sizes, representative[face_vertices])
    kept_faces = sizes >= 3
    original = face_vertices[keep_corner & np.repeat(kept_faces, face_sizes)]
    sizes, welded = sizes[kept_faces], welded[np.repeat(kept_faces, sizes)]
    n = points.shape[0]
    shared = np.bincount(representative, minlength=n) > 1  # vertices that others were welded into
    # without any, no edge or face can be overshared by welding (and the check's sorts are skipped)
    suspect = overshared_vertices(sizes, welded, n) & shared if shared.any() else np.zeros(n, dtype=bool)
    if suspect.any():
        welded = regroup_by_fans(sizes, welded, original, suspect)
        # what regrouping could not separate is unwelded completely
        still = overshared_vertices(sizes, welded, n)[welded] & (welded != original)
        welded = np.where(still, original, welded)
    report = {
        "welded_vertices": int(unique_integers(original).size - unique_integers(welded).size),
        "unwelded_vertices": int(np.count_nonzero(suspect)),
        "dropped_faces": int(np.count_nonzero(~kept_faces)),
    }
    return sizes, welded, kept_faces, report


def coincident_representatives(points: np.ndarray, face_vertices: np.ndarray, tolerance: float = 0.0,
                               keys: np.ndarray | None = None) -> np.ndarray:
    """The lowest-numbered used vertex at the position of each vertex.

    Parameters
    ----------
    points : (V, 3) float
    face_vertices : (H,) int, the corners (only vertices used by a face are welded)
    tolerance : float, relative to the bounding-box diagonal of the used vertices; 0: equal positions.
        Within a tolerance, welding is transitive: a chain of close vertices becomes one.
    keys : (V, k) float or None, data that must be equal as well

    Returns
    -------
    (V,) int, representative of every vertex (itself for unused ones and for vertices at a position of their own)
    """
    n = points.shape[0]
    used = np.flatnonzero(np.bincount(face_vertices, minlength=n) > 0)
    representative = np.arange(n, dtype=np.int64)
    if used.size < 2:
        return representative
    key_columns = np.zeros((used.size, 0)) if keys is None else _comparable(np.asarray(keys, float).reshape(n, -1)[used])
    if tolerance > 0:
        label = _near_labels(points[used], key_columns, tolerance)
    else:
        rows = np.concatenate([np.asarray(points, float)[used], key_columns], axis=1)
        if not _may_coincide(rows):  # the usual file: every used vertex at a position of its own
            return representative
        label = _row_labels(rows)
    lowest = np.full(label.max() + 1, n, dtype=np.int64)
    np.minimum.at(lowest, label, used)
    representative[used] = lowest[label]
    return representative


def _may_coincide(rows: np.ndarray) -> bool:
    """False when no two of (m, k) float ``rows`` are equal (as ``_row_labels`` compares them), by one sort of
    a hash of their bits (4 ms for 180,000 vertices, against 30 ms for the lexicographic sort)."""
    bits = np.ascontiguousarray(rows + 0.0).view(np.uint64)  # + 0.0: -0.0 hashes as 0.0, which it equals
    key = np.full(rows.shape[0], 0x9E3779B97F4A7C15, dtype=np.uint64)
    with np.errstate(over="ignore"):  # a hash: wrapping around is fine
        for column in range(rows.shape[1]):
            key = (key ^ bits[:, column]) * np.uint64(0xBF58476D1CE4E5B9)
            key ^= key >> np.uint64(31)
    key.sort()
    return bool(np.any(key[1:] == key[:-1]))


def _row_labels(rows: np.ndarray) -> np.ndarray:
    """(m,) int: the same label for equal rows of (m, k) ``rows`` (a lexicographic sort, -0.0 equal to 0.0)."""
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    starts = np.r_[True, np.any(ordered[1:] != ordered[:-1], axis=1)]
    label = np.empty(rows.shape[0], dtype=np.int64)
    label[order] = np.cumsum(starts) - 1
    return label


def _edge_keys(a: np.ndarray, b: np.ndarray, n_vertices: int) -> np.ndarray:
    """(H,) int64: one number per undirected edge between vertices ``a`` and ``b`` (each (H,) int)."""
    return np.minimum(a, b) * n_vertices + np.maximum(a, b)


def _comparable(keys: np.ndarray) -> np.ndarray:
    """(m, k) keys with NaN replaced by one value (NaN equals NaN here) and -0.0 by 0.0."""
    return np.where(np.isnan(keys), np.inf, keys + 0.0)


def _near_labels(points: np.ndarray, keys: np.ndarray, tolerance: float) -> np.ndarray:
    """Class of each of (m, 3) ``points``: connected pairs closer than ``tolerance`` times the diagonal, equal keys.

    Returns
    -------
    (m,) int
    """
    # only for a welding tolerance: scipy.sparse, csgraph and scipy.spatial take 0.5 s to import
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    pairs = cKDTree(points).query_pairs(tolerance * diagonal, output_type="ndarray")
    if keys.shape[1]:
        pairs = pairs[np.all(keys[pairs[:, 0]] == keys[pairs[:, 1]], axis=1)]
    m = points.shape[0]
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m))
    return connected_components(graph, directed=False)[1]


def collapse_repeated_corners(face_sizes: np.ndarray, face_vertices: np.ndarray):
    """Drop corners that repeat the previous corner (zero-length edges, e.g. ``f 4 3 5 5``).

    Exporters write triangles as quads this way; the polygon they mean has the
    repeat removed. Non-consecutive repeats are left alone.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int

    Returns
    -------
    face_sizes, face_vertices : the collapsed faces (same face count and order)
    keep : (sum(face_sizes),) bool, which of the given corners remain
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    if face_vertices.size == 0:
        return face_sizes, face_vertices, np.ones(0, bool)
    repeat = face_vertices == face_vertices[_next_corner(face_sizes)]
    keep = ~repeat
    if not repeat.any():
        return face_sizes, face_vertices, keep
    face = np.repeat(np.arange(face_sizes.size), face_sizes)
    sizes = np.bincount(face[keep], minlength=face_sizes.size).astype(np.int64)
    return sizes, face_vertices[keep], keep


def _next_corner(face_sizes: np.ndarray) -> np.ndarray:
    """(H,) int: the next corner of each corner in its face (the last one's is the first)."""
    offsets = np.concatenate([[0], np.cumsum(face_sizes)])
    following = np.arange(offsets[-1]) + 1
    nonempty = face_sizes > 0
    following[offsets[1:][nonempty] - 1] = offsets[:-1][nonempty]
    return following


def overshared_vertices(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> np.ndarray:
    """Vertices at an edge of more than two faces, or visited twice by one face.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (H,) int
    n_vertices : int, V

    Returns
    -------
    (V,) bool
    """
    bad = np.zeros(n_vertices, dtype=bool)
    if face_vertices.size == 0:
        return bad
    following = face_vertices[_next_corner(face_sizes)]
    _, first, counts = np.unique(_edge_keys(face_vertices, following, n_vertices), return_index=True,
                                     return_counts=True)
    crowded = first[counts > 2]
    bad[face_vertices[crowded]] = True
    bad[following[crowded]] = True
    face = np.repeat(np.arange(face_sizes.size, dtype=np.int64), face_sizes)
    visits, visit_counts = np.unique(face * n_vertices + face_vertices, return_counts=True)
    bad[visits[visit_counts > 1] % n_vertices] = True
    return bad


def regroup_by_fans(face_sizes: np.ndarray, welded: np.ndarray, original: np.ndarray, suspect: np.ndarray) -> np.ndarray:
    """Split the welded ``suspect`` vertices into the fans of faces that meet across two-face edges.

    Two corners at one welded vertex stay together when they were one vertex in
    the file, or when their faces share an edge there that lies in exactly two
    faces; the other corners of a suspect vertex each get a vertex of their own.

    Parameters
    ----------
    face_sizes : (F,) int
    welded : (H,) int, welded vertex of each corner
    original : (H,) int, the file's vertex of each corner
    suspect : (V,) bool, welded vertices to regroup

    Returns
    -------
    (H,) int, vertex of each corner: ``welded`` except at suspect vertices, where each
    group of corners gets the lowest file vertex among its corners
    """
    from scipy.sparse import coo_matrix  # only where welding glued surfaces (0.4 s to import)
    from scipy.sparse.csgraph import connected_components

    h = welded.size
    following = _next_corner(face_sizes)
    n = int(max(welded.max(), original.max())) + 1
    _, edge, counts = np.unique(_edge_keys(welded, welded[following], n), return_inverse=True, return_counts=True)
    edge = edge.ravel()
    order = np.argsort(edge, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    pair = starts[counts == 2]
    h1, h2 = order[pair], order[pair + 1]
    same = welded[h1] == welded[h2]  # the two faces run the same way along the edge
    a = np.concatenate([h1, following[h1]])
    b = np.concatenate([np.where(same, h2, following[h2]), np.where(same, following[h2], h2)])
    _, first_of_original, which = np.unique(original, return_index=True, return_inverse=True)
    rows = np.concatenate([a, np.arange(h)])
    cols = np.concatenate([b, first_of_original[which.ravel()]])
    graph = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(h, h))
    group = connected_components(graph, directed=False)[1]
    lowest = np.full(group.max() + 1, np.iinfo(np.int64).max, dtype=np.int64)
    np.minimum.at(lowest, group, original)
    return np.where(suspect[welded], lowest[group], welded)
