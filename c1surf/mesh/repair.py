"""Topology repairs that keep the input's meaning: consistent orientation, pinch splitting.

Both work on integers only and return what they changed, so the caller can
report it ("flipped 3 faces") and map results back to the input's numbering.
"""
from __future__ import annotations

import numpy as np

from .errors import TopologyError
from .halfedges import HalfEdgeMesh, build_halfedges, component_roots, rotation_cycles, undirected_edges


def check_edge_manifold(mesh: HalfEdgeMesh) -> None:
    """Raise TopologyError for an edge in more than two faces (the paper's precondition)."""
    if mesh.n_faces == 0:
        raise TopologyError("the mesh has no faces")
    small = np.flatnonzero(mesh.face_sizes < 3)
    if small.size:
        raise TopologyError(f"face {small[0]} has {mesh.face_sizes[small[0]]} corners; every face needs at least 3", small[:1])
    edges, edge_of, counts = undirected_edges(mesh)
    bad = np.flatnonzero(counts > 2)
    if bad.size:
        e = bad[0]
        raise TopologyError(
            f"edge between vertices {{0}} and {{1}} is shared by {counts[e]} faces; the construction needs at most two "
            f"faces per edge ({bad.size} such edges): split the mesh there (c1surf convert cuts such edges into sheets "
            "that meet along one C0 crease, but not with --non-manifold refuse or --g1-creases)",
            np.unique(mesh.face[edge_of == e]),
            edges[e],
        )


def reverse_faces(face_sizes: np.ndarray, face_vertices: np.ndarray, flip: np.ndarray) -> np.ndarray:
    """Reverse the corner order of the faces marked in ``flip``.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (H,) int
    flip : (F,) bool

    Returns
    -------
    (H,) int, new face_vertices (each flipped face keeps its first corner)
    """
    offsets = np.concatenate([[0], np.cumsum(face_sizes)])
    face = np.repeat(np.arange(face_sizes.size), face_sizes)
    local = np.arange(face_vertices.size) - offsets[face]
    # corner k of a reversed n-gon is old corner (n - k) mod n
    source = np.where(flip[face], offsets[face] + (face_sizes[face] - local) % face_sizes[face], np.arange(face_vertices.size))
    return face_vertices[source]


def orientation_flips(mesh: HalfEdgeMesh):
    """Which faces to reverse so that neighbours agree, per connected component.

    Faces sharing an edge agree when they run along it in opposite directions.
    Relative parities come from a breadth-first tree and pointer jumping; each
    component keeps the orientation most of its faces already have.

    Returns
    -------
    flip : (F,) bool
    non_orientable_faces : (k,) int, faces at an edge that no choice can make consistent (empty if orientable)
    """
    if mesh.n_faces == 0:  # nothing to orient (a file whose every face was degenerate)
        return np.zeros(0, dtype=bool), np.zeros(0, dtype=np.int64)
    from scipy.sparse import coo_matrix, csr_matrix  # only for meshes that need flips: 0.4 s to import
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    edges, edge_of, counts = undirected_edges(mesh)
    interior = np.flatnonzero(counts == 2)
    order = np.argsort(edge_of, kind="stable")
    first_of_edge = np.searchsorted(edge_of[order], interior)
    h1, h2 = order[first_of_edge], order[first_of_edge + 1]
    f1, f2 = mesh.face[h1], mesh.face[h2]
    parity = (mesh.origin[h1] == mesh.origin[h2]).astype(np.int8)  # same direction: one must flip
    n = mesh.n_faces
    _, component = connected_components(coo_matrix((np.ones(f1.size), (f1, f2)), shape=(n, n)), directed=False)
    # A super-root joined to the first face of every component makes one BFS reach all faces.
    roots = np.unique(component, return_index=True)[1]
    # One tree edge per pair of neighbouring faces (faces may share several
    # edges; if those disagree the final check reports it).
    pair_key = np.minimum(f1, f2) * n + np.maximum(f1, f2)
    _, first_pair = np.unique(pair_key, return_index=True)
    t1, t2, tp = f1[first_pair], f2[first_pair], parity[first_pair]
    rows = np.concatenate([t1, t2, np.full(roots.size, n)])
    cols = np.concatenate([t2, t1, roots])
    weight = np.concatenate([tp, tp, np.zeros(roots.size, np.int8)]).astype(np.float64) + 1.0  # +1 keeps zeros stored
    graph = csr_matrix((weight, (rows, cols)), shape=(n + 1, n + 1))
    _, predecessor = breadth_first_order(graph, n, directed=False, return_predecessors=True)
    predecessor[n] = n
    pointer = predecessor.copy()
    acc = np.zeros(n + 1, dtype=np.int8)
    acc[:n] = np.asarray(graph[np.arange(n), predecessor[:n]]).ravel() > 1.5
    while np.any(pointer != pointer[pointer]):
        acc, pointer = acc ^ acc[pointer], pointer[pointer]
    flip = acc[:n].astype(bool)
    # keep the majority orientation of each component
    flipped_count = np.bincount(component, weights=flip, minlength=roots.size)
    size = np.bincount(component, minlength=roots.size)
    flip ^= (flipped_count > size / 2)[component]
    bad = parity.astype(bool) != (flip[f1] ^ flip[f2])
    return flip, np.unique(np.r_[f1[bad], f2[bad]])


