"""One compiled transaction for every local operation: remove faces, add faces, move vertices; check; commit or undo.

An operation (``operations``) describes its change as the faces it removes (``removed[:nr]``), the faces it adds
in their place (``added[:na]``, na <= nr; added face k takes the slot of removed face k, the slots left over die),
the face or two each added face replaces (``parents``: the fold test's reference normal) and the vertices it moves.
``try_edit`` applies it, then keeps it only when

- **topology**: the link of every vertex of a removed or added face is one cycle or one path (``links``), and
  V - E + F over the touched faces is unchanged (so components, Euler characteristic and rims stay);
- **geometry** (unless the caller waives it, as doublet removal does): every corner of an added face, and of a
  face at a moved vertex, turns the way the replaced faces' normal says (the cosine of their angle above
  ``min_fold``), no corner angle is above the bound (``cos_max_corner``), and no edge there is longer than the
  ``limit`` of its ends (the thickness and sizing guard);

and otherwise restores the faces and points it changed. ``vertex_faces`` is written only on a commit.
"""
from __future__ import annotations

import numpy as np

from ....evaluation.compiled.kernels import compiled
from .links import BROKEN, DEAD, corner, link_status

__all__ = ["try_edit", "quad_normal"]


@compiled
def quad_normal(points, row):  # pragma: no cover - compiled
    """(3,) float: twice the area vector of the quad ``row`` (cross product of its diagonals)."""
    d1 = points[row[2]] - points[row[0]]
    d2 = points[row[3]] - points[row[1]]
    return np.cross(d1, d2)


@compiled
def _face_ok(points, row, reference, limit, params):  # pragma: no cover - compiled
    """Whether the quad ``row`` is no fold against ``reference`` (3,), has no corner above the bound and no edge
    longer than its ends' limit (``params``: cos_max_corner, min_fold)."""
    ref_norm = np.sqrt(np.sum(reference * reference))
    for i in range(4):
        p = points[row[i]]
        e1 = points[row[(i + 1) % 4]] - p
        e2 = points[row[(i + 3) % 4]] - p
        l1 = np.sqrt(np.sum(e1 * e1))
        l2 = np.sqrt(np.sum(e2 * e2))
        if l1 <= 0.0 or l2 <= 0.0:
            return False
        if l1 > min(limit[row[i]], limit[row[(i + 1) % 4]]):
            return False
        if np.sum(e1 * e2) / (l1 * l2) < params[0]:
            return False
        n = np.cross(e1, e2)
        nn = np.sqrt(np.sum(n * n))
        if ref_norm > 0.0 and (nn <= 0.0 or np.sum(n * reference) < params[1] * nn * ref_norm):
            return False
    return True


@compiled
def _touched_vertices(quads, removed, nr, added, na, moved, nm):  # pragma: no cover - compiled
    """The distinct vertices (sorted) of the removed faces (as they are now), the added faces and the moved
    vertices."""
    out = np.empty(4 * (nr + na) + nm, dtype=np.int64)
    for k in range(nr):
        out[4 * k:4 * k + 4] = quads[removed[k]]
    for k in range(na):
        out[4 * (nr + k):4 * (nr + k) + 4] = added[k]
    out[4 * (nr + na):] = moved[:nm]
    return np.unique(out)


@compiled
def _new_lists(quads, vertex_faces, counts, touched, removed, nr, na, marks):  # pragma: no cover - compiled
    """(len(touched), cap) faces and (len(touched),) counts at each touched vertex after the edit (``quads``
    already holds the added faces in their slots), or counts[0] = -1 when one exceeds the capacity."""
    cap = vertex_faces.shape[1]
    lists = np.empty((touched.size, cap), dtype=np.int64)
    sizes = np.zeros(touched.size, dtype=np.int64)
    for t in range(touched.size):
        v = touched[t]
        n = 0
        for k in range(counts[v]):
            g = vertex_faces[v, k]
            if not marks[g]:
                if n == cap:
                    sizes[0] = -1
                    return lists, sizes
                lists[t, n] = g
                n += 1
        for k in range(na):
            if corner(quads, removed[k], v) >= 0:
                if n == cap:
                    sizes[0] = -1
                    return lists, sizes
                lists[t, n] = removed[k]
                n += 1
        sizes[t] = n
    return lists, sizes


@compiled
def _edge_in_kept_face(quads, vertex_faces, counts, marks, u, w):  # pragma: no cover - compiled
    """Whether a face the edit leaves alone holds the edge u - w."""
    for k in range(counts[u]):
        g = vertex_faces[u, k]
        if not marks[g]:
            i = corner(quads, g, u)
            if quads[g, (i + 1) % 4] == w or quads[g, (i + 3) % 4] == w:
                return True
    return False


@compiled
def _edge_keys(rows, n, n_vertices):  # pragma: no cover - compiled
    """The distinct undirected edge keys (min * n_vertices + max) of ``rows[:n]``."""
    keys = np.empty(4 * n, dtype=np.int64)
    for k in range(n):
        for i in range(4):
            a, b = rows[k, i], rows[k, (i + 1) % 4]
            keys[4 * k + i] = min(a, b) * n_vertices + max(a, b)
    return np.unique(keys)


