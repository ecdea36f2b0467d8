"""Polygon mesh connectivity as half-edges: integers only, built by sorting.

Half-edge ``h`` is the ``h``-th entry of the concatenated face-vertex list: it
starts at ``origin[h]`` and runs to the next corner of the same face. Faces are
counter-clockwise seen from outside, so a face lies to the left of its
half-edges.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..arrays import unique_integers

_REPEATED_FACES = 1 << 24  # fewer faces than this make ``face`` by np.repeat (its temporary: at most 128 MB)



@dataclass(frozen=True)
class HalfEdgeMesh:
    """Half-edge connectivity of a polygon mesh.

    Attributes
    ----------
    n_vertices : int
    face_sizes : (F,) int64
    face_offsets : (F+1,) int64, half-edges of face f are face_offsets[f]:face_offsets[f+1]
    origin : (H,) int, vertex each half-edge starts at
    face : (H,) int, face each half-edge belongs to
    next, prev : (H,) int, following / preceding half-edge in the same face
    twin : (H,) int, opposite half-edge in the neighbouring face, -1 on a boundary

    The per-half-edge arrays are int64 for input meshes and int32 for refined
    meshes small enough (``doo_sabin.refined_halfedges``: half the memory
    traffic on the largest arrays); products of them are formed in int64.
    ``face_offsets``, ``face`` and ``prev`` may be given as None: each is then
    made when first read, ``face_offsets`` and ``face`` from ``face_sizes``,
    ``prev`` from ``next`` (a refined mesh's: for the 4,000,000-quad torus the
    twice-refined mesh's ``face`` is 1 GB and its offsets 0.5 GB, which a
    conversion reads only once the stages are gone, or never; its ``prev``,
    1 GB, nothing reads when the mesh has no holes). ``release_prev`` lets
    ``prev`` go again. A refined mesh also knows how to make its ``twin``
    again (``remake_twin``, from the coarser mesh): ``release_twin`` lets it go
    until it is read again.
    """

    n_vertices: int
    face_sizes: np.ndarray
    _face_offsets: np.ndarray | None
    origin: np.ndarray
    _face: np.ndarray | None
    next: np.ndarray
    _prev: np.ndarray | None
    _twin: np.ndarray | None
    remake_twin: Callable[[], np.ndarray] | None = None

    @property
    def twin(self) -> np.ndarray:
        """(H,) int, opposite half-edge in the neighbouring face, -1 on a boundary."""
        if self._twin is None and self.remake_twin is not None:
            object.__setattr__(self, "_twin", self.remake_twin())
        return self._twin

    def release_twin(self) -> None:
        """Let ``twin`` go if it can be made again (``remake_twin``; the same values the next time it is read)."""
        if self.remake_twin is not None:
            object.__setattr__(self, "_twin", None)

    @property
    def face_offsets(self) -> np.ndarray:
        """(F+1,) int64, half-edges of face f are face_offsets[f]:face_offsets[f+1]."""
        if self._face_offsets is None:
            offsets = np.zeros(self.face_sizes.size + 1, dtype=np.int64)
            np.cumsum(self.face_sizes, out=offsets[1:])
            object.__setattr__(self, "_face_offsets", offsets)  # made once, as if given (the class is frozen)
        return self._face_offsets

    @property
    def face(self) -> np.ndarray:
        """(H,) int (``origin``'s type), face each half-edge belongs to: face f repeated face_sizes[f] times."""
        if self._face is None:
            if self.face_sizes.size < _REPEATED_FACES:  # 3x faster than the sums below (0.018 s against 0.05 s
                # for the 180,000-quad torus's twice-refined mesh), with a temporary of 8 bytes a face
                face = np.repeat(np.arange(self.face_sizes.size, dtype=self.origin.dtype), self.face_sizes)
            else:  # a 1 where each face but the first starts, summed up: np.repeat makes its repeats intp (that
                # temporary would be 0.5 GB for the 4,000,000-quad torus's twice-refined mesh)
                face = np.zeros(self.origin.size, dtype=self.origin.dtype)
                face[np.cumsum(self.face_sizes[:-1], dtype=self.origin.dtype)] = 1
                np.cumsum(face, out=face)
            object.__setattr__(self, "_face", face)
        return self._face

    @property
    def prev(self) -> np.ndarray:
        """(H,) int, preceding half-edge in the same face: the inverse of ``next``."""
        if self._prev is None:
            prev = np.empty_like(self.next)
            prev[self.next] = np.arange(self.next.size, dtype=self.next.dtype)
            object.__setattr__(self, "_prev", prev)  # made once, as if given (the class is frozen)
        return self._prev

    def release_prev(self) -> None:
        """Let ``prev`` go (made again from ``next`` if read again: the same values, ``next``'s type, as given).

        For a holder done with the rotations: the refinement reads the coarse and once-refined meshes'
        (0.13 and 0.25 GB for the 4,000,000-quad torus); the stages of a mesh without creases never do.
        """
        if self._prev is not None and self._prev.dtype == self.next.dtype:
            object.__setattr__(self, "_prev", None)

    @property
    def n_faces(self) -> int:
        return int(self.face_sizes.size)

    @property
    def n_halfedges(self) -> int:
        return int(self.origin.size)

    @property
    def dest(self) -> np.ndarray:
        """(H,) int64, vertex each half-edge ends at."""
        return self.origin[self.next]

    def rotate(self, h: np.ndarray) -> np.ndarray:
        """Next outgoing half-edge counter-clockwise around ``origin[h]``.

        Parameters
        ----------
        h : (k,) int, outgoing half-edges

        Returns
        -------
        (k,) int; -1 where the rotation meets a boundary.
        """
        return self.twin[self.prev[h]]

    def faces_by_size(self, skip=()):
        """Yield ``(n, faces, halfedges)`` for each distinct face size n not in ``skip``.

        ``faces`` is (Fn,) int, ``halfedges`` is (Fn, n) int: the half-edges of
        each face in order. Lets callers work on whole arrays per cell size.
        """
        for n in np.flatnonzero(np.bincount(self.face_sizes)):  # the sizes present (bincount: no sort)
            if n in skip:
                continue
            faces = np.flatnonzero(self.face_sizes == n)
            halfedges = self.face_offsets[faces][:, None] + np.arange(n)
            yield int(n), faces, halfedges


def face_cycles(face_sizes: np.ndarray, index=np.int64):
    """Half-edge bookkeeping that depends on the face sizes alone.

    Parameters
    ----------
    face_sizes : (F,) int64
    index : integer dtype of the per-half-edge arrays

    Returns
    -------
    offsets : (F+1,) int64; face : (H,) index; next, prev : (H,) index
    """
    offsets = np.zeros(face_sizes.size + 1, dtype=np.int64)
    np.cumsum(face_sizes, out=offsets[1:])
    n_half = int(offsets[-1])
    face = np.repeat(np.arange(face_sizes.size, dtype=index), face_sizes)
    nxt = np.arange(1, n_half + 1, dtype=index)
    last = offsets[1:] - 1
    nxt[last] = offsets[:-1]
    prv = np.arange(-1, n_half - 1, dtype=index)
    prv[offsets[:-1]] = last
    return offsets, face, nxt, prv


def build_halfedges(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> HalfEdgeMesh:
    """Half-edge structure of a polygon mesh (twins found by one sort of edge keys).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int, faces concatenated
    n_vertices : int

    Returns
    -------
    HalfEdgeMesh; ``twin`` is -1 for half-edges without an oppositely directed
    partner (boundary, or inconsistent orientation: see ``repair.prepare_topology``).
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    origin = np.asarray(face_vertices, dtype=np.int64)
    offsets, face, nxt, prv = face_cycles(face_sizes)
    n_half = origin.size
    dest = origin[nxt]
    # Twins: the two half-edges of an undirected edge, if there are exactly two
    # and they run in opposite directions (more, or the same direction, means a
    # non-manifold edge or flipped faces, which repair.prepare_topology handles).
    key = np.minimum(origin, dest) * n_vertices + np.maximum(origin, dest)
    order = np.argsort(key)
    key = key[order]
    twin = np.full(n_half, -1, dtype=np.int64)
    if n_half > 1:
        same = key[1:] == key[:-1]
        run = np.zeros(n_half + 1, dtype=bool)
        run[1:-1] = same
        pair = same & ~run[:-2] & ~run[2:]
        a, b = order[:-1][pair], order[1:][pair]
        opposite = origin[a] == dest[b]
        twin[a[opposite]], twin[b[opposite]] = b[opposite], a[opposite]
    return HalfEdgeMesh(int(n_vertices), face_sizes, offsets, origin, face, nxt, prv, twin)


def undirected_edges(mesh: HalfEdgeMesh):
    """Unique undirected edges and, per half-edge, its edge index.

    Returns
    -------
    edges : (E, 2) int, vertex pairs with edges[:, 0] < edges[:, 1]
    edge_of_halfedge : (H,) int
    counts : (E,) int, half-edges per edge (2 for an interior manifold edge)
    """
    a, b = mesh.origin.astype(np.int64, copy=False), mesh.dest.astype(np.int64, copy=False)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    key = lo * mesh.n_vertices + hi
    unique, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    edges = np.stack([unique // mesh.n_vertices, unique % mesh.n_vertices], axis=1)
    return edges, inverse.ravel(), counts


def vertex_valences(mesh: HalfEdgeMesh) -> np.ndarray:
    """(V,) int: number of faces around each vertex (0 for unused vertices)."""
    return np.bincount(mesh.origin, minlength=mesh.n_vertices)


def rotation_cycles(mesh: HalfEdgeMesh) -> np.ndarray:
    """Label the fans of faces around each vertex.

    Returns
    -------
    (H,) int: half-edges that ``rotate`` into each other share a label. A
    manifold interior vertex has exactly one label among its outgoing half-edges.
    """
    h = np.arange(mesh.n_halfedges)
    r = mesh.rotate(h)
    return orbit_labels(r, int(vertex_valences(mesh).max(initial=0)))


def orbit_labels(successor: np.ndarray, longest: int) -> np.ndarray:
    """Label the orbits of a partial permutation: what ``scipy.sparse.csgraph.connected_components`` gives
    for the undirected graph of the pairs (h, successor[h]), without importing it (0.2 s: csgraph imports
    scipy.sparse.linalg and scipy.linalg).

    Parameters
    ----------
    successor : (n,) int, injective where >= 0, -1 where undefined; its orbits are chains and cycles
    longest : int, at least the length of the longest orbit

    Returns
    -------
    (n,) int32: components numbered in the order of their smallest element, as scipy numbers them

    Every element takes the minimum over a window along its orbit that doubles in each step (pointer
    jumping in both directions), so ceil(log2(longest)) + 1 steps cover every orbit.
    """
    n = successor.size
    kind = np.int32 if n < 2**31 - 1 else np.int64
    # element n is a sentinel: undefined steps go there, it steps to itself and its label is above all
    succ = np.full(n + 1, n, dtype=kind)
    succ[:n] = np.where(successor >= 0, successor, n)
    pred = np.full(n + 1, n, dtype=kind)
    pred[succ[:n]] = np.arange(n, dtype=kind)
    pred[n] = n
    label = np.arange(n + 1, dtype=kind)
    label[n] = np.iinfo(kind).max
    reach = 1
    while reach < max(longest, 1) + 1:
        np.minimum(label, np.take(label, succ, mode="clip"), out=label)  # clip: no bounds check (all valid)
        np.minimum(label, np.take(label, pred, mode="clip"), out=label)
        succ, pred = np.take(succ, succ, mode="clip"), np.take(pred, pred, mode="clip")
        reach *= 2
    label = label[:n]
    first = label == np.arange(n, dtype=kind)  # the smallest element of each orbit
    return (np.cumsum(first) - 1)[label].astype(np.int32)


def component_roots(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) int: the smallest vertex of every vertex's component in the undirected graph of edges (a[i], b[i]).

    Roots are hooked under smaller roots across the edges between components and the forest is
    compressed, until no edge crosses: what ``scipy.sparse.csgraph.connected_components`` finds,
    without importing csgraph (0.2 s, with scipy.sparse.linalg and scipy.linalg), which the usual
    conversion needs nowhere else. Counted with ``np.count_nonzero(roots == np.arange(n))``.
    """
    kind = np.int32 if n < 2**31 else np.int64
    parent = np.arange(n, dtype=kind)
    a, b = np.asarray(a, dtype=kind), np.asarray(b, dtype=kind)
    while a.size:
        root_a, root_b = np.take(parent, a), np.take(parent, b)
        crossing = root_a != root_b
        if not crossing.any():
            break
        a, b, root_a, root_b = a[crossing], b[crossing], root_a[crossing], root_b[crossing]
        np.minimum.at(parent, np.maximum(root_a, root_b), np.minimum(root_a, root_b))  # a smaller root: no cycles
        while True:  # every vertex straight to its root
            grand = np.take(parent, parent)
            if np.array_equal(grand, parent):
                break
            parent = grand
    return parent


def interior_vertices(mesh: HalfEdgeMesh, valence: np.ndarray | None = None) -> np.ndarray:
    """(V,) bool: used vertices not on a boundary edge (their rotation closes).

    valence : (V,) int, ``vertex_valences(mesh)`` if the caller has it (not counted again)
    """
    interior = (vertex_valences(mesh) if valence is None else valence) > 0
    boundary = np.flatnonzero(mesh.twin < 0)
    if boundary.size:  # the ends of boundary half-edges only (not ``dest`` of every half-edge)
        interior[mesh.origin[boundary]] = False
        interior[mesh.origin[mesh.next[boundary]]] = False
    return interior


def first_outgoing(mesh: HalfEdgeMesh) -> np.ndarray:
    """(V,) int: an outgoing half-edge of every vertex, -1 for unused vertices."""
    v = mesh.n_vertices
    if mesh.n_halfedges >= v and np.array_equal(mesh.origin[:v], np.arange(v)):
        # a Doo-Sabin refined mesh: its F-faces come first and list every vertex once, in order
        return np.arange(v, dtype=mesh.origin.dtype)
    first = np.full(v, -1, dtype=np.int64)
    first[mesh.origin[::-1]] = np.arange(mesh.n_halfedges)[::-1]
    return first


def outgoing_rings(mesh: HalfEdgeMesh, index=np.int64):
    """Outgoing half-edges of every interior vertex in counter-clockwise order.

    ``index`` : integer dtype of ``ring``

    Returns
    -------
    vertices : (k,) int, the interior vertices (boundary and unused ones are left out)
    sizes : (k,) int, their valences
    ring : (sum(sizes),) int, each vertex's outgoing half-edges in rotation order,
        concatenated in the order of ``vertices``
    """
    valence = vertex_valences(mesh)
    vertices = np.flatnonzero(interior_vertices(mesh, valence))
    sizes = valence[vertices]
    # Start each ring at the vertex's first half-edge, then walk the rotation:
    # one vectorized step per ring position, over the rings still that long.
    first = first_outgoing(mesh)
    if sizes.size and sizes.min() == sizes.max():  # one valence (4 in a closed Doo-Sabin refined mesh)
        # rings side by side as rows: no offsets, no selection of the rings still that long
        rows = np.empty((vertices.size, int(sizes[0])), dtype=index)
        current = first[vertices]
        for k in range(rows.shape[1]):
            rows[:, k] = current
            if k + 1 < rows.shape[1]:
                current = mesh.rotate(current)
        return vertices, sizes, rows.reshape(-1)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    ring = np.empty(offsets[-1], dtype=index)
    current = first[vertices]
    active = np.arange(vertices.size)
    for k in range(int(sizes.max(initial=0))):
        keep = sizes[active] > k
        active, current = active[keep], current[keep]
        ring[offsets[active] + k] = current
        current = mesh.rotate(current)
    return vertices, sizes, ring


def mesh_edge_keys(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> np.ndarray:
    """Sorted unique keys ``min * V + max`` of the mesh's undirected edges.

    Parameters
    ----------
    face_sizes : ndarray, shape (F,), int
    face_vertices : ndarray, shape (sum(face_sizes),), int
    n_vertices : int, V

    Returns
    -------
    ndarray, shape (number of edges,), int64
    """
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    offs = np.zeros(len(face_sizes) + 1, dtype=np.int64)
    np.cumsum(face_sizes, out=offs[1:])
    nxt = np.arange(1, face_vertices.size + 1)
    nonempty = np.asarray(face_sizes) > 0
    nxt[offs[1:][nonempty] - 1] = offs[:-1][nonempty]
    a, b = face_vertices, face_vertices[nxt] if face_vertices.size else face_vertices
    return unique_integers(np.minimum(a, b) * n_vertices + np.maximum(a, b))
