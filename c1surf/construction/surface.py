"""The object users hold: the refined topology, a list of stages, and the patches.

Topology is refined once (``topology``); geometry enters only through the
stages (``stages``), each a linear map of the points (Theorem 1.3.3), so
``update_points`` on the same connectivity is one loop of ``apply`` over
them and ``stencil()`` is the product of their matrices.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..errors import OptionError

from ..arrays import column_bounds
from ..mesh.errors import TopologyError
from ..mesh.halfedges import HalfEdgeMesh
from .refine.doo_sabin import FACE_FROM_EDGE, FACE_FROM_FACE, FACE_FROM_VERTEX
from .patch_blocks import PatchSource, patch_source
from .crease_sides import crease_side_pairs
from .stages import STAGE_BUILDERS, StageInputs
from .stencil import flat_stencil, row_stencil
from .stencils.blend import check_ratios, corner_ratios
from .stencils.creases import crease_corner_ratios
from .stencils.holes.hole_rules import TRIANGLE_RULES, HoleRules
from .topology import build_topology

SOURCE_NAMES = {FACE_FROM_FACE: "face", FACE_FROM_EDGE: "edge", FACE_FROM_VERTEX: "vertex"}
TANGENT_RULES = ("symmetric", "corners")


@dataclass(frozen=True)
class SurfaceOptions:
    """Shape controls of the construction.

    blend : float, default blend ratio alpha_f of every cell (A1), in [0, 1]
    alpha : float, shape parameter of the bicubic tangents P_32 (A3), default 1
    beta : float, S = S_C + beta (S_P - S_C) (section 1.3.3), default 0
    tangent_rule : "symmetric" (A3) or "corners" (A3a)
    interpolate_vertices : bool, A1a: the surface passes through every input vertex (needs beta = 0)
    triangles : "g1" (A3 for every hole) or "parametric" (section 1.3.4 for 3-sided holes:
        parametrically C1 to the biquadratic patches around); ``stencils.hole_rules``
    refinements : 2 (the paper's A1), 0 or 1 (closed meshes that already satisfy R1-R3 after
        that many steps, Prop. 1.3.1), or "auto" (the fewest that work; ``refine.fewer_steps``)
    exact_creases : bool, infinitely sharp creases become C0 seams where the construction makes
        them exact (``mesh.creases.sheets``; the others stay the sharpest G1 crease). The library's
        construction only, for now: the command line, the patch files and the checks do not yet mark
        crease sides (docs/sharp-features.md)
    """

    blend: float = 0.5
    alpha: float = 1.0
    beta: float = 0.0
    tangent_rule: str = "symmetric"
    interpolate_vertices: bool = False
    triangles: str = "g1"
    refinements: int | str = 2
    exact_creases: bool = False

    def check(self, vertex_normals=None) -> "SurfaceOptions":
        """Raise OptionError (a ValueError) for a value or combination the construction cannot take; else return self."""
        if self.tangent_rule not in TANGENT_RULES:
            raise OptionError(f"tangent rule must be one of {TANGENT_RULES}")
        if self.triangles not in TRIANGLE_RULES:
            raise OptionError(f"triangles must be one of {TRIANGLE_RULES}")
        if self.refinements not in (0, 1, 2, "auto"):
            raise OptionError("refinements must be 0, 1, 2 or 'auto'")
        if self.interpolate_vertices and self.refinements == 0:
            raise OptionError("vertex interpolation (A1a, --interpolate-vertices) needs at least one refinement step "
                              "(--refinements 1, 2 or auto)")
        if self.interpolate_vertices and self.exact_creases:
            raise OptionError("vertex interpolation (A1a, --interpolate-vertices/--interpolate-normals) does not work "
                              "with exact creases (--exact-creases) yet")
        if self.interpolate_vertices and self.beta != 0:
            raise OptionError("vertex interpolation (A1a, --interpolate-vertices/--interpolate-normals) needs --beta 0: "
                              "beta moves the cell centres off the vertices")
        if vertex_normals is not None and not self.interpolate_vertices:
            raise OptionError("vertex normals are interpolated together with the vertices: set interpolate_vertices")
        if vertex_normals is not None and self.alpha == 0:
            raise OptionError("vertex normals (--interpolate-normals) need --alpha > 0: alpha = 0 leaves no tangent plane "
                              "at cell centres")
        return self

    def hole_rules(self) -> HoleRules:
        return HoleRules(self.triangles, self.alpha, self.beta, self.tangent_rule)


@dataclass(frozen=True)
class ExtensionData:
    """The per-face and per-vertex inputs of the paper's extensions and of sharp features (``Surface``'s keywords).

    face_blend : (F,) float or None, per-face blend ratio overriding ``options.blend``
    vertex_blend : (V,) float or None, per-vertex blend ratio (NaN or negative: unset)
    weights : (V,) float > 0 or None, homogeneous weight of every input point (A2a)
    vertex_normals : (V, 3) float or None, NaN rows where unset (A1a)
    features : SharpFeatures or None, creases, corners and holes
    """

    face_blend: object = None
    vertex_blend: object = None
    weights: object = None
    vertex_normals: object = None
    features: object = None


class Surface:
    """A G1 surface of biquadratic and bicubic Bezier patches over a polygon mesh.

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int, faces concatenated, counter-clockwise from outside
    points : (V, d) float, d >= 1 (3 for positions; more columns are carried along linearly)
    options : SurfaceOptions
    lazy_patches : bool, keyword only (below)
    **extensions : the fields of ``ExtensionData``, keyword only:
    face_blend : (F,) float or None, per-face blend ratio overriding ``options.blend``
    vertex_blend : (V,) float or None, per-vertex blend ratio (NaN or negative: unset),
        used for the corners at that vertex (``stencils.blend``)
    weights : (V,) float > 0 or None, homogeneous weight of every input point (A2a):
        the patches become rational, with weights
    vertex_normals : (V, 3) float or None, NaN rows where unset: with
        ``options.interpolate_vertices`` the surface normal at each such vertex is this one
    features : SharpFeatures or None, creases, corners and holes (``construction.features``):
        topology, fixed for the surface's life like the connectivity

    Attributes (after construction)
    -------------------------------
    biquadratic : (Nq, 3, 3, d) float, Bezier coefficients of the A2 patches
    bicubic : (Nc, 4, 4, d) float, Bezier coefficients of the A3 patches
    biquadratic_weights, bicubic_weights : (Nq, 3, 3), (Nc, 4, 4) float, or None when not rational
    topology : SurfaceTopology, the integers (refined meshes, holes, patch frames)
    stages : list of ``stages.Stage``, the geometry steps in order
    refined_points : (Vr, d) float (homogeneous when rational), the points A2 and A3 read
    timings : dict, seconds spent on "topology", on building each stage ("build <name>")
        and on its last application ("apply <name>"; the patches' once they are made)

    ``lazy_patches=True`` makes the four patch arrays on first use instead of at
    construction and ``update_points`` (a rational surface then checks its patch
    weights there too): the streamed conversion reads the patches by blocks
    (``patch_blocks``, ``patch_source``) and never makes them.
    """

    def __init__(self, face_sizes, face_vertices, points, options: SurfaceOptions | None = None, *,
                 lazy_patches: bool = False, **extensions):
        x = ExtensionData(**extensions)
        face_blend, vertex_blend, weights, vertex_normals, features = (x.face_blend, x.vertex_blend, x.weights,
                                                                       x.vertex_normals, x.features)
        self.options = o = (options or SurfaceOptions()).check(vertex_normals)
        self.lazy_patches = bool(lazy_patches)
        points = np.asarray(points, dtype=np.float64)
        n_vertices, n_faces = points.shape[0], np.size(face_sizes)
        blend = np.full(n_faces, float(o.blend))
        if face_blend is not None:
            blend = check_ratios(face_blend, n_faces, "per-face blend ratios", allow_unset=True)
            blend = np.where(np.isnan(blend), float(o.blend), blend)
        if vertex_blend is not None:
            vertex_blend = check_ratios(vertex_blend, n_vertices, "per-vertex blend ratios", allow_unset=True)
        if vertex_normals is not None:
            vertex_normals = np.asarray(vertex_normals, dtype=np.float64).reshape(n_vertices, 3)
        self.weights = None if weights is None else _checked_weights(weights, n_vertices)
        self.timings = {}
        start = time.perf_counter()
        if features is not None:
            features = features.check(n_vertices, n_faces)
        self.features = features
        self.topology = t = build_topology(face_sizes, face_vertices, n_vertices, o.refinements, o.interpolate_vertices,
                                           features, o.exact_creases)
        self.timings["topology"] = time.perf_counter() - start
        # First step: a corner takes its vertex's ratio where one is given, else its cell's (stencils.blend).
        corner = corner_ratios(t.input, t.per_coarse_face(blend, float(o.blend)), t.per_coarse_vertex(vertex_blend))
        if t.crease_sheets is not None:  # both sheets of a C0 crease refine alike along it
            corner = crease_corner_ratios(corner, t.input, t.crease_sheets.crease_vertex)
        inputs = StageInputs(points, corner, o.hole_rules(), o.interpolate_vertices, t.per_coarse_vertex(vertex_normals),
                             self.weights is not None)
        self.stages = self._build_stages(inputs)
        self._stencils = {}
        self._crease_sides = None
        self._reused = False
        self._apply(points)

    def _build_stages(self, inputs: StageInputs) -> list:
        """The stages that apply to this topology and these options, in order (``stages.STAGE_BUILDERS``)."""
        stages = []
        for build in STAGE_BUILDERS:
            start = time.perf_counter()
            stage = build(self.topology, inputs)
            if stage is not None:
                stages.append(stage)
                self.timings[f"build {stage.name}"] = time.perf_counter() - start
        return stages

    # -- the topology's numbers, by their old names -----------------------------------

    n_input_vertices = property(lambda self: self.topology.n_input_vertices)
    n_input_faces = property(lambda self: self.topology.n_input_faces)
    repairs = property(lambda self: self.topology.repairs, doc="what the input repairs did (``repair.prepare_topology``)")
    refinements = property(lambda self: self.topology.refinements, doc="Doo-Sabin steps taken (0, 1 or 2)")
    refined = property(lambda self: self.topology.refined, doc="HalfEdgeMesh that A2 and A3 read")
    holes = property(lambda self: self.topology.holes, doc="list of HoleGroup, the holes with a real corner")
    quad_frames = property(lambda self: self.topology.quad_frames, doc="(Nq, 4) int frames of the biquadratic patches")
    cubic_frames = property(lambda self: self.topology.cubic_frames, doc="(Nc, 4) int frames of the bicubic patches")
    cubic_hole = property(lambda self: self.topology.cubic_hole, doc="(Nc,) int, hole of every bicubic patch")
    frames = property(lambda self: self.topology.frames, doc="(Nq + Nc, 4) int, every patch's frame, biquadratic first")

    def stage(self, name: str):
        """The stage called ``name`` ("place", "doo_sabin_1", ..., "patches"; ``stages``); KeyError if there is none."""
        for stage in self.stages:
            if stage.name == name:
                return stage
        raise KeyError(f"no stage {name!r}: this surface has {[stage.name for stage in self.stages]}")

    @property
    def n_patches(self) -> int:
        return int(self.quad_frames.shape[0] + self.cubic_frames.shape[0])

    def patch_sources(self):
        """Which input element each patch comes from (``SurfaceTopology.patch_sources``)."""
        return self.topology.patch_sources()

    @property
    def rational(self) -> bool:
        return self.weights is not None

    @property
    def patch_weights(self):
        """[biquadratic_weights, bicubic_weights], or None for a polynomial surface."""
        return None if self.weights is None else [self.biquadratic_weights, self.bicubic_weights]

    # -- geometry ---------------------------------------------------------------------

    def update_points(self, points, weights=None) -> "Surface":
        """Recompute all patches for new input points on the same connectivity.

        Parameters
        ----------
        points : (V, d) float
        weights : (V,) float > 0 or None, new homogeneous weights (rational surfaces
            only; None keeps the current ones)

        The result is that of a fresh Surface on these points: the ghost
        corners of an open mesh are classified again (``PlacementStage.follow``).
        A call signals re-use (animation, optimisation), so the first one readies
        the stages' faster forms (their ``reuse``): the matrix of the first Doo-Sabin step
        (the same bits as its rows) and the whole slot table of the biquadratic patches
        (``stencils.biquadratic.GridSlots``). The second step stays factored
        (``stencils.doo_sabin.DooSabinStep``), so the patches equal a fresh Surface's on these
        points bit for bit.

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
            self.weights = _checked_weights(weights, self.n_input_vertices)
            self._stencils.clear()
        if not self._reused:
            self._reused = True
            for stage in self.stages:  # the faster form of a stage applied again (DooSabinStep, PatchLayout)
                if hasattr(stage, "reuse"):
                    stage.reuse()
        if self.stages[0].follow(points):  # the placement stage: ghost corners classified again
            self._stencils.clear()
        return self._apply(points)

    def _apply(self, points: np.ndarray) -> "Surface":
        """Run the stages on ``points``: refined points, then (unless ``lazy_patches``) the patches."""
        # Every stage is affine (its rows sum to 1) and commutes with translations, so
        # the stages run on points centred on their bounding box and the centre is added
        # back: round-off then scales with the model's size, not its distance from the origin.
        if points.size:
            low, high = column_bounds(points)
            origin = (low + high) / 2
        else:
            origin = np.zeros(points.shape[1])
        x = points - origin
        if self.weights is not None:
            x = np.concatenate([x * self.weights[:, None], self.weights[:, None]], axis=1)
        for stage in self.stages[:-1]:
            start = time.perf_counter()
            x = stage.apply(x)
            self.timings[f"apply {stage.name}"] = time.perf_counter() - start
        self.points, self._centred, self._origin = points, x, origin
        self._refined = self._patches = None
        if not self.lazy_patches:
            self._patch_arrays()
        return self

    @property
    def refined_points(self) -> np.ndarray:
        """(Vr, d) float (homogeneous when rational): the refined points A2 and A3 read (made on first use)."""
        if self._refined is None:
            refined = self._centred.copy()
            if self.weights is None:
                refined += self._origin
            else:
                refined[:, :-1] += self._origin * refined[:, -1:]
            self._refined = refined
        return self._refined

    def _patch_arrays(self) -> tuple:
        """(biquadratic, bicubic, biquadratic_weights, bicubic_weights), made by the last stage on first use."""
        if self._patches is not None:
            return self._patches
        stage, origin = self.stages[-1], self._origin
        start = time.perf_counter()
        # a polynomial surface's patches get the centre back in the pass that writes them
        x = stage.apply(self._centred, offset=origin) if self.weights is None else stage.apply(self._centred)
        self.timings[f"apply {stage.name}"] = time.perf_counter() - start
        n_quad, d = self.quad_frames.shape[0], x.shape[1]
        biquadratic, bicubic = x[: 9 * n_quad].reshape(n_quad, 3, 3, d), x[9 * n_quad :].reshape(-1, 4, 4, d)
        if self.weights is None:
            self._patches = (biquadratic, bicubic, None, None)
            return self._patches
        weights = biquadratic[..., -1], bicubic[..., -1]
        if not (np.all(weights[0] > 0) and np.all(weights[1] > 0)):
            raise ValueError("the vertex weights vary too much: some patch weight is not positive")
        biquadratic = biquadratic[..., :-1] / biquadratic[..., -1:]
        bicubic = bicubic[..., :-1] / bicubic[..., -1:]
        biquadratic += origin
        bicubic += origin
        self._patches = (biquadratic, bicubic) + weights
        return self._patches

    biquadratic = property(lambda self: self._patch_arrays()[0], doc="(Nq, 3, 3, d) float, the A2 patches")
    bicubic = property(lambda self: self._patch_arrays()[1], doc="(Nc, 4, 4, d) float, the A3 patches")
    biquadratic_weights = property(lambda self: self._patch_arrays()[2], doc="(Nq, 3, 3) float or None")
    bicubic_weights = property(lambda self: self._patch_arrays()[3], doc="(Nc, 4, 4) float or None")

    @property
    def crease_sides(self) -> np.ndarray:
        """(k, 2) int: curve ids ``4 * patch + side`` of the two patch sides along each piece of a C0
        crease (``exact_creases``; ``crease_sides.crease_side_pairs``): equal curves, not G1 across."""
        if self._crease_sides is None:
            self._crease_sides = crease_side_pairs(self.topology)
        return self._crease_sides

    def patch_source(self, **options) -> PatchSource:
        """The patch coefficients by blocks on demand, bit for bit those of ``biquadratic`` / ``bicubic``
        (``patch_blocks.PatchSource``; ``cache_bytes``: the most blocks it keeps). Valid until ``update_points``."""
        return patch_source(self.stages[-1], self._centred, self._origin, self.rational, **options)

    def patch_blocks(self, size: int = 1 << 16):
        """Yield ``patch_blocks.PatchBlock``s (kind, global ids, coefficients, weights) of up to ``size``
        patches, biquadratic then bicubic, in the order of ``frames``: all patches without holding them all."""
        return self.patch_source().blocks(size)

    def stencil(self, flat: bool = False):
        """The whole construction as one sparse matrix, for the current connectivity (and weights).

        Returns
        -------
        flat=False: (R, V) csr_matrix S with ``S @ points`` equal to
            ``np.concatenate([surface.biquadratic.reshape(-1, d), surface.bicubic.reshape(-1, d)])``
            (R = 9 Nq + 16 Nc): row ``9 p + 3 i + j`` is coefficient [i, j] of biquadratic
            patch p, row ``9 Nq + 16 p + 4 k + l`` coefficient [k, l] of bicubic patch p.
            Rational surfaces: the Euclidean coefficients for the current (fixed) weights,
            ``diag(1 / (S_h w)) S_h diag(w)``. Raises ValueError when a stage mixes the
            coordinates (vertex normals, A1a): use ``flat=True`` then.
        flat=True: (R d, V d) csr_matrix F with ``F @ points.ravel()`` equal to that
            concatenation, raveled; works for every surface (d = the columns of the points).

        Built on the first call and kept until the weights change or a ghost corner
        changes between convex and reflex. It is large: about 8 entries per row
        (217 M for a 180,000-triangle torus, 16 s to build), and dense around a cell of many sides, which the
        conversion applies in O(n) (``stencils.hole_rules.HoleOperator``, ``stencils.cyclic_sums``): an n-sided
        hole's P_22, P_32 and P_33 read the whole ring (the rule's (16 n, 4 n) block) and, through the Doo-Sabin
        steps and the perturbation, the whole cell, so each n-sided cell adds about 70 n^2 entries (measured on
        prisms: 5.4 M at n = 200; n = 10,000 would need 7e9, about 80 GB: no stencil for such a mesh).
        Move the points along with ``S @ new_points``
        as long as neither happens (``update_points`` follows both).
        """
        key = (flat, self.points.shape[1])
        if key not in self._stencils:
            if flat:
                self._stencils[key] = flat_stencil(self.stages, self.points.shape[1], self.weights)
            else:
                self._stencils[key] = row_stencil(self.stages, self.weights)
        return self._stencils[key]


def _checked_weights(weights, n_vertices: int) -> np.ndarray:
    """(V,) float64 homogeneous weights, or ValueError."""
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.size != n_vertices:
        raise ValueError(f"expected {n_vertices} weights, got {w.size}")
    if not np.all(np.isfinite(w) & (w > 0)):
        raise ValueError("vertex weights must be finite and positive")
    return w


def build_surface(points, face_sizes, face_vertices, **options) -> Surface:
    """Convenience: ``Surface(face_sizes, face_vertices, points, SurfaceOptions(**options))``.

    ``face_blend``, ``vertex_blend``, ``weights``, ``vertex_normals`` and ``features`` go to ``Surface``.
    """
    data = {key: options.pop(key, None) for key in ("face_blend", "vertex_blend", "weights", "vertex_normals", "features")}
    return Surface(face_sizes, face_vertices, points, SurfaceOptions(**options), **data)


__all__ = ["Surface", "SurfaceOptions", "build_surface", "TopologyError", "HalfEdgeMesh", "SOURCE_NAMES", "TANGENT_RULES",
           "TRIANGLE_RULES"]