@compiled
def _euler_change(mesh, marks, old_rows, added, dead):  # pragma: no cover - compiled
    """V - E + F after the edit minus before, over the touched faces (``old_rows`` the removed faces as they were,
    ``dead``: vertices the edit leaves faceless)."""
    quads, vertex_faces, counts = mesh[0], mesh[2], mesh[3]
    nr, na = old_rows.shape[0], added.shape[0]
    nv = vertex_faces.shape[0]
    old_keys = _edge_keys(old_rows, nr, nv)
    new_keys = _edge_keys(added, na, nv)
    change_e = 0
    for key in new_keys:
        u, w = key // nv, key % nv
        if not _contains(old_keys, key) and not _edge_in_kept_face(quads, vertex_faces, counts, marks, u, w):
            change_e += 1
    for key in old_keys:
        u, w = key // nv, key % nv
        if not _contains(new_keys, key) and not _edge_in_kept_face(quads, vertex_faces, counts, marks, u, w):
            change_e -= 1
    return -dead - change_e + (na - nr)


@compiled
def _contains(sorted_keys, key):  # pragma: no cover - compiled
    """Whether ``key`` is in the sorted array."""
    i = np.searchsorted(sorted_keys, key)
    return i < sorted_keys.size and sorted_keys[i] == key


@compiled
def _geometry_ok(mesh, guard, removed, na, parents, reference, local, moved):  # pragma: no cover - compiled
    """The geometry half of ``try_edit``: added faces against their parents' normals, the kept faces at moved
    vertices against their own old normals (``reference``: (face ids sorted, their old normals); ``local``:
    (touched vertices sorted, their new face lists, their counts))."""
    quads, points = mesh[0], mesh[4]
    limit, params, marks = guard
    reference_ids, reference_normals = reference
    touched, lists, sizes = local
    nm = moved.size
    for k in range(na):
        ref = np.zeros(3)
        for j in range(2):
            if parents[k, j] >= 0:
                ref += reference_normals[np.searchsorted(reference_ids, parents[k, j])]
        if not _face_ok(points, quads[removed[k]], ref, limit, params):
            return False
    for m in range(nm):
        t = np.searchsorted(touched, moved[m])
        for k in range(sizes[t]):
            g = lists[t, k]
            if marks[g]:
                continue
            ref = reference_normals[np.searchsorted(reference_ids, g)]
            if not _face_ok(points, quads[g], ref, limit, params):
                return False
    return True


@compiled
def _old_normals(quads, vertex_faces, counts, points, removed, nr, moved, nm):  # pragma: no cover - compiled
    """(ids sorted, (k, 3) normals): the current normals of the removed faces and of the faces at the moved
    vertices."""
    n = nr
    for m in range(nm):
        n += counts[moved[m]]
    ids = np.empty(n, dtype=np.int64)
    for k in range(nr):
        ids[k] = removed[k]
    n = nr
    for m in range(nm):
        for k in range(counts[moved[m]]):
            ids[n] = vertex_faces[moved[m], k]
            n += 1
    ids = np.unique(ids)
    normals = np.empty((ids.size, 3))
    for k in range(ids.size):
        normals[k] = quad_normal(points, quads[ids[k]])
    return ids, normals


@compiled
def try_edit(mesh, guard, removed, added, parents, moved, moved_to, check_geometry):  # pragma: no cover - compiled
    """Apply the edit (module docstring) and keep it when it passes the checks; True when kept.

    mesh: (quads (F, 4), alive (F,), vertex_faces (V, cap), counts (V,), points (V, 3)) (``QuadMesh.state()``);
    guard: (limit (V,) float, the longest edge at each vertex; params (cos_max_corner, min_fold); marks (F,) bool
    all False, scratch left all False); removed (nr,) int, added (na, 4) int, parents (na, 2) int (-1: none),
    moved (nm,) int, moved_to (nm, 3) float
    """
    quads, alive, vertex_faces, counts, points = mesh
    marks = guard[2]
    nr, na, nm = removed.size, added.shape[0], moved.size
    ids, normals = _old_normals(quads, vertex_faces, counts, points, removed, nr, moved, nm)
    touched = _touched_vertices(quads, removed, nr, added, na, moved, nm)
    old_rows = np.empty((nr, 4), dtype=np.int64)
    old_points = np.empty((nm, 3))
    for k in range(nr):
        old_rows[k] = quads[removed[k]]
        marks[removed[k]] = True
    for k in range(na):
        quads[removed[k]] = added[k]
    for m in range(nm):
        old_points[m] = points[moved[m]]
        points[moved[m]] = moved_to[m]
    lists, sizes = _new_lists(quads, vertex_faces, counts, touched, removed, nr, na, marks)
    ok = sizes[0] >= 0
    dead = 0
    for t in range(touched.size):
        if not ok:
            break
        status = link_status(quads, lists[t], sizes[t], touched[t])
        if status == BROKEN:
            ok = False
        elif status == DEAD and counts[touched[t]] > 0:
            dead += 1
    if ok:
        ok = _euler_change(mesh, marks, old_rows, added, dead) == 0
    if ok and check_geometry:
        ok = _geometry_ok(mesh, guard, removed, na, parents, (ids, normals), (touched, lists, sizes), moved)
    if ok:
        for t in range(touched.size):
            counts[touched[t]] = sizes[t]
            vertex_faces[touched[t], :sizes[t]] = lists[t, :sizes[t]]
        for k in range(na, nr):
            alive[removed[k]] = False
    else:
        for k in range(nr):
            quads[removed[k]] = old_rows[k]
        for m in range(nm):
            points[moved[m]] = old_points[m]
    for k in range(nr):
        marks[removed[k]] = False
    return ok
