"""Fewer refinements when the input allows (paper, A1 and Prop. 1.3.1).

"If the input mesh already satisfies some or all conditions R1-R3 of
Proposition 1.3.1, then only one or no refinement step is necessary." What
A2 and A3 need of the mesh they are applied to (the conditions the two
refinements guarantee):

- R1: every vertex has four cells (closed meshes: no boundary);
- every non-quadrilateral cell (a *hole*) is surrounded by quads: the quads
  beside its edges and at its corners (``holes.hole_neighbourhoods``);
- R2/R3: no vertex is a corner of two holes, and the edge neighbours
  (B points) of a hole's corners are corners of no hole, so every patch
  beside a hole is biquadratic. (A hole's diagonal point A may be the
  corner of another hole: the v-c pair of R3, as after two refinements.)

``refinements_needed`` finds the smallest number of refinement steps (0, 1
or 2) after which these hold; two always suffice (Prop. 1.3.1).
"""
from __future__ import annotations

import numpy as np

from ...mesh.errors import TopologyError
from ...mesh.halfedges import HalfEdgeMesh
from .doo_sabin import FACE_FROM_FACE, FACE_FROM_VERTEX, refine_doo_sabin, refined_halfedges
from .holes import hole_neighbourhoods


def structure_problem(mesh: HalfEdgeMesh) -> str | None:
    """Why A2/A3 cannot be applied to ``mesh`` directly, or None when they can."""
    if np.any(mesh.twin < 0):
        return "the mesh has a boundary (fewer refinements need a closed mesh)"
    valence = np.bincount(mesh.origin, minlength=mesh.n_vertices)
    odd = np.flatnonzero((valence > 0) & (valence != 4))
    if odd.size:
        return f"{odd.size} vertices do not have four cells (R1)"
    try:
        holes = hole_neighbourhoods(mesh)
    except TopologyError:
        return "a non-quadrilateral cell is next to another one"
    hole_of = np.full(mesh.n_vertices, -1, dtype=np.int64)
    count = 0
    for g in holes:
        for k in range(g.cells.size):
            if np.any(hole_of[g.C[k]] >= 0):
                return "a vertex is a corner of two non-quadrilateral cells (R3)"
            hole_of[g.C[k]] = count
            count += 1
    for g in holes:
        if np.any(hole_of[g.B1] >= 0) or np.any(hole_of[g.B2] >= 0):
            return "two non-quadrilateral cells are only one edge apart (R2)"
    return None


def once_refined(mesh: HalfEdgeMesh) -> HalfEdgeMesh:
    """The topology after one Doo-Sabin step."""
    faces = refine_doo_sabin(mesh)
    return refined_halfedges(mesh, faces)


def refinements_needed(mesh: HalfEdgeMesh, at_least: int = 0) -> int:
    """Smallest k in at_least..2 such that A2/A3 apply after k refinement steps."""
    if at_least <= 0 and structure_problem(mesh) is None:
        return 0
    if at_least <= 1 and structure_problem(once_refined(mesh)) is None:
        return 1
    return 2


def check_refinements(mesh: HalfEdgeMesh, k: int) -> None:
    """Raise TopologyError when A2/A3 do not apply after ``k`` (0 or 1) refinement steps."""
    problem = structure_problem(mesh if k == 0 else once_refined(mesh))
    if problem is not None:
        raise TopologyError(f"{'one refinement step is' if k == 1 else 'no refinement is'} not enough: {problem}; "
                            "use --refinements 2 (the paper's two steps) or auto")


def fewer_refinement_sources(topology, centre: np.ndarray):
    """``SurfaceTopology.patch_sources`` after 0 or 1 refinement steps.

    One step: a refined vertex is an input corner (f, v): its biquadratic
    patch comes from face f, the bicubic patches of a hole from the input
    element the hole was made from (face f, or vertex v for a V-cell). No
    step: biquadratic patches come from input vertices, bicubic ones from
    input faces.

    Parameters
    ----------
    topology : SurfaceTopology
    centre : (P,) int, the refined vertex of every patch
    """
    n_quad = topology.quad_frames.shape[0]
    cells = np.concatenate([g.cells for g in topology.holes]) if topology.holes else np.zeros(0, np.int64)
    hole_cell = cells[topology.cubic_hole]
    kind = np.full(centre.size, FACE_FROM_FACE, dtype=np.int8)
    if topology.refinements == 0:
        kind[:n_quad] = FACE_FROM_VERTEX
        index = np.r_[topology.vertex_source[centre[:n_quad]], hole_cell]
    else:
        coarse = topology.input
        index = coarse.face[centre].astype(np.int64)
        from_vertex = topology.faces1.kind[hole_cell] == FACE_FROM_VERTEX
        kind[n_quad:][from_vertex] = FACE_FROM_VERTEX
        index[n_quad:][from_vertex] = topology.vertex_source[topology.faces1.parent[hole_cell[from_vertex]]]
        index[n_quad:][~from_vertex] = topology.faces1.parent[hole_cell[~from_vertex]]
    return kind, index, np.full((centre.size, 2), -1, dtype=np.int64)
