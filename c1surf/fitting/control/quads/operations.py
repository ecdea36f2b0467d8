"""The local operations of quad-mesh simplification, compiled, each one ``edits.try_edit`` transaction.

After Tarini et al. 2010 ("Practical quad mesh simplification") and Daniels et al. 2008 (polychords); written
from the papers' descriptions. Every operation keeps a pure-quad mesh and is refused when ``try_edit``'s checks
fail (the link condition, V - E + F, no fold, the corner bound, the edge limit).

- ``collapse_diagonal``: quad (a, b, c, d) goes, c merges into a (at the midpoint; at the rim vertex when one of
  the two is on a rim; never two rim vertices: that would pinch or join rims). b and d lose an edge.
- ``rotate_edge``: the two quads at an edge are a hexagon; the edge turns to the next diagonal either way.
- ``remove_doublet``: an interior vertex in two quads (valence 2) is dissolved; the two become one quad.
- ``collapse_polychord``: the strip of quads through opposite edges from a start quad (Daniels et al. 2008's
  polychord) goes, each edge it crosses merging into a point; open strips end on rims, which lose an edge
  at each end (never below four).

Singlets (a quad folded onto itself, a vertex of valence 1) cannot arise: a face must keep four distinct
vertices (``links.link_status``), so every operation that would make one is refused.
"""
from __future__ import annotations

import numpy as np

from ....evaluation.compiled.kernels import compiled
from .edits import try_edit
from .links import corner, face_across, is_boundary

__all__ = ["collapse_diagonal", "rotate_edge", "remove_doublet", "collapse_polychord", "rim_at_least"]


@compiled
def _merged_position(quads, vertex_faces, counts, points, keep, go):  # pragma: no cover - compiled
    """Where ``go`` merged into ``keep`` lands: the midpoint, or the rim vertex's place; None-like (nan) when both
    are on rims (the caller decides whether that is allowed)."""
    on_keep = is_boundary(quads, vertex_faces, counts, keep)
    on_go = is_boundary(quads, vertex_faces, counts, go)
    if on_keep and not on_go:
        return points[keep].copy(), 1
    if on_go and not on_keep:
        return points[go].copy(), 1
    return 0.5 * (points[keep] + points[go]), 2 if on_keep else 0


@compiled
def collapse_diagonal(mesh, guard, face, k):  # pragma: no cover - compiled
    """Collapse the diagonal of ``face`` from corner k to corner k + 2 (module docstring); True when done.
    ``mesh``, ``guard``: ``edits.try_edit``'s."""
    quads, vertex_faces, counts, points = mesh[0], mesh[2], mesh[3], mesh[4]
    a, c = quads[face, k], quads[face, (k + 2) % 4]
    position, rims = _merged_position(quads, vertex_faces, counts, points, a, c)
    if rims == 2:
        return False
    n = counts[c]
    removed = np.empty(n, dtype=np.int64)
    added = np.empty((n - 1, 4), dtype=np.int64)
    parents = np.full((n - 1, 2), -1, dtype=np.int64)
    j = 0
    for s in range(n):
        g = vertex_faces[c, s]
        if g != face:
            removed[j] = g
            for i in range(4):
                added[j, i] = a if quads[g, i] == c else quads[g, i]
            parents[j, 0] = g
            j += 1
    removed[n - 1] = face
    moved = np.array([a], dtype=np.int64)
    return try_edit(mesh, guard, removed, added, parents, moved, position.reshape(1, 3), True)


@compiled
def rotate_edge(mesh, guard, face, k, turn):  # pragma: no cover - compiled
    """Turn the edge from corner k to k + 1 of ``face`` to the next hexagon diagonal (turn +1 or -1)."""
    quads, vertex_faces, counts = mesh[0], mesh[2], mesh[3]
    u, v = quads[face, k], quads[face, (k + 1) % 4]
    other, j = face_across(quads, vertex_faces, counts, v, u)
    if other < 0 or other == face:
        return False
    hexagon = np.array([v, quads[face, (k + 2) % 4], quads[face, (k + 3) % 4], u, quads[other, (j + 2) % 4],
                        quads[other, (j + 3) % 4]], dtype=np.int64)
    s = 1 if turn > 0 else 2
    added = np.empty((2, 4), dtype=np.int64)
    for i in range(4):
        added[0, i] = hexagon[(s + i) % 6]
        added[1, i] = hexagon[(s + 3 + i) % 6]
    removed = np.array([face, other], dtype=np.int64)
    parents = np.array([[face, other], [face, other]], dtype=np.int64)
    return try_edit(mesh, guard, removed, added, parents, np.empty(0, dtype=np.int64), np.empty((0, 3)), True)


