"""The stages of a Surface: every geometry step behind one interface.

A stage maps points to points linearly (Theorem 1.3.3: the construction is
linear in the input points) and says so twice: ``apply`` is its fastest way
to map one set of points, ``matrix()`` the same map as a scipy.sparse matrix,
built when first asked for and kept. ``Surface.update_points`` is one loop of
``apply`` over ``Surface.stages``; ``Surface.stencil()`` multiplies the matrices.

In order (``STAGE_BUILDERS``; a builder returns None where its step does not apply):

- ``place``: input points to the coarse mesh (vertex copies of the repairs, ghost points);
- ``doo_sabin_1``: the first Doo-Sabin step, with A1a's vertex interpolation folded in;
- ``doo_sabin_2``: the second step, kept factored (``stencils.doo_sabin.DooSabinStep``);
  both steps pull points towards creases and corners (``stencils.creases``);
- ``perturbation``: A1's perturbation of the B points of even holes;
- ``vertex_normals``: A1a's normal constraint; it mixes the coordinates, so its
  matrix acts on flattened points (``mixes_coordinates``);
- ``patches``: A2 and A3 side by side, the coefficient rows of all biquadratic
  patches, then of all bicubic ones.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from ..memory import return_freed_memory
from ..mesh.ghost_layer import ghost_points_parts, reflex_corners
from .extensions.interpolation import normal_constraint, vertex_interpolation_parts
from .features import INFINITELY_SHARP
from .refine.doo_sabin import FACE_FROM_VERTEX
from .stencils.holes.bicubic import bicubic_layout
from .stencils.biquadratic import biquadratic_layout
from .stencils.blend import second_step_ratios
from .stencils.creases import (crease_correction, mirror_perturbation, mirror_perturbation_left, mirror_rows,
                               refined_sharpness)
from .stencils.doo_sabin import (LARGE_FACE, DooSabinStep, FirstDooSabinStep, centroid_columns,
                                 doo_sabin_augmented, doo_sabin_matrix, has_large_face, large_face_centroids)
from .stencils.holes.hole_rules import LARGE_HOLE, HoleRules
from .stencils.perturbation import PerturbationStep, perturbation_matrix, perturbation_parts
from .topology import RELEASED_TWIN_HALFEDGES, SurfaceTopology

if TYPE_CHECKING:  # scipy.sparse is imported where a matrix is made: a closed mesh's conversion makes none (0.2 s)
    from scipy.sparse import csr_matrix


@runtime_checkable
class Stage(Protocol):
    """One linear geometry step of a Surface.

    name : str
    shape : (rows out, rows in)
    mixes_coordinates : bool; False: the same map on every column of the points,
        ``matrix()`` is (rows out, rows in); True: ``matrix(d, weights=None)`` acts
        on the flattened points, (rows out * d, rows in * d), and a rational
        surface's passes the (fixed) weight column it is applied to
    apply(points) : (rows in, d) float -> (rows out, d) float
    matrix() : scipy.sparse matrix of the same map (built on demand, kept)
    """

    name: str
    shape: tuple
    mixes_coordinates: bool

    def apply(self, points: np.ndarray) -> np.ndarray: ...

    def matrix(self): ...


class MatrixStage:
    """A stage that is its sparse matrix."""

    mixes_coordinates = False

    def __init__(self, name: str, matrix):
        self.name = name
        self._matrix = matrix.tocsr()
        self.shape = self._matrix.shape

    def apply(self, points: np.ndarray) -> np.ndarray:
        return self._matrix @ points

    def matrix(self) -> csr_matrix:
        return self._matrix


class CentroidStage:
    """A stage whose matrix holds n^2 entries per n-sided cell (the first Doo-Sabin step on creases or with
    A1a), kept in O(n) entries: ``step`` acts on the points followed by derived points, each ``derived``
    matrix making some from those before it (the centroids (L, V) of the L large faces,
    ``stencils.doo_sabin.doo_sabin_augmented``; the mean rows of large V-cells, ``vertex_interpolation_parts``);
    ``matrix()`` multiplies them out."""

    mixes_coordinates = False

    def __init__(self, name: str, step, derived):
        self.name, self._step, self._derived = name, step.tocsr(), [d.tocsr() for d in derived]
        self.shape = (step.shape[0], self._derived[0].shape[1])
        self._matrix = None

    def apply(self, points: np.ndarray) -> np.ndarray:
        y = points
        for derived in self._derived:
            y = np.concatenate([y, derived @ y])
        return self._step @ y

    def matrix(self) -> csr_matrix:
        if self._matrix is None:
            full = self._step
            for derived in reversed(self._derived):
                k = derived.shape[1]
                full = (full[:, :k] + full[:, k:] @ derived).tocsr()
            self._matrix = full
        return self._matrix


class PlacementStage:
    """Input points to the coarse mesh's points: each repaired vertex's input point, then the ghost points.

    The ghost points of open meshes follow a rule that reads the geometry once
    (convex or reflex single-face corners, ``mesh.ghost_layer``): ``follow``
    classifies the corners again for new points and rebuilds the matrix when
    the classification changed, so moved points give what a fresh Surface gives.
    A closed mesh's stage is a selection of rows, applied without its matrix.
    """

    name = "place"
    mixes_coordinates = False

    def __init__(self, topology: SurfaceTopology, points: np.ndarray):
        self._topology = topology
        self._layer = topology.ghost
        self._source = topology.vertex_source
        self.reflex = None  # (k,) bool per ghost corner, or None (closed input)
        self._matrix = None  # made when asked for (closed input) or by ``follow`` (open input)
        self._derived = None  # (L, V) csr_matrix: centroids of large faces, read as points of their own
        self.follow(points)
        self.shape = (topology.input.n_vertices, topology.n_input_vertices)

    def follow(self, points: np.ndarray) -> bool:
        """Classify the ghost corners for input ``points`` (V, d); True if the matrix changed."""
        if self._layer is None:
            return False
        reflex = reflex_corners(self._layer, points[self._source, :3])
        if self.reflex is not None and np.array_equal(reflex, self.reflex):
            return False
        self.reflex = reflex
        matrix, centroids = ghost_points_parts(self._layer, reflex, LARGE_FACE)
        select = self._topology.select_matrix()
        if centroids is None:
            self._matrix, self._derived = matrix @ select, None
        else:  # faces of many sides: their centroids as points of their own (``ghost_points_parts``)
            from scipy.sparse import hstack

            n = centroids.shape[1]
            self._derived = (centroids @ select).tocsr()
            self._matrix = hstack([matrix[:, :n] @ select, matrix[:, n:]], format="csr")
            self._whole = None
        return True

    def apply(self, points: np.ndarray) -> np.ndarray:
        if self._matrix is None:  # the selection's product adds each row's one point to 0.0 (-0.0 becomes 0.0)
            return np.take(points, self._source, axis=0) + 0.0
        if self._derived is not None:
            return self._matrix @ np.concatenate([points, self._derived @ points])
        return self._matrix @ points

    def matrix(self) -> csr_matrix:
        if self._matrix is None:
            self._matrix = self._topology.select_matrix()
        if self._derived is not None:
            if self._whole is None:
                n = self._derived.shape[1]
                self._whole = (self._matrix[:, :n] + self._matrix[:, n:] @ self._derived).tocsr()
            return self._whole
        return self._matrix


class StackedStage:
    """Stages applied to the same points, their output rows one after the other (``patches``: A2, then A3).

    Each part is a ``stencils.layout.PatchLayout`` (``apply`` writes into the rows given).
    """

    mixes_coordinates = False

    def __init__(self, name: str, parts):
        self.name = name
        self.parts = tuple(parts)
        self.shape = (sum(part.shape[0] for part in self.parts), self.parts[0].shape[1])
        self._matrix = None

    def apply(self, points: np.ndarray, offset: np.ndarray | None = None) -> np.ndarray:
        """(rows out, d) from (rows in, d); ``offset`` (d,) is added to every output row (points relative
        to an origin: every part's rows sum to 1, so this puts the origin back, block by block in cache)."""
        out = np.empty((self.shape[0], points.shape[1]))
        start = 0
        for part in self.parts:
            part.apply(points, out=out[start : start + part.shape[0]], offset=offset)
            start += part.shape[0]
        return out

    def reuse(self) -> None:
        """Applied again (``Surface.update_points``): each part readies its faster form (``PatchLayout.reuse``)."""
        for part in self.parts:
            part.reuse()

    def matrix(self) -> csr_matrix:
        if self._matrix is None:
            from scipy.sparse import vstack

            self._matrix = vstack([part.matrix() for part in self.parts], format="csr")
        return self._matrix


@dataclass(frozen=True)
class StageInputs:
    """What the stages need besides the topology (validated, in the coarse mesh's numbering).

    points : (V, d) float, the input points (the ghost-corner rule reads them)
    corner_ratio : (H,) float, first-step blend ratio of every corner of the coarse mesh (``stencils.blend``)
    hole_rules : HoleRules, the A3 rule of every hole size and its shape parameters
    interpolate_vertices : bool, A1a
    vertex_normals : (Vc, 3) float or None, NaN rows where unset
    rational : bool, points carry a homogeneous weight as last column
    """

    points: np.ndarray
    corner_ratio: np.ndarray
    hole_rules: HoleRules
    interpolate_vertices: bool = False
    vertex_normals: np.ndarray | None = None
    rational: bool = False


def placement_stage(topology: SurfaceTopology, inputs: StageInputs) -> PlacementStage:
    return PlacementStage(topology, inputs.points)


def first_step_stage(topology: SurfaceTopology, inputs: StageInputs):
    """A1's first Doo-Sabin step; with A1a every V-cell gets its input vertex as centroid."""
    if topology.refinements == 0:
        return None
    sharp = topology.sharpness
    # infinitely sharp corners off the C0 seams: the surface passes through them (A1a at those vertices;
    # beta moves the cell centres off them, so not with beta)
    corners = None if sharp is None or inputs.hole_rules.beta != 0 else sharp.vertex >= INFINITELY_SHARP
    corners = corners if corners is not None and corners.any() else None
    plain = sharp is None and not inputs.interpolate_vertices and topology.crease_sheets is None
    if plain:  # the plain step: its matrix's map, without the matrix
        return FirstDooSabinStep(topology.input, inputs.corner_ratio)
    centroids, derived = None, []  # derived: points made from the points, as columns of the step (CentroidStage)
    if has_large_face(topology.input):  # n^2 entries per n-sided face: its centroid as a column instead
        step, centroids = doo_sabin_augmented(topology.input, inputs.corner_ratio)
        derived.append(centroids)
    else:
        step = doo_sabin_matrix(topology.input, inputs.corner_ratio, per_corner=True)
    if sharp is not None:  # creases and corners pull their points towards the crease polygon (stencils.creases)
        columns = None if centroids is None else centroid_columns(topology.input)
        correction = crease_correction(topology.input, inputs.corner_ratio, inputs.corner_ratio, sharp.halfedge,
                                       sharp.vertex, step=1, centroid_column=columns, n_columns=step.shape[1])
        step = step if correction is None else (step + correction).tocsr()
    if inputs.interpolate_vertices or corners is not None:
        step, means = vertex_interpolation_parts(step, topology.input, topology.faces1,
                                                 None if inputs.interpolate_vertices else corners, LARGE_FACE)
        derived += [] if means is None else [means]
    if topology.crease_sheets is not None:  # C0 creases: ghost points mirror the real ones (stencils.creases)
        step = mirror_rows(step, topology.input, topology.crease_sheets, inputs.corner_ratio)
    return CentroidStage("doo_sabin_1", step, derived) if derived else MatrixStage("doo_sabin_1", step)


def second_step_stage(topology: SurfaceTopology, inputs: StageInputs) -> DooSabinStep | None:
    """A1's second step: a once-refined vertex keeps its first-step ratio, V-cells the minimum."""
    if topology.refinements < 2:
        return None
    is_vertex_cell = topology.faces1.kind == FACE_FROM_VERTEX
    ratio = second_step_ratios(topology.level1, is_vertex_cell, inputs.corner_ratio)
    correction, centroids, sharp = None, None, topology.sharpness
    if sharp is not None:  # the creases of the first step, one step weaker (stencils.creases)
        ratio = np.ascontiguousarray(ratio)
        halfedge, vertex = refined_sharpness(topology.input, topology.level1, sharp.halfedge, sharp.vertex)
        columns = None
        if has_large_face(topology.level1):  # n^2 entries per n-sided face: its centroid as a column instead
            centroids, columns = large_face_centroids(topology.level1), centroid_columns(topology.level1)
        correction = crease_correction(topology.level1, ratio, inputs.corner_ratio[topology.level1.origin], halfedge,
                                       vertex, step=2, centroid_column=columns,
                                       n_columns=None if centroids is None else sum(centroids.shape))
    step = DooSabinStep(topology.level1, ratio, correction=correction, centroids=centroids)
    if topology.refined.n_halfedges >= RELEASED_TWIN_HALFEDGES:
        return_freed_memory()  # what this stage's temporaries freed, before the largest arrays of the build
    return step


def perturbation_stage(topology: SurfaceTopology, inputs: StageInputs):
    """A1's perturbation of even holes: its matrix, or factored when some even hole has more than
    ``LARGE_HOLE`` sides (the matrix holds (2n)^2 entries for an n-sided hole)."""
    large = any(g.n % 2 == 0 and g.n > LARGE_HOLE and not g.dart for g in topology.holes)
    if large:
        constraints, inverse_gram = perturbation_parts(topology.refined, topology.holes)
        left = None
        if topology.crease_sheets is not None:  # C0 creases: ghost partners follow (stencils.creases)
            left = mirror_perturbation_left(constraints, topology.refined, topology.real_vertex,
                                            _sheet_ghost(topology))
        return PerturbationStep(constraints, inverse_gram, left)
    matrix = perturbation_matrix(topology.refined, topology.holes)
    if matrix is not None and topology.crease_sheets is not None:  # C0 creases: ghost partners follow
        matrix = mirror_perturbation(matrix, topology.refined, topology.real_vertex, _sheet_ghost(topology))
    return None if matrix is None else MatrixStage("perturbation", matrix)


def _sheet_ghost(topology: SurfaceTopology) -> np.ndarray:
    """(Vr,) bool: the refined points of the crease sheets' ghost quads (``creases.mirror_perturbation``)."""
    return np.isin(topology.input.face[topology.coarse_corner()], topology.crease_sheets.ghost_faces)


def normal_stage(topology: SurfaceTopology, inputs: StageInputs):
    """A1a's normal constraint, where vertex normals are given."""
    if inputs.vertex_normals is None or topology.faces1 is None:
        return None
    return normal_constraint(topology.refined, topology.faces1, inputs.vertex_normals, inputs.hole_rules.tangent_datum,
                             inputs.rational)


def patch_stage(topology: SurfaceTopology, inputs: StageInputs) -> StackedStage:
    """A2 and A3: refined points to the coefficient rows of every kept patch."""
    refined = topology.refined
    biquadratic = biquadratic_layout(refined, topology.quad_frames)
    bicubic = bicubic_layout(topology.holes, inputs.hole_rules.weights, refined.n_vertices, topology.cubic_keep,
                             inputs.hole_rules.dart_weights)
    return StackedStage("patches", (biquadratic, bicubic))


STAGE_BUILDERS = (placement_stage, first_step_stage, second_step_stage, perturbation_stage, normal_stage, patch_stage)
