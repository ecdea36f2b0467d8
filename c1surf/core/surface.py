"""The object users hold: refined topology, sparse operators, and the patches.

Topology is refined once; geometry enters only as sparse products
(Theorem 1.3.3: the construction is linear in the input points), so
``update_points`` on the same connectivity costs a few sparse products.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .doo_sabin import FACE_FROM_EDGE, FACE_FROM_FACE, FACE_FROM_VERTEX, doo_sabin_matrix, refine_doo_sabin, second_step_ratio
from .errors import TopologyError
from scipy.sparse import csr_matrix

from .boundary import add_ghost_layer
from .patches import biquadratic_stencil, bicubic_stencil, hole_neighbourhoods, patch_frames, perturbation_matrix
from .repair import check_valence, prepare_topology
from .topology import HalfEdgeMesh, build_halfedges

SOURCE_NAMES = {FACE_FROM_FACE: "face", FACE_FROM_EDGE: "edge", FACE_FROM_VERTEX: "vertex"}
TANGENT_RULES = ("symmetric", "corners")


@dataclass(frozen=True)
class SurfaceOptions:
    """Shape controls of the construction.

    blend : float, default blend ratio alpha_f of every cell (A1), in [0, 1]
    alpha : float, shape parameter of the bicubic tangents P_32 (A3), default 1
    beta : float, S = S_C + beta (S_P - S_C) (section 1.3.3), default 0
    tangent_rule : "symmetric" (A3) or "corners" (A3a)
    """

    blend: float = 0.5
    alpha: float = 1.0
    beta: float = 0.0
    tangent_rule: str = "symmetric"


class Surface:
    """A G1 surface of biquadratic and bicubic Bezier patches over a polygon mesh.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int, faces concatenated, counter-clockwise from outside
    points : (V, d) float, d >= 1 (3 for positions; more columns are carried along linearly)
    options : SurfaceOptions
    face_blend : (F,) float or None, per-face blend ratio overriding ``options.blend``

    Attributes (after construction)
    -------------------------------
    biquadratic : (Nq, 3, 3, d) float, Bezier coefficients of the A2 patches
    bicubic : (Nc, 4, 4, d) float, Bezier coefficients of the A3 patches
    """

    def __init__(self, face_sizes, face_vertices, points, options: SurfaceOptions | None = None, face_blend=None):
        self.options = options or SurfaceOptions()
        if self.options.tangent_rule not in TANGENT_RULES:
            raise ValueError(f"tangent rule must be one of {TANGENT_RULES}")
        points = np.asarray(points, dtype=np.float64)
        self.n_input_vertices = points.shape[0]
        face_sizes = np.asarray(face_sizes, dtype=np.int64)
        self.n_input_faces = int(face_sizes.size)
        blend = np.full(face_sizes.size, float(self.options.blend))
        if face_blend is not None:
            blend = np.asarray(face_blend, dtype=np.float64).copy()
        self._build_topology(face_sizes, np.asarray(face_vertices, dtype=np.int64), blend, points)
        self.update_points(points)

    # -- topology and operators (no coordinates) ------------------------------------

    def _build_topology(self, face_sizes, face_vertices, blend, points) -> None:
        # Repairs first (orientation, pinched vertices), then a ghost layer
        # closes any boundary; from there on every mesh is handled alike.
        prepared, vertex_source, self.repairs = prepare_topology(face_sizes, face_vertices, self.n_input_vertices)
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
        self.input = coarse

        step1 = doo_sabin_matrix(coarse, blend)
        faces1 = refine_doo_sabin(coarse)
        level1 = build_halfedges(faces1.face_sizes, faces1.face_vertices, coarse.n_halfedges)
        # Second step: F-faces keep their cell's blend ratio; cells born at
        # edges and vertices take the global one (the paper leaves this open).
        blend1 = np.full(level1.n_faces, float(self.options.blend))
        from_face = faces1.kind == FACE_FROM_FACE
        blend1[from_face] = blend[faces1.parent[from_face]]
        step2 = doo_sabin_matrix(level1, second_step_ratio(level1.face_sizes, blend1))
        faces2 = refine_doo_sabin(level1)
        refined = build_halfedges(faces2.face_sizes, faces2.face_vertices, level1.n_halfedges)
        # A refined vertex is a corner of a corner of a coarse face: real if that face is.
        real_vertex = real_face[coarse.face[level1.origin[np.arange(refined.n_vertices)]]]
        holes = hole_neighbourhoods(refined, None if real_face.all() else real_vertex)
        quad_frames, cubic_frames = patch_frames(refined, holes, real_vertex)

        self.level1, self.faces1, self.refined, self.holes = level1, faces1, refined, holes
        self.quad_frames = quad_frames
        self.operators = [place, step1, step2]
        perturb = perturbation_matrix(refined, holes)
        if perturb is not None:
            self.operators.append(perturb)
        o = self.options
        self.quad_stencil = biquadratic_stencil(refined, quad_frames)
        cubic_stencil = bicubic_stencil(refined, holes, o.alpha, o.beta, o.tangent_rule)
        # keep the bicubic patches at real corners only (all of them on a closed mesh)
        real_cubic = real_vertex[refined.origin[cubic_frames[:, 0]]]
        self.cubic_frames = cubic_frames[real_cubic]
        rows = (np.flatnonzero(real_cubic)[:, None] * 16 + np.arange(16)).ravel()
        self.cubic_stencil = cubic_stencil[rows] if not real_cubic.all() else cubic_stencil
        self.cubic_hole = np.repeat(np.arange(sum(g.cells.size for g in holes)), [g.n for g in holes for _ in range(g.cells.size)])[real_cubic]

    # -- geometry ---------------------------------------------------------------------

    def update_points(self, points) -> "Surface":
        """Recompute all patches for new input points on the same connectivity.

        Parameters
        ----------
        points : (V, d) float
        """
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[0] != self.n_input_vertices:
            raise ValueError(f"expected points of shape ({self.n_input_vertices}, d), got {points.shape}")
        x = points
        for operator in self.operators:
            x = operator @ x
        self.points = points
        self.refined_points = x
        d = points.shape[1]
        self.biquadratic = (self.quad_stencil @ x).reshape(-1, 3, 3, d)
        self.bicubic = (self.cubic_stencil @ x).reshape(-1, 4, 4, d)
        return self

    # -- bookkeeping ------------------------------------------------------------------

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
    """Convenience: ``Surface(face_sizes, face_vertices, points, SurfaceOptions(**options))``."""
    face_blend = options.pop("face_blend", None)
    return Surface(face_sizes, face_vertices, points, SurfaceOptions(**options), face_blend=face_blend)


__all__ = ["Surface", "SurfaceOptions", "build_surface", "TopologyError", "HalfEdgeMesh", "SOURCE_NAMES"]
