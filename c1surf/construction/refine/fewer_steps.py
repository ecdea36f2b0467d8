"""Fewer refinements when the input allows (paper, A1 and Prop. 1.3.1).

"If the input mesh already satisfies some or all conditions R1-R3 of
Proposition 1.3.1, then only one or no refinement step is necessary." What
A2 and A3 need of the mesh they are applied to (the conditions the two
refinements guarantee), stated on the cells that the *kept* patches read:

- R1: every kept patch's centre (a refined vertex in a real face) has four
  cells, and so has every corner of a hole with a kept patch;
- every such hole is surrounded by quads: the quads beside its edges and at
  its corners (``holes.hole_neighbourhoods``);
- R2/R3: no corner of such a hole is a corner of another one, and the edge
  neighbours (B points) of its kept corners are corners of no hole, so every
  kept patch beside a hole is biquadratic. (A hole's diagonal point A may be
  the corner of another hole: the v-c pair of R3, as after two refinements.)

A closed mesh keeps every patch. An open mesh (closed by the ghost layer,
``mesh.ghost_layer``), a mesh cut along C0 creases (``mesh.creases.sheets``: ghost
quads across the cuts) and a mesh with hole faces keep the patches of the
refined vertices inside real faces only: after one step a refined vertex is a
corner (f, v) of the coarse mesh, kept when f is real, and every point its
patch reads is a corner of a face around v (docs/sharp-features.md, "One
Doo-Sabin step"). The ghosts' own outer edges and the far side of a cut are
then read by no kept patch, so they need not meet the conditions.

``refinements_needed`` finds the smallest number of refinement steps (0, 1
or 2) after which these hold; two always suffice (Prop. 1.3.1).
"""
from __future__ import annotations

import numpy as np

from ...mesh.errors import TopologyError
from ...mesh.halfedges import HalfEdgeMesh
from .doo_sabin import FACE_FROM_FACE, FACE_FROM_VERTEX, refine_doo_sabin, refined_halfedges
from .holes import hole_neighbourhoods


def structure_problem(mesh: HalfEdgeMesh, wanted: np.ndarray | None = None) -> str | None:
    """Why A2/A3 cannot be applied to ``mesh`` directly, or None when they can.

    Parameters
    ----------
    mesh : HalfEdgeMesh, the mesh A2 and A3 would read
    wanted : (V,) bool or None, the vertices whose patches are kept (None: all, and the mesh must be closed)
    """
    if wanted is None:
        if np.any(mesh.twin < 0):
            return "the mesh has a boundary (fewer refinements need a closed mesh)"
        wanted = np.ones(mesh.n_vertices, dtype=bool)
    valence = np.bincount(mesh.origin, minlength=mesh.n_vertices)
    open_vertex = np.zeros(mesh.n_vertices, dtype=bool)
    border = np.flatnonzero(mesh.twin < 0)
    open_vertex[mesh.origin[border]] = open_vertex[mesh.dest[border]] = True
    bad = wanted & (valence > 0) & ((valence != 4) | open_vertex)
    if bad.any():
        return f"{int(bad.sum())} vertices do not have four cells (R1)"
    hole_of = np.full(mesh.n_vertices, -1, dtype=np.int64)
    for n, cells, h in mesh.faces_by_size(skip=(4,)):  # the corners of every hole with a kept patch first
        corners = mesh.origin[h][wanted[mesh.origin[h]].any(axis=1)]
        if np.any((valence[corners] != 4) | open_vertex[corners]):
            return "a non-quadrilateral cell has a corner without four cells (R1)"
        shared = hole_of[corners.ravel()] >= 0
        if shared.any() or np.unique(corners).size != corners.size:
            return "a vertex is a corner of two non-quadrilateral cells (R3)"
        hole_of[corners.ravel()] = n
    try:
        holes = hole_neighbourhoods(mesh, wanted)
    except TopologyError:
        return "a non-quadrilateral cell is next to another one"
    near = 0  # kept corners with an edge neighbour (B point) that is another cell's corner
    for g in holes:
        near += int(np.sum(wanted[g.C] & ((wanted[g.B1] & (hole_of[g.B1] >= 0)) | (wanted[g.B2] & (hole_of[g.B2] >= 0)))))
    if near:
        return (f"non-quadrilateral cells are only one edge apart ({near} of their corners; R2: after one step, two "
                "vertices of valence other than 4 joined by an edge of a kept face, a rim vertex counting the two ghost "
                "faces of the ghost layer, or a non-quadrilateral face next to another)")
    return None


