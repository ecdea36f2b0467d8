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

__all__ = ["TopologyCounts", "topology_counts", "compare_topology"]


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
