"""Compiled passes of the simplification driver (``simplify``): many local operations in one sequential loop.

Each pass walks its candidates in the order the driver gives (cheapest first) and tries each operation
(``operations``); a face none of whose vertices an earlier operation of the same round touched (``stamp``) is
still as the driver measured it, so its cost holds, and the others wait for the next round. The loops are
sequential by nature (an operation changes what its neighbours may do), hence compiled.
"""
from __future__ import annotations

import numpy as np

from ....evaluation.compiled.kernels import compiled
from .links import face_across
from .operations import collapse_diagonal, collapse_polychord, remove_doublet, rotate_edge

__all__ = ["collapse_pass", "doublet_pass", "rotate_pass", "polychord_pass"]


@compiled
def _fresh(quads, stamp, face, round_id):  # pragma: no cover - compiled
    """Whether no vertex of ``face`` was touched in this round."""
    for i in range(4):
        if stamp[quads[face, i]] == round_id:
            return False
    return True


@compiled
def _stamp_ring(quads, vertex_faces, counts, stamp, vertex, round_id):  # pragma: no cover - compiled
    """Mark ``vertex`` and every vertex of its faces as touched."""
    stamp[vertex] = round_id
    for s in range(counts[vertex]):
        for i in range(4):
            stamp[quads[vertex_faces[vertex, s], i]] = round_id


@compiled
def collapse_pass(mesh, guard, order_face, order_corner, budget, quadrics, stamp, round_id):  # pragma: no cover
    """Diagonal collapses in the given order until ``live`` faces reach ``target``; the doublets a collapse leaves
    at the quad's other two corners are removed at once; ``budget``: (live, target); ``quadrics`` (V, 4, 4): the
    merged vertex takes the sum. Returns (live faces, collapses)."""
    quads, alive, vertex_faces, counts = mesh[0], mesh[1], mesh[2], mesh[3]
    live, target = budget
    done = 0
    for t in range(order_face.size):
        if live <= target:
            break
        f = order_face[t]
        if not alive[f] or not _fresh(quads, stamp, f, round_id):
            continue
        k = order_corner[t]
        a, b, c, d = quads[f, k], quads[f, (k + 1) % 4], quads[f, (k + 2) % 4], quads[f, (k + 3) % 4]
        if collapse_diagonal(mesh, guard, f, k):
            quadrics[a] += quadrics[c]
            live -= 1
            done += 1
            _stamp_ring(quads, vertex_faces, counts, stamp, a, round_id)
            for v in (b, d):
                if remove_doublet(mesh, guard, v):
                    live -= 1
    return live, done


@compiled
def doublet_pass(mesh, guard):  # pragma: no cover - compiled
    """Remove every interior vertex of valence 2, until none is left. Returns the faces removed."""
    counts = mesh[3]
    removed, changed = 0, True
    while changed:
        changed = False
        for v in range(counts.size):
            if counts[v] == 2 and remove_doublet(mesh, guard, v):
                removed += 1
                changed = True
    return removed


@compiled
def _valence_gain(quads, valence, ideal, face, k, other, j):  # pragma: no cover - compiled
    """(gain of turn +1, gain of turn -1, the hexagon): the drop of the sum of (valence - ideal)^2 over the hexagon
    of the two quads at the edge (``ideal`` 4 inside, 3 on a rim)."""
    hexagon = np.array([quads[face, (k + 1) % 4], quads[face, (k + 2) % 4], quads[face, (k + 3) % 4], quads[face, k],
                        quads[other, (j + 2) % 4], quads[other, (j + 3) % 4]])
    dev = np.empty(6)
    for i in range(6):
        dev[i] = valence[hexagon[i]] - ideal[hexagon[i]]
    base = (dev[0] - 1) ** 2 + (dev[3] - 1) ** 2 - dev[0] ** 2 - dev[3] ** 2
    plus = base + (dev[1] + 1) ** 2 + (dev[4] + 1) ** 2 - dev[1] ** 2 - dev[4] ** 2
    minus = base + (dev[2] + 1) ** 2 + (dev[5] + 1) ** 2 - dev[2] ** 2 - dev[5] ** 2
    return -plus, -minus, hexagon


@compiled
def rotate_pass(mesh, guard, valence, ideal):  # pragma: no cover - compiled
    """Turn every interior edge whose turn lowers the valence energy (``_valence_gain``) by 2 or more (the turn
    of larger gain first); ``valence`` (V,) edges at each vertex, kept up to date, ``ideal`` (V,) 4 or 3 (rim).
    Returns the edges turned."""
    quads, alive, vertex_faces, counts = mesh[0], mesh[1], mesh[2], mesh[3]
    turned = 0
    for f in range(quads.shape[0]):
        for k in range(4):
            if not alive[f]:
                break
            other, j = face_across(quads, vertex_faces, counts, quads[f, (k + 1) % 4], quads[f, k])
            if other < 0 or other < f:
                continue
            plus, minus, hexagon = _valence_gain(quads, valence, ideal, f, k, other, j)
            best, turn = (plus, 1) if plus >= minus else (minus, -1)
            if best >= 2.0 and rotate_edge(mesh, guard, f, k, turn):
                turned += 1
                valence[hexagon[0]] -= 1
                valence[hexagon[3]] -= 1
                s = 1 if turn > 0 else 2
                valence[hexagon[s]] += 1
                valence[hexagon[s + 3]] += 1
    return turned


@compiled
def polychord_pass(mesh, guard, order_face, order_corner, budget, quadrics, stamp,
                   round_id):  # pragma: no cover - compiled
    """Polychord collapses in the given order until the live faces reach ``target`` or ``tries`` attempts in a row
    fail (``budget``: (live, target, tries); ``quadrics`` as ``collapse_pass``'s).
    Returns (live faces, strips collapsed)."""
    quads, alive, vertex_faces, counts, points = mesh
    live, target, tries = budget
    faces = np.empty(quads.shape[0], dtype=np.int64)
    edges = np.empty((quads.shape[0] + 1, 2), dtype=np.int64)
    remap = np.full(points.shape[0], -1, dtype=np.int64)
    done, misses = 0, 0
    for t in range(order_face.size):
        if live <= target or misses >= tries:
            break
        f = order_face[t]
        if not alive[f] or not _fresh(quads, stamp, f, round_id):
            continue
        m = collapse_polychord(mesh, guard, f, order_corner[t], (faces, edges, remap))
        misses += 1
        if m > 0:
            misses = 0
            live = 0
            for g in range(alive.size):
                live += 1 if alive[g] else 0
            done += 1
            for s in range(m):
                quadrics[edges[s, 0]] += quadrics[edges[s, 1]]
                _stamp_ring(quads, vertex_faces, counts, stamp, edges[s, 0], round_id)
    return live, done