@compiled
def remove_doublet(mesh, guard, vertex):  # pragma: no cover - compiled
    """Dissolve an interior vertex of two quads (v, a, c, b) and (v, b, d, a) into the quad (a, c, b, d); topology
    checked only (a doublet must go: the construction refuses it), the smoothing straightens the quad."""
    quads, vertex_faces, counts = mesh[0], mesh[2], mesh[3]
    if counts[vertex] != 2 or is_boundary(quads, vertex_faces, counts, vertex):
        return False
    f, g = vertex_faces[vertex, 0], vertex_faces[vertex, 1]
    i, j = corner(quads, f, vertex), corner(quads, g, vertex)
    a, c, b = quads[f, (i + 1) % 4], quads[f, (i + 2) % 4], quads[f, (i + 3) % 4]
    if quads[g, (j + 1) % 4] != b or quads[g, (j + 3) % 4] != a:
        return False
    added = np.array([[a, c, b, quads[g, (j + 2) % 4]]], dtype=np.int64)
    return try_edit(mesh, guard, np.array([f, g]), added, np.array([[f, g]]), np.empty(0, dtype=np.int64),
                    np.empty((0, 3)), False)


@compiled
def rim_at_least(quads, vertex_faces, counts, a, b, edges):  # pragma: no cover - compiled
    """Whether the rim through the boundary edge a -> b (a face holds a -> b, none b -> a) has ``edges`` or more."""
    steps, there = 1, b
    while steps < edges:
        nxt = -1
        for s in range(counts[there]):  # the boundary edge leaving ``there``
            g = vertex_faces[there, s]
            i = corner(quads, g, there)
            w = quads[g, (i + 1) % 4]
            if face_across(quads, vertex_faces, counts, w, there)[0] < 0:
                nxt = w
        if nxt < 0:
            return False
        if nxt == a:
            return steps + 1 >= edges
        there, steps = nxt, steps + 1
    return True


@compiled
def _strip_step(quads, vertex_faces, counts, g, e, strip, n, m):  # pragma: no cover - compiled
    """Add face g (entered through its edge e -> e + 1) to the strip and its far edge to the crossed edges
    (``strip``: the buffers faces, edges and marks): (n, m, the next face, its entry corner, ok), not ok when g is
    in the strip already or the buffers are full."""
    faces, edges, marks = strip
    if marks[g] or n >= faces.size:
        return n, m, -1, -1, False
    marks[g] = True
    faces[n] = g
    p, q = quads[g, (e + 2) % 4], quads[g, (e + 3) % 4]
    h, j = face_across(quads, vertex_faces, counts, q, p)
    edges[m, 0], edges[m, 1] = p, q
    return n + 1, m + 1, h, j, True


@compiled
def _chord(quads, vertex_faces, counts, face, k, faces, edges, marks):  # pragma: no cover - compiled
    """Walk the polychord through ``face`` across its edge k -> k + 1 both ways: (faces, crossed edges, n faces,
    m edges), n = -1 when the strip runs into itself. ``faces`` (F,), ``edges`` (F + 1, 2): buffers."""
    n, m, ok, closed = 0, 1, True, False
    edges[0, 0], edges[0, 1] = quads[face, k], quads[face, (k + 1) % 4]
    g, e = face, k
    while g >= 0 and ok:
        n, m, g, e, ok = _strip_step(quads, vertex_faces, counts, g, e, (faces, edges, marks), n, m)
        if ok and g == face:  # closed: the last far edge is the first edge
            m, g, closed = m - 1, -1, True
    if ok and not closed:  # open: walk the other way from the first edge
        g, e = face_across(quads, vertex_faces, counts, quads[face, (k + 1) % 4], quads[face, k])
        while g >= 0 and ok:
            n, m, g, e, ok = _strip_step(quads, vertex_faces, counts, g, e, (faces, edges, marks), n, m)
    for s in range(n):
        marks[faces[s]] = False
    return faces, edges, n if ok else -1, m


