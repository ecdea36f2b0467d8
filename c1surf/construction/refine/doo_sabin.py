"""Doo-Sabin refinement topology (dual quad quadrisection): integers only.

One refinement makes a new point for every corner of every face, that is for
every half-edge ``h`` of the coarse mesh (the corner at ``origin[h]`` in
``face[h]``), so fine vertex ``h`` *is* coarse half-edge ``h``. The new faces are

- an F-face per coarse face (same size, its corners in order),
- an E-face per coarse interior edge (a quad),
- a V-face per coarse vertex (as many sides as the vertex has faces).

Where the new points go is ``stencils.doo_sabin``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ...mesh.halfedges import HalfEdgeMesh, outgoing_rings
from ...parallel import run_tasks

FACE_FROM_FACE, FACE_FROM_EDGE, FACE_FROM_VERTEX = 0, 1, 2
THREADED_HALFEDGES = 1 << 25  # refined meshes below this many half-edges make next and twin on two threads


@dataclass(frozen=True)
class RefinedFaces:
    """Faces of a refined mesh and where each came from.

    Attributes
    ----------
    face_sizes : (F',) int (int32 when the fine half-edges fit, as ``face_vertices``)
    face_vertices : (sum(face_sizes),) int (int32 when it fits), indices of fine vertices (= coarse half-edges)
    kind : (F',) int8, FACE_FROM_FACE / FACE_FROM_EDGE / FACE_FROM_VERTEX (None: not asked for)
    parent : (F',) int64, coarse face, coarse half-edge (one of the edge's two) or coarse vertex (None: not asked for)
    """

    face_sizes: np.ndarray
    face_vertices: np.ndarray
    kind: np.ndarray
    parent: np.ndarray


def refined_index_type(mesh: HalfEdgeMesh):
    """int32 if every index of the once-refined ``mesh`` fits (fine half-edges <= 4 H + 4 V), else int64."""
    return np.int32 if 4 * (mesh.n_halfedges + mesh.n_vertices) < 2**31 else np.int64


def refine_doo_sabin(mesh: HalfEdgeMesh, sources: bool = True) -> RefinedFaces:
    """Faces of one Doo-Sabin (dual quad quadrisection) step of a closed mesh.

    Parameters
    ----------
    mesh : HalfEdgeMesh, closed and manifold (every twin defined)
    sources : bool, make ``kind`` and ``parent`` (False: None; the last step's are not read, and its
        ``parent`` is 0.5 GB for the 4,000,000-quad torus)

    Returns
    -------
    RefinedFaces, consistently oriented with the coarse faces.
    """
    # fine vertices are coarse half-edges, and the fine mesh has about 4 times as
    # many half-edges: int32 whenever that fits
    index = refined_index_type(mesh)
    n_half, n_faces = mesh.n_halfedges, mesh.n_faces
    rep = _edge_halfedges(mesh, index)  # one half-edge of each interior edge, in order
    vertices, v_sizes, ring = outgoing_rings(mesh, index)
    # every part written in place into the arrays of all faces (no concatenation of the parts)
    n_fine = n_faces + rep.size + vertices.size
    face_sizes = np.empty(n_fine, dtype=index)
    face_sizes[:n_faces] = mesh.face_sizes
    face_sizes[n_faces : n_faces + rep.size] = 4
    face_sizes[n_faces + rep.size :] = v_sizes
    face_vertices = np.empty(n_half + 4 * rep.size + ring.size, dtype=index)
    # F-faces: the corners of each face, in order.
    face_vertices[:n_half] = np.arange(n_half, dtype=index)
    # E-faces: for the edge of h (a -> b in face f) and its twin t (b -> a in
    # face g), the quad (corner b in f, corner a in f, corner a in g, corner b in g).
    t = mesh.twin[rep]
    quads = face_vertices[n_half : n_half + 4 * rep.size].reshape(-1, 4)
    quads[:, 0], quads[:, 1], quads[:, 2], quads[:, 3] = mesh.next[rep], rep, mesh.next[t], t
    # V-faces: the corners around each vertex in rotation order.
    face_vertices[n_half + 4 * rep.size :] = ring
    if not sources:
        return RefinedFaces(face_sizes=face_sizes, face_vertices=face_vertices, kind=None, parent=None)
    kind = np.empty(n_fine, dtype=np.int8)
    kind[:n_faces], kind[n_faces : n_faces + rep.size], kind[n_faces + rep.size :] = \
        FACE_FROM_FACE, FACE_FROM_EDGE, FACE_FROM_VERTEX
    parent = np.empty(n_fine, dtype=np.int64)
    parent[:n_faces] = np.arange(n_faces)
    parent[n_faces : n_faces + rep.size] = rep
    parent[n_faces + rep.size :] = vertices
    return RefinedFaces(face_sizes=face_sizes, face_vertices=face_vertices, kind=kind, parent=parent)


def refined_halfedges(mesh: HalfEdgeMesh, faces: RefinedFaces) -> HalfEdgeMesh:
    """Half-edges of the refined mesh by index arithmetic (no sort, no search).

    Every fine half-edge has its twin at a known place, so this gives exactly
    ``build_halfedges(faces.face_sizes, faces.face_vertices, mesh.n_halfedges)``
    at a fraction of the cost (the twice-refined mesh has 16 times the coarse
    half-edges). With H coarse half-edges, E interior edges and fine faces in
    ``refine_doo_sabin``'s order, the fine half-edges are

    - F-face of ``face[h]``: h -> next[h] at position h; twin in the E-face of h's edge;
    - E-face k of ``rep`` (twin ``t``): next[rep] -> rep, rep -> next[t],
      next[t] -> t, t -> next[rep] at H + 4k + 0..3; twins in the F-faces and
      in the V-faces of the edge's two end vertices;
    - V-face of a vertex: h -> rotate(h) at H + 4E + (h's place in the ring);
      twin in the E-face of ``prev[h]``'s edge.

    Boundary half-edges (the coarse edge or vertex has no E- or V-face) get -1. The F-faces' part of
    ``next`` is the coarse mesh's, the E-faces are quads in a row; ``face_offsets``, ``face`` and ``prev``
    are made when first read (``HalfEdgeMesh``), so the only per-half-edge arrays made here are ``next``
    and ``twin`` (and the refined faces' ``face_vertices`` are its ``origin``).

    Parameters
    ----------
    mesh : HalfEdgeMesh, the coarse mesh ``faces`` was refined from
    faces : RefinedFaces, ``refine_doo_sabin(mesh)``

    Returns
    -------
    HalfEdgeMesh with ``mesh.n_halfedges`` vertices
    """
    index = faces.face_vertices.dtype
    n_fine = faces.face_vertices.size
    rep = _edge_halfedges(mesh, index)  # the E-faces' coarse half-edges (their ``parent``, which may be None)
    ring_sizes = faces.face_sizes[mesh.n_faces + rep.size :]
    tasks = [partial(_refined_next, mesh, ring_sizes, rep.size, n_fine, index),
             partial(_refined_twin, mesh, rep, faces.face_vertices)]
    # independent: two tasks on the thread pool, but one after the other for the largest meshes, where both
    # tasks' temporaries at once would be a GB more (the 4,000,000-quad torus peaks 0.4 GB below its 8 GB goal)
    nxt, twin = run_tasks(tasks) if n_fine < THREADED_HALFEDGES else [task() for task in tasks]
    del rep, tasks
    # face offsets, face and prev: made when first read (the twice-refined mesh's offsets and face are read
    # once the stages are gone, if at all: 1.5 GB for the 4,000,000-quad torus); twin can be made again
    return HalfEdgeMesh(int(mesh.n_halfedges), faces.face_sizes, None, faces.face_vertices, None, nxt, None, twin,
                        remake_twin=partial(_remade_twin, mesh, faces.face_vertices))


def _remade_twin(mesh: HalfEdgeMesh, origin: np.ndarray) -> np.ndarray:
    """The refined mesh's ``twin`` again (``HalfEdgeMesh.remake_twin``), from the coarse ``mesh`` and the refined
    ``origin``: its E-faces' half-edges are the coarse ones below their twins, in order (``refine_doo_sabin``)."""
    twin = _refined_twin(mesh, _edge_halfedges(mesh, origin.dtype), origin)
    mesh.release_prev()  # made for this: the coarse mesh's holder had let it go (``topology.refine``)
    return twin


def _edge_halfedges(mesh: HalfEdgeMesh, index) -> np.ndarray:
    """(E,) ``index``: the half-edges below their twins, in order: one per interior edge (``refine_doo_sabin``'s)."""
    h = np.arange(mesh.n_halfedges, dtype=index)
    return h[h < mesh.twin]


def _refined_twin(mesh: HalfEdgeMesh, rep: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """(H',) ``twin`` of the refined mesh (``refined_halfedges``) whose half-edges start at ``origin`` (H',), refined
    from ``mesh``; ``rep`` (E,): the coarse half-edge of every E-face (the refined faces' ``parent`` there)."""
    index, n_half, n_fine = origin.dtype, mesh.n_halfedges, origin.size
    n_edges = rep.size
    rep = rep.astype(index, copy=False)
    t = np.take(mesh.twin, rep).astype(index, copy=False)
    ring_start = n_half + 4 * n_edges
    # twins: F-face half-edge h and its E-face side (0 for rep, 2 for t) ...
    twin = np.full(n_fine, -1, dtype=index)
    side = np.arange(n_half, ring_start, 4, dtype=index)
    twin[rep], twin[t] = side, side + 2
    # ... the E-faces' sides 1 and 3 in the V-faces of the edge's ends ...
    ring = origin[ring_start:]
    ring_slot = np.full(n_half, -1, dtype=index)  # where each coarse half-edge is in its vertex's V-face
    ring_slot[ring] = np.arange(ring_start, n_fine, dtype=index)
    e_twin = twin[n_half:ring_start].reshape(n_edges, 4)
    e_twin[:, 0], e_twin[:, 2] = rep, t
    e_twin[:, 1], e_twin[:, 3] = ring_slot[np.take(mesh.next, t)], ring_slot[np.take(mesh.next, rep)]
    # ... and a V-face's half-edge from h: side 3 (prev[h] is rep) or 1 (it is t) of prev[h]'s E-face,
    # which is twin[prev[h]] (side 0 or 2) + 3 or - 1
    across = twin[np.take(mesh.prev, ring)]
    ends = twin[ring_start:]
    np.subtract(across, n_half, out=ends)
    ends &= 3
    ends *= -2
    ends += across
    ends += 3  # across + 3 - 2 ((across - H) & 3)
    return twin


def _refined_next(mesh: HalfEdgeMesh, ring_sizes: np.ndarray, n_edges: int, n_fine: int, index) -> np.ndarray:
    """``next`` (n_fine,) of the refined mesh (``refined_halfedges``): the F-faces' is the coarse mesh's, the
    E-faces are quads in a row, the V-faces (sizes ``ring_sizes``) cycles of their sizes."""
    n_half = mesh.n_halfedges
    ring_start = n_half + 4 * n_edges
    nxt = np.empty(n_fine, dtype=index)
    nxt[:n_half] = mesh.next
    # E-faces: a long run of arange, then every fourth entry wrapped (broadcasting over rows of 4 runs
    # inner loops of 4 and is 3x slower)
    e_next = nxt[n_half:ring_start]
    e_next[:] = np.arange(n_half + 1, ring_start + 1, dtype=index)
    e_next[3::4] -= 4
    # V-faces: each face's half-edges in a cycle (``halfedges.face_cycles``, shifted)
    v_next = nxt[ring_start:]
    v_next[:] = np.arange(ring_start + 1, n_fine + 1, dtype=index)
    if ring_sizes.size:
        ends = np.cumsum(ring_sizes)  # one past each V-face's last half-edge, from ring_start
        v_next[ends - 1] = ring_start + ends - ring_sizes
    return nxt