def orientation_double_cover(mesh: HalfEdgeMesh):
    """Faces of the orientation double cover of a non-orientable mesh.

    Every face appears twice, as itself (sheet 0) and reversed (sheet 1). Across
    an edge where the two faces agree, copies on the same sheet are glued;
    where they disagree, copies on opposite sheets. Cover vertices are the
    classes of glued corners, so the cover is oriented by construction.

    Returns
    -------
    face_sizes : (2F,) int, sheet 0 then sheet 1
    face_vertices : (2H,) int, cover vertex of each corner
    vertex_source : (V',) int, input vertex of each cover vertex
    """
    from scipy.sparse import coo_matrix  # non-orientable meshes only
    from scipy.sparse.csgraph import connected_components

    n_half = mesh.n_halfedges
    # corner node (sheet s, half-edge h) = s * H + h, the corner at origin[h] of face copy s
    edges, edge_of, counts = undirected_edges(mesh)
    interior = np.flatnonzero(counts == 2)
    order = np.argsort(edge_of, kind="stable")
    first_of_edge = np.searchsorted(edge_of[order], interior)
    h1, h2 = order[first_of_edge], order[first_of_edge + 1]
    same_direction = mesh.origin[h1] == mesh.origin[h2]
    # corners of h1's face at its two ends, and of h2's face at the same two vertices
    a1, b1 = h1, mesh.next[h1]  # corners at origin[h1], dest[h1]
    a2 = np.where(same_direction, h2, mesh.next[h2])  # corner of g at origin[h1]
    b2 = np.where(same_direction, mesh.next[h2], h2)  # corner of g at dest[h1]
    cross = same_direction.astype(np.int64)  # glue to the other sheet where the faces disagree
    rows, cols = [], []
    for sheet in (0, 1):
        other = (sheet + cross) % 2
        rows += [sheet * n_half + a1, sheet * n_half + b1]
        cols += [other * n_half + a2, other * n_half + b2]
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(2 * n_half, 2 * n_half))
    _, label = connected_components(graph, directed=False)
    label = label.astype(np.int64)
    vertex_source = np.empty(label.max() + 1, dtype=np.int64)
    vertex_source[label] = np.r_[mesh.origin, mesh.origin]
    sheet0 = label[:n_half]
    sheet1 = reverse_faces(mesh.face_sizes, label[n_half:], np.ones(mesh.n_faces, bool))
    return np.r_[mesh.face_sizes, mesh.face_sizes], np.r_[sheet0, sheet1], vertex_source


def split_pinched_vertices(mesh: HalfEdgeMesh):
    """One vertex per fan of faces: renumber corners so no vertex is pinched.

    Unused vertices disappear from the numbering.

    Returns
    -------
    face_vertices : (H,) int, corners renumbered
    vertex_source : (V',) int, the input vertex each new vertex copies
    n_split : int, how many input vertices had more than one fan
    """
    fan = rotation_cycles(mesh)
    used = np.bincount(mesh.origin, minlength=mesh.n_vertices) > 0
    if fan.max(initial=-1) + 1 == np.count_nonzero(used):  # one fan per used vertex (the usual mesh): no sort
        rank = np.cumsum(used) - 1  # what the sort below gives: the used vertices renumbered in order
        return rank[mesh.origin].astype(np.int64), np.flatnonzero(used).astype(mesh.origin.dtype), 0
    key = mesh.origin * (fan.max() + 1) + fan
    unique_key, new_vertex = np.unique(key, return_inverse=True)
    vertex_source = mesh.origin[np.unique(new_vertex, return_index=True)[1]]
    fans_per_vertex = np.bincount(vertex_source, minlength=mesh.n_vertices)
    return new_vertex.ravel().astype(np.int64), vertex_source, int(np.sum(fans_per_vertex > 1))