@compiled
def collapse_polychord(mesh, guard, face, k, buffers):  # pragma: no cover - compiled
    """Collapse the polychord through ``face`` across its edge k -> k + 1 (module docstring). ``buffers``: faces
    (F,), edges (F + 1, 2) and remap (V,) all -1 (scratch, left all -1). Returns the edges merged (their
    kept ends in ``edges[:m, 0]``), 0 when refused.

    Long: the walk, the merge map, the renamed faces and the rim guard belong to one transaction."""
    quads, vertex_faces, counts, points = mesh[0], mesh[2], mesh[3], mesh[4]
    marks = guard[2]
    faces, edges, remap = buffers
    faces, edges, n, m = _chord(quads, vertex_faces, counts, face, k, faces, edges, marks)
    if n <= 0:
        return 0
    ok = True
    moved = np.empty(m, dtype=np.int64)
    moved_to = np.empty((m, 3))
    for s in range(m):
        p, q = edges[s, 0], edges[s, 1]
        if remap[p] != -1 or remap[q] != -1 or p == q:
            ok = False
            m = s
            break
        remap[q] = p
        remap[p] = p
        position, rims = _merged_position(quads, vertex_faces, counts, points, p, q)
        rim_edge = face_across(quads, vertex_faces, counts, p, q)[0] < 0 or \
            face_across(quads, vertex_faces, counts, q, p)[0] < 0
        if rims == 2 and not (rim_edge and _rim_keeps(quads, vertex_faces, counts, p, q)):
            ok = False
        moved[s], moved_to[s] = p, position
    removed = np.empty(0, dtype=np.int64)
    added = np.empty((0, 4), dtype=np.int64)
    if ok:
        for s in range(n):
            marks[faces[s]] = True
        renamed = _renamed_faces(quads, vertex_faces, counts, edges, m, marks)
        for s in range(n):
            marks[faces[s]] = False
        removed = np.concatenate((renamed, faces[:n].copy()))
        added = np.empty((renamed.size, 4), dtype=np.int64)
        for r in range(renamed.size):
            for i in range(4):
                w = quads[renamed[r], i]
                added[r, i] = w if remap[w] == -1 else remap[w]
    for s in range(m):
        remap[edges[s, 0]] = -1
        remap[edges[s, 1]] = -1
    if not ok:
        return 0
    na = added.shape[0]
    parents = np.full((na, 2), -1, dtype=np.int64)
    parents[:, 0] = removed[:na]
    kept = try_edit(mesh, guard, removed, added, parents, moved[:m], moved_to[:m], True)
    return m if kept else 0


@compiled
def _rim_keeps(quads, vertex_faces, counts, p, q):  # pragma: no cover - compiled
    """Whether the rim through the boundary edge p - q keeps four edges or more after losing two (both chord ends
    may lie on it)."""
    if face_across(quads, vertex_faces, counts, q, p)[0] < 0:
        return rim_at_least(quads, vertex_faces, counts, p, q, 6)
    return rim_at_least(quads, vertex_faces, counts, q, p, 6)


@compiled
def _renamed_faces(quads, vertex_faces, counts, edges, m, marks):  # pragma: no cover - compiled
    """The faces outside the strip (``marks`` set on the strip) at a vertex that merges away (edges[:, 1])."""
    out = np.empty(0, dtype=np.int64)
    found = []
    for s in range(m):
        q = edges[s, 1]
        for t in range(counts[q]):
            g = vertex_faces[q, t]
            if not marks[g]:
                marks[g] = True
                found.append(g)
    out = np.array(found, dtype=np.int64) if len(found) else out
    for g in out:
        marks[g] = False
    return out
