"""Everything about a Surface that depends on the connectivity alone: integers, computed once.

``build_topology`` runs the steps in order: repair the input (orientation,
pinched vertices, the double cover of a non-orientable mesh), close its
boundaries with a ghost layer, choose the number of refinements, refine, and
find the holes and the patch frames. Geometry never enters: the one rule
that reads points (convex or reflex ghost corners) is a stage
(``stages.PlacementStage``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..arrays import unique_integers
from ..mesh.errors import TopologyError
from ..mesh.ghost_layer import GhostLayer, add_ghost_layer
from ..mesh.halfedges import HalfEdgeMesh
from ..mesh.repair import check_valence, prepare_topology
from ..mesh.creases.sheets import CreaseSheets, cut_crease_sheets
from .features import INFINITELY_SHARP, CoarseSharpness, SharpFeatures, coarse_sharpness
from .refine.doo_sabin import FACE_FROM_EDGE, FACE_FROM_VERTEX, RefinedFaces, refine_doo_sabin, refined_halfedges
from .refine.fewer_steps import check_refinements, fewer_refinement_sources, refinement_choice
from ..memory import return_freed_memory
from .refine.holes import HoleGroup, hole_neighbourhoods, patch_frames, split_dart_holes


# From this many refined half-edges on (the 1,000,000-quad torus has 64M: its twin is 256 MB), the refined mesh's
# twin is let go once the patch frames are made, and made again if read (``HalfEdgeMesh.release_twin``): the
# stages never read it, nor a streamed tessellation at resolution 2, and the patch adjacency of its sides
# (-r 3 and more, patch files, the in-memory path) reads it once the stages are gone. Smaller meshes keep it.
# The build of such a mesh also gives freed memory back between its largest steps (``return_freed_memory``).
RELEASED_TWIN_HALFEDGES = 1 << 25


@dataclass(frozen=True)
class SurfaceTopology:
    """The refined connectivity of a Surface and which patches it has.

    Attributes
    ----------
    n_input_vertices, n_input_faces : int
    repairs : dict, ``repair.prepare_topology``'s report (without ``second_sheet``)
    vertex_source : (V',) int, input vertex of every vertex of the repaired mesh
    second_sheet : (F',) bool, faces of the double cover's second sheet (non-orientable input)
    ghost : GhostLayer or None (closed input)
    input : HalfEdgeMesh, the coarse mesh: repaired, and closed by the ghost layer
    real_face : (Fc,) bool, faces of ``input`` whose patches are kept
    refinements : int, 0, 1 or 2
    faces1 : RefinedFaces or None, the faces of the first refinement
    level1 : HalfEdgeMesh or None, the once-refined mesh
    refined : HalfEdgeMesh, the mesh A2 and A3 read (twice refined, or fewer)
    real_vertex : (Vr,) bool, refined vertices inside real faces
    holes : list of HoleGroup, the holes with a real corner
    frames : (Nq + Nc, 4) int, half-edges e0..e3 of every patch, biquadratic first: one array, handed out
        without a copy (46 MB for the 180,000-quad torus); ``quad_frames`` and ``cubic_frames`` are its parts
    n_quad : int, Nq
    cubic_keep : (sum over holes of n,) bool or None, which bicubic patches are kept (None: all)
    cubic_hole : (Nc,) int, hole (in ``holes`` order) of every kept bicubic patch
    sharpness : CoarseSharpness or None, creases and corners on ``input`` (``features``) that the
        refinement steps pull towards (the G1 creases: semi-sharp ones, and infinitely sharp ones
        not cut into sheets)
    hole_faces : (k,) int, input faces tagged as holes (no patches)
    crease_sheets : CreaseSheets or None, the C0 creases: the mesh cut along them, ghost quads
        across them (``mesh.creases.sheets``; ``exact_creases``)
    two_steps_why : str or None, with ``refinements="auto"`` and two steps taken: why one is not enough
        (``refine.fewer_steps.refinement_choice``), for a note
    """

    n_input_vertices: int
    n_input_faces: int
    repairs: dict
    vertex_source: np.ndarray
    second_sheet: np.ndarray
    ghost: GhostLayer | None
    input: HalfEdgeMesh
    real_face: np.ndarray
    refinements: int
    faces1: RefinedFaces | None
    level1: HalfEdgeMesh | None
    refined: HalfEdgeMesh
    real_vertex: np.ndarray
    holes: list[HoleGroup]
    frames: np.ndarray
    n_quad: int
    cubic_keep: np.ndarray | None
    cubic_hole: np.ndarray
    sharpness: CoarseSharpness | None = None
    hole_faces: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    crease_sheets: CreaseSheets | None = None
    two_steps_why: str | None = None

    def coarse_corner(self, refined_vertices=None) -> np.ndarray:
        """(k,) int: the corner of ``input`` (a coarse half-edge) each refined vertex was made at (all: None).

        One step: a refined vertex *is* a coarse corner; two: a corner of a corner (``level1.origin``)."""
        v = np.arange(self.refined.n_vertices) if refined_vertices is None else np.asarray(refined_vertices)
        if self.refinements == 0:
            raise ValueError("internal: no refinement, no corners")
        return v if self.refinements == 1 else self.level1.origin[v]

    @property
    def quad_frames(self) -> np.ndarray:
        """(Nq, 4) int: frames of the biquadratic patches (a view of ``frames``)."""
        return self.frames[: self.n_quad]

    @property
    def cubic_frames(self) -> np.ndarray:
        """(Nc, 4) int: frames of the kept bicubic patches (a view of ``frames``)."""
        return self.frames[self.n_quad :]

    def select_matrix(self):
        """(V', V) csr_matrix: the input point of every vertex of the repaired mesh."""
        from scipy.sparse import csr_matrix  # scipy.sparse is imported where a matrix is made: the usual conversion needs none (0.2 s)

        source = self.vertex_source
        return csr_matrix((np.ones(source.size), (np.arange(source.size), source)), shape=(source.size, self.n_input_vertices))

    def per_coarse_vertex(self, values: np.ndarray | None) -> np.ndarray | None:
        """(V, ...) values per input vertex -> (Vc, ...) per vertex of ``input`` (ghost vertices: NaN)."""
        if values is None:
            return None
        pad = np.full((self.input.n_vertices - self.vertex_source.size,) + values.shape[1:], np.nan)
        return np.concatenate([values[self.vertex_source], pad])

    def per_coarse_face(self, values: np.ndarray, fill: float) -> np.ndarray:
        """(F,) values per input face -> (Fc,) per face of ``input``: both sheets alike, ``fill`` on ghost faces."""
        if self.second_sheet.any():
            values = np.r_[values, values]
        return np.r_[values, np.full(self.input.n_faces - values.size, fill)]

    def patch_sources(self):
        """Which input element each patch comes from, in the input's numbering.

        Returns
        -------
        kind : (P,) int8, FACE_FROM_FACE / FACE_FROM_EDGE / FACE_FROM_VERTEX
        index : (P,) int, input face or input vertex (-1 for edges)
        edge : (P, 2) int, the input edge's two vertices (-1 unless an edge)
        """
        centre = self.refined.origin[self.frames[:, 0]]
        if self.refinements < 2:
            return fewer_refinement_sources(self, centre)
        face1 = self.level1.face[centre]
        kind, parent = self.faces1.kind[face1], self.faces1.parent[face1]
        is_vertex, is_edge = kind == FACE_FROM_VERTEX, kind == FACE_FROM_EDGE
        index = parent.copy()
        index[is_vertex] = self.vertex_source[parent[is_vertex]]
        index[is_edge] = -1
        edge = np.full((kind.size, 2), -1, dtype=np.int64)
        h = parent[is_edge]
        edge[is_edge] = self.vertex_source[np.stack([self.input.origin[h], self.input.dest[h]], axis=1)]
        return kind, index, edge


def build_topology(face_sizes, face_vertices, n_vertices: int, refinements="auto", interpolate_vertices: bool = False,
                   features: SharpFeatures | None = None, exact_creases: bool = False) -> SurfaceTopology:
    """Repair, close, refine and lay out the patches of a polygon mesh.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    n_vertices : int, input vertices
    refinements : 0, 1, 2 or "auto" (``SurfaceOptions.refinements``)
    interpolate_vertices : bool, A1a (needs at least one refinement)
    features : SharpFeatures or None: hole faces lose their patches; creases and corners
        are mapped onto the coarse mesh for the refinement stages
    exact_creases : bool, cut the mesh along its infinitely sharp creases where that is exact
        (``mesh.creases.sheets``): C0 creases instead of the sharpest G1 ones
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    prepared, vertex_source, repairs = prepare_topology(face_sizes, np.asarray(face_vertices, dtype=np.int64), n_vertices)
    # A non-orientable input comes back as its orientation double cover:
    # both sheets are refined, the patches of the second are dropped.
    second_sheet = repairs.pop("second_sheet")
    sheets = crease_sheets(prepared, vertex_source, features) if exact_creases and features is not None else None
    if sheets is not None:  # the sheets and their ghost quads, which are open along the ghost strips
        prepared, vertex_source = sheets.mesh, vertex_source[sheets.vertex_source]
        second_sheet = np.r_[second_sheet, np.zeros(sheets.ghost_faces.size, bool)]
    check_valence(prepared, vertex_source)  # after the cut: a seam vertex in two faces has four in its sheets
    ghost = add_ghost_layer(prepared) if repairs["boundary_edges"] or sheets is not None else None
    coarse = prepared if ghost is None else ghost.mesh
    real_face = np.ones(coarse.n_faces, bool) if ghost is None else ghost.real_face.copy()
    real_face[: second_sheet.size] &= ~second_sheet
    hole_faces = np.zeros(0, dtype=np.int64) if features is None else unique_integers(features.hole_faces)
    real_face[hole_faces] = False  # a hole keeps its corners in the refinement, but no patches
    if sheets is not None:
        real_face[sheets.ghost_faces] = False
    if not real_face.any():
        raise TopologyError("every face is tagged as a hole: there is no surface to build", hole_faces[:8])
    closed = real_face.all() and not repairs["boundary_edges"]
    levels, why_two, once = refinement_count(coarse, refinements, None if closed else real_face, interpolate_vertices)
    faces1, level1, refined = refine(coarse, levels, once)
    del once
    real_vertex = real_refined_vertices(coarse, level1, refined, real_face, levels)
    holes = hole_neighbourhoods(refined, None if real_face.all() else real_vertex)
    if sheets is not None and sheets.dart_vertex is not None and sheets.dart_vertex.size and levels >= 1:
        holes = split_dart_holes(holes, *dart_cells(coarse, faces1, level1, refined, sheets))
    frames, n_quad, real_cubic = patch_frames(refined, holes, real_vertex)  # bicubic patches at real corners only
    if refined.n_halfedges >= RELEASED_TWIN_HALFEDGES:
        refined.release_twin()  # made again if read: the stages and a tessellation at -r 2 never do
        return_freed_memory()  # the twin and the refinement's temporaries: not resident beside the stages'
    sizes = np.concatenate([np.full(g.cells.size, g.n) for g in holes]) if holes else np.zeros(0, dtype=np.int64)
    return SurfaceTopology(
        n_input_vertices=int(n_vertices), n_input_faces=int(face_sizes.size), repairs=repairs,
        vertex_source=vertex_source, second_sheet=second_sheet, ghost=ghost, input=coarse, real_face=real_face,
        refinements=levels, faces1=faces1, level1=level1, refined=refined, real_vertex=real_vertex, holes=holes,
        frames=frames, n_quad=n_quad, cubic_keep=None if real_cubic.all() else real_cubic,
        cubic_hole=np.repeat(np.arange(sizes.size), sizes)[real_cubic],
        sharpness=pulled_sharpness(coarse, vertex_source, features, sheets), hole_faces=hole_faces, crease_sheets=sheets,
        two_steps_why=why_two,
    )


def fewest_refinements(face_sizes, face_vertices, n_vertices: int, features: SharpFeatures | None = None,
                       exact_creases: bool = False) -> int:
    """The Doo-Sabin steps ``refinements="auto"`` takes on this mesh (0, 1 or 2; open meshes, C0 creases and
    darts included: ``refine.fewer_steps``), from its topology alone; 2 for a mesh the construction refuses as it
    stands (e.g. an interior vertex of valence 2, which a later cleanup may still dissolve)."""
    try:
        return build_topology(face_sizes, face_vertices, n_vertices, "auto", False, features, exact_creases).refinements
    except TopologyError:
        return 2


def dart_cells(coarse: HalfEdgeMesh, faces1: RefinedFaces, level1: HalfEdgeMesh, refined: HalfEdgeMesh,
               sheets: CreaseSheets):
    """(refined faces of the darts' holes (k,) int, refined points in the sheets' ghost quads (Vr,) bool).

    A dart's hole is its vertex's V-cell of the first step: after one step that cell itself, after two its
    F-cell (the same index: F-cells come first)."""
    vertex_cell = np.flatnonzero((faces1.kind == FACE_FROM_VERTEX) & np.isin(faces1.parent, sheets.dart_vertex))
    corner = np.arange(refined.n_vertices)
    corner = corner if refined is level1 else level1.origin[corner]
    ghost = np.isin(coarse.face[corner], sheets.ghost_faces)
    return vertex_cell, ghost


def crease_sheets(prepared: HalfEdgeMesh, vertex_source: np.ndarray, features: SharpFeatures) -> CreaseSheets | None:
    """``mesh.creases.sheets.cut_crease_sheets`` of the infinitely sharp edges and corners, or None."""
    sharp = coarse_sharpness(prepared, vertex_source, features)
    if sharp is None or not np.any(sharp.halfedge >= INFINITELY_SHARP):
        return None
    tagged = np.zeros(int(max(vertex_source.max(initial=-1), features.corner_vertices.max(initial=-1))) + 1, dtype=bool)
    tagged[features.corner_vertices[features.corner_sharpness >= INFINITELY_SHARP]] = True
    names = vertex_source if features.vertex_identity is None else features.vertex_identity[vertex_source]
    sheets = cut_crease_sheets(prepared, sharp.halfedge >= INFINITELY_SHARP, tagged[vertex_source], names=names)
    if features.vertex_identity is not None:
        check_sheets_meet(features, sheets)
    return sheets


def check_sheets_meet(features: SharpFeatures, sheets: CreaseSheets | None) -> None:
    """Refuse non-manifold edges cut into sheets (``mesh.creases.non_manifold``) that one of the sheets cannot
    cut exactly: the sheets would not meet there (a sheet that holds the end of the edge's polyline inside
    it has a crease end, a dart, there)."""
    identity = features.vertex_identity
    pairs = np.sort(identity[features.crease_edges], axis=1)
    unique, counts = np.unique(pairs, axis=0, return_counts=True)
    shared = unique[counts > 1]  # an edge whose copies lie in several sheets
    kept = np.zeros((0, 2), dtype=np.int64) if sheets is None else sheets.kept_edges
    if sheets is None or len(kept):
        width = int(identity.max(initial=0)) + 1
        bad = shared[np.isin(shared[:, 0] * width + shared[:, 1], kept[:, 0] * width + kept[:, 1])] if sheets else shared
        if len(bad):
            raise TopologyError(
                f"edge between vertices {{0}} and {{1}} is in more than two faces and its sheets cannot be made to meet "
                f"exactly ({len(bad)} such edges): a sheet holds an end of its line of such edges inside it (there its "
                "crease would end at a dart, whose curve the other sheets' boundary cannot follow), or a vertex of the "
                "line has too many faces on one side of a sheet; split the mesh there, or convert with --non-manifold "
                "refuse to see the plain error", vertices=list(bad[0]))


def pulled_sharpness(coarse: HalfEdgeMesh, vertex_source: np.ndarray, features: SharpFeatures | None,
                     sheets: CreaseSheets | None) -> CoarseSharpness | None:
    """The creases and corners the refinement pulls towards: all of ``features``'s but those cut into sheets."""
    sharp = None if features is None else coarse_sharpness(coarse, vertex_source, features)
    if sharp is None or sheets is None:
        return sharp
    cut = np.full(coarse.n_vertices, False)
    cut[: sheets.crease_vertex.size] = sheets.crease_vertex >= 0
    halfedge, vertex = sharp.halfedge.copy(), np.where(cut, 0.0, sharp.vertex)
    halfedge[sheets.cut_halfedges] = 0.0  # the seams (the semi-sharp edges at their vertices keep their pull)
    halfedge[np.isin(coarse.face, sheets.ghost_faces)] = 0.0
    return CoarseSharpness(halfedge, vertex) if (halfedge > 0).any() or (vertex > 0).any() else None


def refinement_count(coarse: HalfEdgeMesh, requested, real_face: np.ndarray | None, interpolate_vertices: bool):
    """(steps, why, once): the number of Doo-Sabin steps, ``requested`` or with "auto" the fewest after which A2/A3
    apply to the kept patches; why: with "auto" and two steps, why one is not enough (else None); once: the first
    step's (faces, mesh) where they were made to decide (``fewer_steps.once_refined_parts``), else None.

    ``real_face`` : (Fc,) bool, the faces whose patches are kept, or None for a closed mesh that keeps all.
    No step needs a closed mesh that satisfies R1-R3 (Prop. 1.3.1); one step needs R1-R3 on the cells the kept
    patches read (``refine.fewer_steps``); otherwise a one-line TopologyError.
    """
    if requested == "auto":
        return refinement_choice(coarse, 1 if interpolate_vertices else 0, real_face)
    once = check_refinements(coarse, requested, real_face) if requested < 2 else None  # or a one-line error
    return requested, None, once


def refine(coarse: HalfEdgeMesh, levels: int, once=None):
    """(faces1, level1, refined): the first step's faces and mesh (None without refinement), and the last mesh;
    ``once``: the first step's (faces, mesh) if already made (``refinement_count``)."""
    if levels == 0:
        return None, None, coarse
    faces1, level1 = once if once is not None else (None, None)
    if faces1 is None:
        faces1 = refine_doo_sabin(coarse)
        level1 = refined_halfedges(coarse, faces1)
    coarse.release_prev()  # read by the rotations of the refinement only, unless there are creases
    if levels == 1:
        return faces1, level1, level1
    faces2 = refine_doo_sabin(level1, sources=False)  # its faces' sources: not read
    if faces2.face_vertices.size >= RELEASED_TWIN_HALFEDGES:
        return_freed_memory()  # the rings' temporaries (1.6 GB for the 4,000,000-quad torus), before its half-edges
    refined = refined_halfedges(level1, faces2)
    level1.release_prev()  # 0.25 GB for the 4,000,000-quad torus
    return faces1, level1, refined


def real_refined_vertices(coarse: HalfEdgeMesh, level1, refined: HalfEdgeMesh, real_face: np.ndarray, levels: int) -> np.ndarray:
    """(Vr,) bool: refined vertices inside real (not ghost, first-sheet) faces.

    After one step a refined vertex is a corner of a coarse face, after two a
    corner of a corner: real if that face is. No step is for closed meshes only,
    where every vertex is real.
    """
    if levels == 0 or real_face.all():
        return np.ones(refined.n_vertices, dtype=bool)
    corner = np.arange(refined.n_vertices) if levels == 1 else level1.origin[: refined.n_vertices]
    return real_face[coarse.face[corner]]