def once_refined(mesh: HalfEdgeMesh) -> HalfEdgeMesh:
    """The topology after one Doo-Sabin step."""
    return once_refined_parts(mesh)[1]


def once_refined_parts(mesh: HalfEdgeMesh):
    """(RefinedFaces, HalfEdgeMesh): one Doo-Sabin step's faces (with their sources) and mesh, as
    ``topology.refine`` makes them (it takes them from here rather than refining twice)."""
    faces = refine_doo_sabin(mesh)
    return faces, refined_halfedges(mesh, faces)


def kept_after_one_step(mesh: HalfEdgeMesh, real_face: np.ndarray | None) -> np.ndarray | None:
    """(H,) bool: the once-refined vertices (= corners of ``mesh``) whose patches are kept, or None (all)."""
    return None if real_face is None or real_face.all() else real_face[mesh.face]


def refinements_needed(mesh: HalfEdgeMesh, at_least: int = 0, real_face: np.ndarray | None = None) -> int:
    """Smallest k in at_least..2 such that A2/A3 apply after k refinement steps.

    ``real_face`` : (F,) bool or None, the faces whose patches are kept (None: all, a closed mesh). With some
    face not kept (ghost faces, hole faces), no step is not enough (the patches of no step sit at the vertices,
    across the faces' borders).
    """
    return refinement_choice(mesh, at_least, real_face)[0]


def refinement_choice(mesh: HalfEdgeMesh, at_least: int = 0, real_face: np.ndarray | None = None):
    """(k, why, once): ``refinements_needed``; when it is 2, why one step is not enough (else None); and the
    once-refined ``once_refined_parts`` where they were made to decide (else None), for ``topology.refine``."""
    if at_least <= 0 and kept_after_one_step(mesh, real_face) is None and structure_problem(mesh) is None:
        return 0, None, None
    if at_least <= 1:
        once = once_refined_parts(mesh)
        problem = _one_step_problem(mesh, once[1], real_face)
        return (1, None, once) if problem is None else (2, problem, once)
    return 2, None, None


def _one_step_problem(mesh: HalfEdgeMesh, level1: HalfEdgeMesh, real_face: np.ndarray | None) -> str | None:
    """``structure_problem`` of the once-refined ``level1`` of ``mesh``, its kept patches those of ``real_face``."""
    kept = kept_after_one_step(mesh, real_face)
    return structure_problem(level1, kept if kept is not None else
                             (None if real_face is None else np.ones(mesh.n_halfedges, dtype=bool)))


def check_refinements(mesh: HalfEdgeMesh, k: int, real_face: np.ndarray | None = None):
    """Raise TopologyError when A2/A3 do not apply after ``k`` (0 or 1) refinement steps; else return the
    once-refined ``once_refined_parts`` (k = 1) or None, for ``topology.refine``."""
    once = None
    if k == 0:
        problem = "some faces' patches are not kept (an open mesh, C0 creases or hole faces: no step puts the patches " \
                  "across the faces' borders)" if real_face is not None and not real_face.all() else structure_problem(mesh)
    else:
        once = once_refined_parts(mesh)
        problem = _one_step_problem(mesh, once[1], real_face)
    if problem is not None:
        raise TopologyError(f"{'one refinement step is' if k == 1 else 'no refinement is'} not enough: {problem}; "
                            "use --refinements 2 (the paper's two steps) or auto")
    return once


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