def prepare_topology(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int):
    """Check, orient and un-pinch an input polygon mesh.

    Returns
    -------
    mesh : HalfEdgeMesh, consistently oriented, every vertex one fan
    vertex_source : (V',) int, input vertex of each vertex of ``mesh``
    report : dict with ``flipped_faces``, ``split_vertices``, ``unused_vertices``, ``components``,
        ``boundary_edges``, ``non_orientable`` and ``second_sheet`` ((F',) bool: faces of the
        orientation double cover's second sheet, built for a non-orientable input; the
        surface keeps the patches of the first sheet only)
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    raw = build_halfedges(face_sizes, face_vertices, n_vertices)
    if raw.n_faces and np.all(raw.twin >= 0) and np.all(raw.face_sizes >= 3):
        # every edge has exactly two half-edges running opposite ways (that is what pairs
        # twins): closed, manifold edges, consistently oriented; nothing to check or flip
        flip, non_orientable = np.zeros(raw.n_faces, dtype=bool), np.zeros(0, dtype=np.int64)
    else:
        check_edge_manifold(raw)
        flip, non_orientable = orientation_flips(raw)
    if non_orientable.size:
        # Work on the orientation double cover; the caller keeps sheet 0 only.
        cover_sizes, cover_vertices, cover_source = orientation_double_cover(raw)
        cover = build_halfedges(cover_sizes, cover_vertices, cover_source.size)
        split_vertices, pinch_source, n_split = split_pinched_vertices(cover)
        mesh = build_halfedges(cover_sizes, split_vertices, pinch_source.size)
        vertex_source = cover_source[pinch_source]
        sheet = np.r_[np.zeros(raw.n_faces, bool), np.ones(raw.n_faces, bool)]
    else:
        if flip.any():
            face_vertices = reverse_faces(face_sizes, face_vertices, flip)
            raw = build_halfedges(face_sizes, face_vertices, n_vertices)
        split_vertices, vertex_source, n_split = split_pinched_vertices(raw)
        # nothing split or renumbered: the half-edges are already those of the final mesh
        same = vertex_source.size == n_vertices and np.array_equal(split_vertices, raw.origin)
        mesh = raw if same else build_halfedges(face_sizes, split_vertices, vertex_source.size)
        sheet = np.zeros(raw.n_faces, bool)
    used = np.zeros(n_vertices, dtype=bool)
    used[face_vertices] = True
    n_components = np.count_nonzero(component_roots(mesh.n_vertices, mesh.origin, mesh.dest) == np.arange(mesh.n_vertices))
    report = {
        "flipped_faces": 0 if non_orientable.size else int(flip.sum()),
        "split_vertices": n_split,
        "unused_vertices": int((~used).sum()),
        "components": int(n_components),
        "boundary_edges": int(np.sum(mesh.twin < 0)) // (2 if non_orientable.size else 1),  # the cover doubles them
        "non_orientable": bool(non_orientable.size),
        "second_sheet": sheet,
    }
    return mesh, vertex_source, report


def check_valence(mesh: HalfEdgeMesh, vertex_source: np.ndarray) -> None:
    """Refuse interior vertices of valence 2: they make 2-sided holes (c = -1 in A3)."""
    boundary = np.zeros(mesh.n_vertices, dtype=bool)
    b = mesh.twin < 0
    boundary[mesh.origin[b]] = True
    boundary[mesh.dest[b]] = True
    valence = np.bincount(mesh.origin, minlength=mesh.n_vertices)
    two = np.flatnonzero((valence == 2) & ~boundary)
    if two.size:
        v = two[0]
        raise TopologyError(
            f"vertex {{0}} is an interior vertex of valence 2 ({two.size} such vertices): it makes a 2-sided cell "
            "the construction cannot fill; merge its two faces or add an edge there (c1surf convert and "
            "api.surface_from_file dissolve such vertices: mesh.valence_two)",
            np.unique(mesh.face[mesh.origin == v]),
            [vertex_source[v]],
        )
