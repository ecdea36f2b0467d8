"""A mesh's topology as a few counts, and what differs between two meshes: ``c1surf fit``'s ``topology`` report.

Components are **edge-connected**: two faces are in one component when a chain of faces, each sharing an edge
with the next, joins them; faces that only touch at a vertex are not joined (the vertex is split into one per fan
of faces first, as ``repair.split_pinched_vertices`` does before the construction). The Euler characteristic is
V - E + F of the used vertices after that split, per component and summed over the mesh; rims are the boundary
loops (closed chains of edges in one face). A closed surface of genus g has Euler characteristic 2 - 2g and no
rim; a disc 1 and one rim; an annulus 0 and two. The counts come from ``statistics.mesh_statistics`` (one
half-edge build, sorts and scipy.sparse.csgraph's connected components; no loop over faces).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .statistics import mesh_statistics

__all__ = ["TopologyCounts", "topology_counts", "compare_topology", "counts_as_read"]


@dataclass(frozen=True)
class TopologyCounts:
    """The topology of a polygon mesh (module docstring).

    components : int, edge-connected components
    euler_characteristic : int, V - E + F (the sum of the components')
    rims : int, boundary loops
    component_euler, component_rims, component_faces : tuple of int, one per component, in the order of
        ``statistics.component_statistics`` (by lowest split vertex)
    """

    components: int
    euler_characteristic: int
    rims: int
    component_euler: tuple
    component_rims: tuple
    component_faces: tuple

    def as_dict(self) -> dict:
        """The counts as JSON values (the fit report's ``topology``)."""
        return {"components": self.components, "euler_characteristic": self.euler_characteristic,
                "rims": self.rims, "component_euler": list(self.component_euler),
                "component_rims": list(self.component_rims), "component_faces": list(self.component_faces)}

    def kinds(self) -> list:
        """Sorted (Euler characteristic, rims) of the components: what two meshes of the same topology share."""
        return sorted(zip(self.component_euler, self.component_rims))


def topology_counts(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> TopologyCounts:
    """The ``TopologyCounts`` of a polygon mesh.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int, 0 .. n_vertices - 1 (unused vertices are not counted)
    n_vertices : int
    """
    sizes = np.asarray(face_sizes, dtype=np.int64)
    if sizes.size == 0:
        return TopologyCounts(0, 0, 0, (), (), ())
    parts = mesh_statistics(sizes, np.asarray(face_vertices, dtype=np.int64), int(n_vertices)).components
    euler = tuple(int(x) for x in parts.euler_characteristic)
    rims = tuple(int(x) for x in parts.boundary_loops)
    return TopologyCounts(len(euler), int(sum(euler)), int(sum(rims)), euler, rims,
                          tuple(int(x) for x in parts.faces))


def counts_as_read(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int) -> dict:
    """A mesh's counts as its faces are, nothing split: ``components`` (vertex-connected: faces meeting at a pinched
    vertex are one), ``euler_characteristic`` (V - E + F of the used vertices and the distinct edges), ``rims``
    (components of the edges in one face), ``pinched_vertices`` (in more than one fan of faces) and
    ``non_manifold_edges`` (in three or more faces). A manifold mesh has ``topology_counts``' counts here too."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from .halfedges import build_halfedges
    from .repair import split_pinched_vertices

    sizes = np.asarray(face_sizes, dtype=np.int64)
    corners = np.asarray(face_vertices, dtype=np.int64)
    n = int(n_vertices)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    face = np.repeat(np.arange(sizes.size), sizes)
    following = corners[offsets[face] + (np.arange(corners.size) - offsets[face] + 1) % np.maximum(sizes[face], 1)]
    key = np.minimum(corners, following) * n + np.maximum(corners, following)
    edges, counts = np.unique(key, return_counts=True)
    used = np.unique(corners)

    def parts(pairs: np.ndarray, nodes: np.ndarray) -> int:
        graph = coo_matrix((np.ones(pairs.size), (pairs // n, pairs % n)), shape=(n, n))
        return int(np.unique(connected_components(graph, directed=False)[1][nodes]).size) if nodes.size else 0

    rim = edges[counts == 1]
    crowded = int(np.count_nonzero(counts > 2))
    pinched = 0
    if not crowded and sizes.size:
        pinched = split_pinched_vertices(build_halfedges(sizes, corners, n))[2]
    return {"components": parts(edges, used), "euler_characteristic": int(used.size - edges.size + sizes.size),
            "rims": parts(rim, np.unique(np.r_[rim // n, rim % n])), "pinched_vertices": int(pinched),
            "non_manifold_edges": crowded}


def compare_topology(scan: TopologyCounts, surface: TopologyCounts) -> list[str]:
    """What differs between the ``scan``'s counts and the ``surface``'s, one phrase each; [] when nothing does.

    Components, Euler characteristic and rims are compared in total, then (when the totals agree) the
    components' own (Euler characteristic, rims) as multisets: a sphere and a double torus (2 and -2) against
    two tori (0 and 0) differ only there.
    """
    differences = [f"{what}: scan {getattr(scan, name)}, surface {getattr(surface, name)}"
                   for what, name in (("components", "components"), ("Euler characteristic", "euler_characteristic"),
                                      ("rims (boundary loops)", "rims"))
                   if getattr(scan, name) != getattr(surface, name)]
    if not differences and scan.kinds() != surface.kinds():
        differences.append(f"components' (Euler characteristic, rims): scan {_kinds_text(scan)}, surface "
                           f"{_kinds_text(surface)}")
    return differences


def _kinds_text(counts: TopologyCounts, shown: int = 6) -> str:
    kinds = counts.kinds()
    text = ", ".join(f"({e}, {r})" for e, r in kinds[:shown])
    return text + (f", ... ({len(kinds)} in all)" if len(kinds) > shown else "")
