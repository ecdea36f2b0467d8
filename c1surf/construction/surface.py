"""The object users hold: refined topology, sparse operators, and the patches.

Topology is refined once; geometry enters only as sparse products
(Theorem 1.3.3: the construction is linear in the input points), so
``update_points`` on the same connectivity costs a few sparse products.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .refine.doo_sabin import FACE_FROM_EDGE, FACE_FROM_FACE, FACE_FROM_VERTEX, DooSabinStep, doo_sabin_matrix, refine_doo_sabin, refined_halfedges
from ..mesh.errors import TopologyError
from scipy.sparse import csr_matrix

from .stencils.blend import check_ratios, corner_ratios, second_step_corner_ratios
from ..mesh.ghost_layer import add_ghost_layer
from .extensions.interpolation import normal_constraint, vertex_interpolation_step
from .refine.fewer_steps import check_refinements, fewer_refinement_sources, refinements_needed
from .stencils.patches import (biquadratic_layout, biquadratic_patches, biquadratic_stencil, bicubic_layout, bicubic_patches,
                      bicubic_stencil,
                      hole_neighbourhoods, patch_frames, perturbation_matrix)
from ..mesh.repair import check_valence, prepare_topology
from ..mesh.halfedges import HalfEdgeMesh

SOURCE_NAMES = {FACE_FROM_FACE: "face", FACE_FROM_EDGE: "edge", FACE_FROM_VERTEX: "vertex"}
TANGENT_RULES = ("symmetric", "corners")
TRIANGLE_RULES = ("g1", "parametric")


@dataclass(frozen=True)
class SurfaceOptions:
    """Shape controls of the construction.

    blend : float, default blend ratio alpha_f of every cell (A1), in [0, 1]
    alpha : float, shape parameter of the bicubic tangents P_32 (A3), default 1
    beta : float, S = S_C + beta (S_P - S_C) (section 1.3.3), default 0
    tangent_rule : "symmetric" (A3) or "corners" (A3a)
    interpolate_vertices : bool, A1a: the surface passes through every input vertex (needs beta = 0)
    triangles : "g1" (A3 for every hole) or "parametric" (section 1.3.4 for 3-sided holes:
        parametrically C1 to the biquadratic patches around)
    refinements : 2 (the paper's A1), 0 or 1 (closed meshes that already satisfy R1-R3 after
        that many steps, Prop. 1.3.1), or "auto" (the fewest that work; ``core.refinement``)
    """

    blend: float = 0.5
    alpha: float = 1.0
    beta: float = 0.0
    tangent_rule: str = "symmetric"
    interpolate_vertices: bool = False
    triangles: str = "g1"
    refinements: int | str = 2


class Surface:
    """A G1 surface of biquadratic and bicubic Bezier patches over a polygon mesh.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int, faces concatenated, counter-clockwise from outside
    points : (V, d) float, d >= 1 (3 for positions; more columns are carried along linearly)
    options : SurfaceOptions
    face_blend : (F,) float or None, per-face blend ratio overriding ``options.blend``
    vertex_blend : (V,) float or None, per-vertex blend ratio (NaN or negative: unset),
        used for the corners at that vertex (``core.blend``)
    weights : (V,) float > 0 or None, homogeneous weight of every input point (A2a):
        the patches become rational, with weights
    vertex_normals : (V, 3) float or None, NaN rows where unset: with
        ``options.interpolate_vertices`` the surface normal at each such vertex is this one

    Attributes (after construction)
    -------------------------------
    biquadratic : (Nq, 3, 3, d) float, Bezier coefficients of the A2 patches
    bicubic : (Nc, 4, 4, d) float, Bezier coefficients of the A3 patches
    biquadratic_weights, bicubic_weights : (Nq, 3, 3), (Nc, 4, 4) float, or None when not rational
    """

    def __init__(self, face_sizes, face_vertices, points, options: SurfaceOptions | None = None, face_blend=None,
                 vertex_blend=None, weights=None, vertex_normals=None):
        self.options = o = options or SurfaceOptions()
        if o.tangent_rule not in TANGENT_RULES:
            raise ValueError(f"tangent rule must be one of {TANGENT_RULES}")
        if o.triangles not in TRIANGLE_RULES:
            raise ValueError(f"triangles must be one of {TRIANGLE_RULES}")
        if o.refinements not in (0, 1, 2, "auto"):
            raise ValueError("refinements must be 0, 1, 2 or 'auto'")
        if o.interpolate_vertices and o.refinements == 0:
            raise ValueError("vertex interpolation (A1a) needs at least one refinement step")
        if o.interpolate_vertices and o.beta != 0:
            raise ValueError("vertex interpolation (A1a) needs beta = 0: beta moves the cell centres off the vertices")
        if vertex_normals is not None and not o.interpolate_vertices:
            raise ValueError("vertex normals are interpolated together with the vertices: set interpolate_vertices")
        if vertex_normals is not None and o.alpha == 0:
            raise ValueError("vertex normals need alpha > 0 (alpha = 0 leaves no tangent plane at cell centres)")
        points = np.asarray(points, dtype=np.float64)
        self.n_input_vertices = points.shape[0]
        face_sizes = np.asarray(face_sizes, dtype=np.int64)
        self.n_input_faces = int(face_sizes.size)
        blend = np.full(face_sizes.size, float(self.options.blend))
        if face_blend is not None:
            blend = check_ratios(face_blend, face_sizes.size, "per-face blend ratios", allow_unset=True)
            blend = np.where(np.isnan(blend), float(self.options.blend), blend)
        if vertex_blend is not None:
            vertex_blend = check_ratios(vertex_blend, self.n_input_vertices, "per-vertex blend ratios", allow_unset=True)
        if vertex_normals is not None:
            vertex_normals = np.asarray(vertex_normals, dtype=np.float64).reshape(self.n_input_vertices, 3)
        self.weights = None if weights is None else self._check_weights(weights)
        self._build_topology(face_sizes, np.asarray(face_vertices, dtype=np.int64), blend, points,
                             vertex_blend=vertex_blend, vertex_normals=vertex_normals)
        self.update_points(points)

    def _check_weights(self, weights) -> np.ndarray:
        w = np.asarray(weights, dtype=np.float64).reshape(-1)
        if w.size != self.n_input_vertices:
            raise ValueError(f"expected {self.n_input_vertices} weights, got {w.size}")
        if not np.all(np.isfinite(w) & (w > 0)):
            raise ValueError("vertex weights must be finite and positive")
        return w

    @property
    def rational(self) -> bool:
        return self.weights is not None

    @property
    def patch_weights(self):
        """[biquadratic_weights, bicubic_weights], or None for a polynomial surface."""
        return None if self.weights is None else [self.biquadratic_weights, self.bicubic_weights]

    # -- topology and operators (no coordinates) ------------------------------------

    def _build_topology(self, face_sizes, face_vertices, blend, points, vertex_blend=None, vertex_normals=None) -> None:
        # Repairs first (orientation, pinched vertices), then a ghost layer
        # closes any boundary; from there on every mesh is handled alike.
        prepared, vertex_source, self.repairs = prepare_topology(face_sizes, face_vertices, self.n_input_vertices)
        # A non-orientable input comes back as its orientation double cover:
        # both sheets are refined, the patches of the second are dropped.
        second_sheet = self.repairs.pop("second_sheet")
        if second_sheet.any():
            blend = np.r_[blend, blend]
        check_valence(prepared, vertex_source)
        self.vertex_source = vertex_source
        select = csr_matrix((np.ones(vertex_source.size), (np.arange(vertex_source.size), vertex_source)),
                            shape=(vertex_source.size, self.n_input_vertices))
        if self.repairs["boundary_edges"]:
            layer = add_ghost_layer(prepared, (select @ points)[:, :3])
            coarse, real_face, place = layer.mesh, layer.real_face, layer.points_matrix @ select
            blend = np.r_[blend, np.full(coarse.n_faces - blend.size, float(self.options.blend))]
        else:
            coarse, real_face, place = prepared, np.ones(prepared.n_faces, bool), select
        real_face[: second_sheet.size] &= ~second_sheet
        self.input = coarse

        def per_coarse_vertex(values):  # input numbering -> coarse numbering (ghost vertices: NaN)
            if values is None:
                return None
            pad = np.full((coarse.n_vertices - vertex_source.size,) + values.shape[1:], np.nan)
            return np.concatenate([values[vertex_source], pad])

        # First step: a corner takes its vertex's ratio where one is given,
        # else its cell's. Second step: a point made from once-refined vertex
        # (= input corner) h takes h's ratio; V-cells the minimum of theirs (core.blend).
        corner = corner_ratios(coarse, blend, per_coarse_vertex(vertex_blend))
        levels = self.options.refinements
        closed = real_face.all() and not self.repairs["boundary_edges"]
        if levels == "auto":
            levels = refinements_needed(coarse, 1 if self.options.interpolate_vertices else 0) if closed else 2
        elif levels < 2:
            if not closed:
                raise TopologyError(f"--refinements {levels} needs a closed, orientable mesh: use 2 or auto")
            check_refinements(coarse, levels)  # fewer steps (Prop. 1.3.1), or a one-line error
        self.refinements = levels
        operators, faces1, level1 = [place], None, None
        if levels >= 1:
            step1 = doo_sabin_matrix(coarse, corner, per_corner=True)
            faces1 = refine_doo_sabin(coarse)
            if self.options.interpolate_vertices:
                step1 = vertex_interpolation_step(step1, coarse, faces1)  # A1a
            level1 = refined_halfedges(coarse, faces1)
            operators.append(step1)
        if levels == 2:
            ratio2 = second_step_corner_ratios(level1, faces1.kind == FACE_FROM_VERTEX, corner)
            step2 = DooSabinStep(level1, ratio2)  # factored: its matrix would be the largest object here
            faces2 = refine_doo_sabin(level1)
            refined = refined_halfedges(level1, faces2)
            operators.append(step2)
            # A refined vertex is a corner of a corner of a coarse face: real if that face is.
            real_vertex = real_face[coarse.face[level1.origin[np.arange(refined.n_vertices)]]]
        else:  # closed meshes only: every vertex is real
            refined = level1 if levels == 1 else coarse
            real_vertex = np.ones(refined.n_vertices, dtype=bool)
        holes = hole_neighbourhoods(refined, None if real_face.all() else real_vertex)
        quad_frames, cubic_frames = patch_frames(refined, holes, real_vertex)

        self.level1, self.faces1, self.refined, self.holes = level1, faces1, refined, holes
        self.quad_frames = quad_frames
        self.operators = operators
        perturb = perturbation_matrix(refined, holes)
        if perturb is not None:
            self.operators.append(perturb)
        o = self.options
        # Functions applied after the (linear, row-wise) operators: vertex normals (A1a).
        self.constraints = []
        if vertex_normals is not None and faces1 is not None:
            constraint = normal_constraint(refined, faces1, per_coarse_vertex(vertex_normals), o.tangent_rule,
                                           o.triangles == "parametric", self.weights is not None)
            if constraint is not None:
                self.constraints.append(constraint)
        self.quad_layout = biquadratic_layout(refined, quad_frames)
        # keep the bicubic patches at real corners only (all of them on a closed mesh)
        real_cubic = real_vertex[refined.origin[cubic_frames[:, 0]]]
        self.cubic_frames = cubic_frames[real_cubic]
        self.cubic_layout = bicubic_layout(holes, o.alpha, o.beta, o.tangent_rule, o.triangles, keep=real_cubic)
        sizes = np.concatenate([np.full(g.cells.size, g.n) for g in holes]) if holes else np.zeros(0, dtype=np.int64)
        self.cubic_hole = np.repeat(np.arange(sizes.size), sizes)[real_cubic]

    # -- geometry ---------------------------------------------------------------------

    def update_points(self, points, weights=None) -> "Surface":
        """Recompute all patches for new input points on the same connectivity.

        Parameters
        ----------
        points : (V, d) float
        weights : (V,) float > 0 or None, new homogeneous weights (rational surfaces
            only; None keeps the current ones)

        A rational surface runs every step on the homogeneous points
        ``(w x, w)`` (A2a); ``refined_points`` are then homogeneous and the
        patch coefficients are ``(w x) / w`` with ``*_weights`` = w.
        """
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[0] != self.n_input_vertices:
            raise ValueError(f"expected points of shape ({self.n_input_vertices}, d), got {points.shape}")
        if weights is not None:
            if self.weights is None:
                raise ValueError("this surface is polynomial: build it with weights to make it rational")
            self.weights = self._check_weights(weights)
        x = points
        if self.weights is not None:
            x = np.concatenate([points * self.weights[:, None], self.weights[:, None]], axis=1)
        for operator in self.operators:
            x = operator @ x
        for constraint in self.constraints:
            x = constraint.apply(x)
        self.points = points
        self.refined_points = x
        d = x.shape[1]
        biquadratic = biquadratic_patches(self.quad_layout, x)
        bicubic = bicubic_patches(self.cubic_layout, x)
        if self.weights is None:
            self.biquadratic, self.bicubic = biquadratic, bicubic
            self.biquadratic_weights = self.bicubic_weights = None
            return self
        self.biquadratic_weights, self.bicubic_weights = biquadratic[..., -1], bicubic[..., -1]
        if not (np.all(self.biquadratic_weights > 0) and np.all(self.bicubic_weights > 0)):
            raise ValueError("the vertex weights vary too much: some patch weight is not positive")
        self.biquadratic = biquadratic[..., :-1] / biquadratic[..., -1:]
        self.bicubic = bicubic[..., :-1] / bicubic[..., -1:]
        return self

    # -- bookkeeping ------------------------------------------------------------------

    @property
    def cubic_stencil(self):
        """(Nc * 16, V2) csr_matrix of step A3 (built on demand; ``update_points`` uses ``cubic_layout``)."""
        o = self.options
        stencil = bicubic_stencil(self.refined, self.holes, o.alpha, o.beta, o.tangent_rule, o.triangles)
        keep = self.cubic_layout.keep
        if keep is None:
            return stencil
        return stencil[(np.flatnonzero(keep)[:, None] * 16 + np.arange(16)).ravel()]

    @property
    def quad_stencil(self):
        """(Nq * 9, V2) csr_matrix of step A2 (built on demand; ``update_points`` uses ``quad_layout``)."""
        return biquadratic_stencil(self.refined, self.quad_frames)

    @property
    def n_patches(self) -> int:
        return int(self.quad_frames.shape[0] + self.cubic_frames.shape[0])

    @property
    def frames(self) -> np.ndarray:
        """(Nq + Nc, 4) int: half-edges e0..e3 of every patch, biquadratic first."""
        return np.concatenate([self.quad_frames, self.cubic_frames])

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
        coarse = self.input
        is_vertex, is_edge = kind == FACE_FROM_VERTEX, kind == FACE_FROM_EDGE
        index = parent.copy()
        index[is_vertex] = self.vertex_source[parent[is_vertex]]
        index[is_edge] = -1
        edge = np.full((kind.size, 2), -1, dtype=np.int64)
        h = parent[is_edge]
        edge[is_edge] = self.vertex_source[np.stack([coarse.origin[h], coarse.dest[h]], axis=1)]
        return kind, index, edge


def build_surface(points, face_sizes, face_vertices, **options) -> Surface:
    """Convenience: ``Surface(face_sizes, face_vertices, points, SurfaceOptions(**options))``.

    ``face_blend``, ``vertex_blend``, ``weights`` and ``vertex_normals`` go to ``Surface``.
    """
    data = {key: options.pop(key, None) for key in ("face_blend", "vertex_blend", "weights", "vertex_normals")}
    return Surface(face_sizes, face_vertices, points, SurfaceOptions(**options), **data)


__all__ = ["Surface", "SurfaceOptions", "build_surface", "TopologyError", "HalfEdgeMesh", "SOURCE_NAMES"]
