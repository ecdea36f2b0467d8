"""Compiled local topology of a pure-quad mesh: a vertex's link, its boundary status, the face across an edge.

The mesh is four arrays (``quad_mesh.QuadMesh``): ``quads`` (F, 4) int64 counter-clockwise, ``alive`` (F,) bool,
``vertex_faces`` (V, cap) int64, the faces at each vertex (``counts`` (V,) int64 of them, in no order). A face
(v, x, y, z) puts the directed path x -> y -> z into the *link* of v; v is a manifold vertex, its faces
consistently oriented, exactly when its link is one simple cycle (interior) or one simple path (on a rim). Every
local operation (``edits.try_edit``) checks the links of the vertices it touches: that is the link condition
(Dey et al. 1999 for triangles). A link that visits a vertex twice is refused too: two faces meeting at two vertices
that are not an edge, as at a doublet (an interior vertex of valence 2), so no operation ever makes one.
"""
from __future__ import annotations

import numpy as np

from ....evaluation.compiled.kernels import compiled

__all__ = ["corner", "link_status", "is_boundary", "face_across", "edge_valence", "DEAD", "BROKEN", "INTERIOR",
           "RIM"]

BROKEN, INTERIOR, RIM, DEAD = 0, 1, 2, 3  # link_status: not a disk, a cycle, a path, no face


@compiled
def corner(quads, face, vertex):  # pragma: no cover - compiled
    """The corner (0..3) of ``vertex`` in ``face``, -1 when the face does not hold it."""
    for i in range(4):
        if quads[face, i] == vertex:
            return i
    return -1


@compiled
def _slot(ids, n, value):  # pragma: no cover - compiled
    """The index of ``value`` among ``ids[:n]``, or n (then the caller appends it)."""
    for i in range(n):
        if ids[i] == value:
            return i
    return n


@compiled
def link_status(quads, faces, n, vertex):  # pragma: no cover - compiled
    """BROKEN, INTERIOR, RIM or DEAD: the link of ``vertex`` over the faces ``faces[:n]`` (module docstring).

    A face holding the vertex twice, or not at all, or with a repeated corner, is BROKEN."""
    if n == 0:
        return DEAD
    ids = np.empty(2 * n + 1, dtype=np.int64)
    succ = np.full(2 * n + 1, -1, dtype=np.int64)
    has_in = np.zeros(2 * n + 1, dtype=np.bool_)
    count = 0
    for k in range(n):
        g = faces[k]
        i = corner(quads, g, vertex)
        if i < 0:
            return BROKEN
        path = (quads[g, (i + 1) % 4], quads[g, (i + 2) % 4], quads[g, (i + 3) % 4])
        if path[0] == vertex or path[1] == vertex or path[2] == vertex or path[0] == path[1] \
                or path[1] == path[2] or path[0] == path[2]:
            return BROKEN
        for step in range(2):
            s = _slot(ids, count, path[step])
            if s == count:
                ids[count] = path[step]
                count += 1
            t = _slot(ids, count, path[step + 1])
            if t == count:
                ids[count] = path[step + 1]
                count += 1
            if succ[s] != -1 or has_in[t]:
                return BROKEN
            succ[s] = t
            has_in[t] = True
    edges = 2 * n
    if count == edges:  # every link vertex has one edge in and one out: one cycle, or several
        walk, steps = succ[0], 1
        while walk != 0 and steps <= edges:
            walk, steps = succ[walk], steps + 1
        return INTERIOR if steps == edges else BROKEN
    if count != edges + 1:
        return BROKEN
    start = -1
    for s in range(count):
        if not has_in[s]:
            start = s
    steps, walk = 0, start
    while succ[walk] != -1 and steps <= edges:
        walk, steps = succ[walk], steps + 1
    return RIM if steps == edges else BROKEN


@compiled
def is_boundary(quads, vertex_faces, counts, vertex):  # pragma: no cover - compiled
    """Whether ``vertex`` lies on a rim: an edge from it lies in one face only (on a valid mesh, its link is a
    path)."""
    for k in range(counts[vertex]):
        g = vertex_faces[vertex, k]
        i = corner(quads, g, vertex)
        if face_across(quads, vertex_faces, counts, quads[g, (i + 1) % 4], vertex)[0] < 0:
            return True
    return False


@compiled
def edge_valence(quads, vertex_faces, counts, vertex):  # pragma: no cover - compiled
    """The edges at ``vertex``: its faces, one more on a rim."""
    return counts[vertex] + (1 if is_boundary(quads, vertex_faces, counts, vertex) else 0)


@compiled
def face_across(quads, vertex_faces, counts, a, b):  # pragma: no cover - compiled
    """The face holding the directed edge a -> b and the corner of a in it, or (-1, -1)."""
    for k in range(counts[a]):
        g = vertex_faces[a, k]
        i = corner(quads, g, a)
        if i >= 0 and quads[g, (i + 1) % 4] == b:
            return g, i
    return -1, -1
