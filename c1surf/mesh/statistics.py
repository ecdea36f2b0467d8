"""What a polygon mesh is, as counts: sizes, valences, boundaries, components, genus. Integers only.

Everything is computed on the plain arrays of the input (``face_sizes``,
``face_vertices``), vectorized: one half-edge build, sorts, bincounts and
``connected_components``; no loop over faces or vertices.

Vertices are counted as the file has them, except for the components and
their genus, which are those of the surface after each pinched vertex is
split into one vertex per fan of faces (what ``repair.split_pinched_vertices``
makes before the construction): two spheres touching at a point are two
components of genus 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..arrays import unique_integers
from .halfedges import HalfEdgeMesh, build_halfedges, undirected_edges
from .repair import orientation_flips


@dataclass(frozen=True)
class ComponentStatistics:
    """Counts of the connected components of a mesh (after pinch splitting), one entry each.

    Attributes
    ----------
    vertices, edges, faces : (K,) int64
    boundary_edges, boundary_loops : (K,) int64
    non_manifold_edges : (K,) int64, edges in more than two faces
    euler_characteristic : (K,) int64, V - E + F
    orientable : (K,) bool, False where ``repair.orientation_flips`` finds no consistent orientation
    """

    vertices: np.ndarray
    edges: np.ndarray
    faces: np.ndarray
    boundary_edges: np.ndarray
    boundary_loops: np.ndarray
    non_manifold_edges: np.ndarray
    euler_characteristic: np.ndarray
    orientable: np.ndarray

    @property
    def genus(self) -> np.ndarray:
        """(K,) float: (2 - chi - b) / 2 of an orientable manifold component, NaN for the others.

        ``b`` counts the boundary loops, so a disk has genus 0 and an open cylinder too.
        """
        g = (2 - self.euler_characteristic - self.boundary_loops) / 2
        return np.where(self.orientable & (self.non_manifold_edges == 0), g, np.nan)

    @property
    def nonorientable_genus(self) -> np.ndarray:
        """(K,) float: 2 - chi - b (the number of cross-caps) of a non-orientable manifold component, else NaN."""
        k = (2 - self.euler_characteristic - self.boundary_loops).astype(float)
        return np.where(~self.orientable & (self.non_manifold_edges == 0), k, np.nan)


@dataclass(frozen=True)
class MeshStatistics:
    """Counts of a polygon mesh, as the file has it.

    Attributes
    ----------
    n_vertices, n_faces, n_edges : int, V (unused vertices included), F, undirected edges E
    face_sizes : (S, 2) int64, rows (face size, number of faces), sizes increasing
    interior_valences, boundary_valences : (k, 2) int64, rows (valence, number of vertices):
        faces around a used vertex, for vertices on no boundary edge and for those on one
    unused_vertices : int, vertices in no face
    boundary_edges : int, edges in one face
    boundary_loops : int, closed chains of boundary edges (after pinch splitting)
    non_manifold_edges : int, edges in more than two faces
    pinched_vertices : int, vertices where several fans of faces meet (faces glued across edges)
    valence2_interior_vertices : int, interior vertices in exactly two faces
    components : ComponentStatistics
    """

    n_vertices: int
    n_faces: int
    n_edges: int
    face_sizes: np.ndarray
    interior_valences: np.ndarray
    boundary_valences: np.ndarray
    unused_vertices: int
    boundary_edges: int
    boundary_loops: int
    non_manifold_edges: int
    pinched_vertices: int
    valence2_interior_vertices: int
    components: ComponentStatistics


def histogram(values: np.ndarray) -> np.ndarray:
    """(k, 2) int64 rows (value, count) of the distinct ``values`` ((n,) int), values increasing."""
    value, count = np.unique(np.asarray(values, dtype=np.int64), return_counts=True)
    return np.stack([value, count], axis=1).astype(np.int64).reshape(-1, 2)


def degenerate_faces(face_sizes: np.ndarray, face_vertices: np.ndarray) -> np.ndarray:
    """Faces that visit some vertex more than once (``f 1 2 3 3``, ``f 1 2 1 3``).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int

    Returns
    -------
    (k,) int64, those faces in increasing order
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    face = np.repeat(np.arange(face_sizes.size, dtype=np.int64), face_sizes)
    vertex = np.asarray(face_vertices, dtype=np.int64)
    span = int(vertex.max(initial=0)) + 1
    unique, count = np.unique(face * span + vertex, return_counts=True)
    return unique_integers(unique[count > 1] // span)


def corner_fans(mesh: HalfEdgeMesh, edge_of: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Split vertex of every corner: corners glued across every edge in two or more faces.

    Corner ``h`` is the corner of face ``mesh.face[h]`` at ``mesh.origin[h]``. Two
    faces on one edge share their corners at its two ends, whichever way they
    run along it, so the classes are the fans of faces around each vertex
    regardless of orientation (for an oriented manifold mesh: the rotation cycles
    of ``halfedges.rotation_cycles``).

    Parameters
    ----------
    mesh : HalfEdgeMesh (H half-edges)
    edge_of : (H,) int, undirected edge of every half-edge (``undirected_edges``)
    counts : (E,) int, half-edges per edge

    Returns
    -------
    (H,) int64, labels 0 .. V' - 1 (V' vertices after pinch splitting)
    """
    h = np.arange(mesh.n_halfedges)
    order = np.argsort(edge_of, kind="stable")
    first = order[np.concatenate([[0], np.cumsum(counts)[:-1]])] if counts.size else order
    head = first[edge_of]  # first half-edge of every half-edge's edge
    nxt = np.asarray(mesh.next, dtype=np.int64)
    same = mesh.origin[h] == mesh.origin[head]
    rows = np.concatenate([h, nxt])
    cols = np.concatenate([np.where(same, head, nxt[head]), np.where(same, nxt[head], head)])
    graph = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(h.size, h.size))
    return connected_components(graph, directed=False)[1].astype(np.int64)


def components_of(n_nodes: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n_nodes,) int64 component label of every node of the undirected graph with edges ``a[i]``-``b[i]`` ((m,) int)."""
    graph = coo_matrix((np.ones(a.size), (a, b)), shape=(n_nodes, n_nodes))
    return connected_components(graph, directed=False)[1].astype(np.int64)


def mesh_statistics(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> MeshStatistics:
    """Count what a polygon mesh is (see ``MeshStatistics``).

    Parameters
    ----------
    face_sizes : (F,) int, every face with at least one corner
    face_vertices : (sum(face_sizes),) int, faces concatenated, 0 .. n_vertices - 1
    n_vertices : int, V (unused vertices included)

    Returns
    -------
    MeshStatistics
    """
    mesh = build_halfedges(face_sizes, face_vertices, n_vertices)
    edges, edge_of, counts = undirected_edges(mesh)
    valence = np.bincount(mesh.origin, minlength=n_vertices)
    boundary_half = counts[edge_of] == 1
    on_boundary = np.zeros(n_vertices, dtype=bool)
    on_boundary[edges[counts == 1].ravel()] = True
    interior = (valence > 0) & ~on_boundary
    fan = corner_fans(mesh, edge_of, counts)
    n_split = int(fan.max(initial=-1)) + 1
    split_source = np.zeros(n_split, dtype=np.int64)
    split_source[fan] = mesh.origin
    loops = components_of(n_split, fan[boundary_half], fan[mesh.next[boundary_half]])
    boundary_split = unique_integers(fan[boundary_half])
    components = component_statistics(mesh, fan, edge_of, counts, loops, boundary_split)
    return MeshStatistics(
        n_vertices=int(n_vertices), n_faces=mesh.n_faces, n_edges=int(counts.size),
        face_sizes=histogram(mesh.face_sizes), interior_valences=histogram(valence[interior]),
        boundary_valences=histogram(valence[on_boundary]), unused_vertices=int(np.sum(valence == 0)),
        boundary_edges=int(np.sum(counts == 1)), boundary_loops=int(unique_integers(loops[boundary_split]).size),
        non_manifold_edges=int(np.sum(counts > 2)),
        pinched_vertices=int(np.sum(np.bincount(split_source, minlength=n_vertices) > 1)),
        valence2_interior_vertices=int(np.sum(interior & (valence == 2))), components=components,
    )


def component_statistics(mesh: HalfEdgeMesh, fan: np.ndarray, edge_of: np.ndarray, counts: np.ndarray,
                         loops: np.ndarray, boundary_split: np.ndarray) -> ComponentStatistics:
    """Per-component counts of a mesh whose corners ``fan`` ((H,) int) names the split vertices.

    Parameters
    ----------
    mesh : HalfEdgeMesh of the input (H half-edges, F faces)
    fan : (H,) int, split vertex of every corner (``corner_fans``), 0 .. V' - 1
    edge_of : (H,) int; counts : (E,) int (``undirected_edges``)
    loops : (V',) int, boundary loop label of every split vertex (meaningful on boundary vertices)
    boundary_split : (b,) int, the split vertices on a boundary edge

    Returns
    -------
    ComponentStatistics, components numbered by their lowest split vertex
    """
    n_split = int(fan.max(initial=-1)) + 1
    label = components_of(n_split, fan, fan[mesh.next])
    k = int(label.max(initial=-1)) + 1
    face_label = label[fan[mesh.face_offsets[:-1]]]
    edge_label = np.zeros(counts.size, dtype=np.int64)
    edge_label[edge_of] = label[fan]
    loop_ids, loop_first = np.unique(loops[boundary_split], return_index=True)
    _, bad_faces = orientation_flips(mesh)
    vertices = np.bincount(label, minlength=k)
    edges = np.bincount(edge_label, minlength=k)
    faces = np.bincount(face_label, minlength=k)
    return ComponentStatistics(
        vertices=vertices, edges=edges, faces=faces,
        boundary_edges=np.bincount(edge_label[counts == 1], minlength=k),
        boundary_loops=np.bincount(label[boundary_split[loop_first]], minlength=k),
        non_manifold_edges=np.bincount(edge_label[counts > 2], minlength=k),
        euler_characteristic=vertices - edges + faces,
        orientable=np.bincount(face_label[bad_faces], minlength=k) == 0,
    )
