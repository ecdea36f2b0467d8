"""The Open CASCADE B-rep of a patch set, built from c1surf's own topology (``brep.topology``), not by sewing.

The STEP writer (``io.patches.step``) writes the shape this module builds.
``topology.brep_topology`` says which patch sides are one edge and where the
vertices are; here every item becomes its Open CASCADE counterpart through
``BRep_Builder``, so nothing is guessed from distances:

- **faces**: one per topology face, on the exact surface (``Geom_BSplineSurface``
  of a merged piece over [0, m] x [0, n], ``Geom_BezierSurface`` of a patch over
  [0, 1]^2; rational where the patch set has weights), each bounded by one wire
  on its natural bounds, so the STEP reader still sees untrimmed faces;
- **edges**: one per chain of topology edges (``edge_chains``: the patch
  sides between the same two faces, joined where nothing else meets them), its
  3D curve the sides' Bezier curves one after the other as a ``Geom_BSplineCurve``
  over [0, k] (degree 2 or 3, rational with weights), and on each face that uses
  it a straight pcurve, a ``Geom2d_BSplineCurve`` of degree 1 over the same
  [0, k] run at unit speed, so both representations share their parameter
  (SameParameter, SameRange); a seam (one face using an edge twice: a piece that
  closes on itself) gets both pcurves on that face (FORWARD use first, as
  ``BRep_CurveOnClosedSurface`` wants);
- **vertices**: one at each chain end, at its corner coefficient;
- **shells**: one per connected component (faces joined through shared edges);
  a closed component (every edge in two faces) is made a solid, turned so that
  its enclosed volume is positive; several components go into one compound.

Tolerances (:func:`brep_tolerance`) come from the size, not from Open CASCADE's
absolute default: the faces of a c1surf surface meet to round-off (a few units
in the last place of the coordinates), and the tolerance is 1e-9 of the
bounding-box diagonal, six orders of magnitude above that and far below any
feature of the surface (or 1e-12 of the largest coordinate, where a small
surface far from the origin has coarser coordinates). ``BRep_Tool.Tolerance`` never reports less than
``Precision::Confusion()`` (1e-7), so that is the floor Open CASCADE checks with.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from ...errors import OutputError
from ..merged import piece_patches
from .edge_chains import EdgeChains, chain_curve, edge_chains
from .solids import closed_components, face_components, signed_volumes
from .topology import FACE_PIECE, BRepTopology, brep_topology, edge_curves

RELATIVE_TOLERANCE = 1e-9  # of the bounding-box diagonal: the faces meet to round-off, ~1e-15 of it
ROUNDING_TOLERANCE = 1e-12  # of the largest coordinate magnitude: round-off of a surface far from the origin
_KNOT_ARRAYS: dict = {}  # (spans, degree) or ("segment", length) -> Open CASCADE knots and multiplicities
_CAD_HINT = "STEP output needs Open CASCADE: pip install 'c1surf[cad]' (cadquery-ocp)"


def occ_classes() -> SimpleNamespace:
    """The Open CASCADE classes the B-rep needs (cadquery-ocp 7 or 8), or an OutputError saying what to install."""
    try:
        import OCP  # noqa: F401
    except ImportError:
        raise OutputError("STEP", _CAD_HINT) from None
    from OCP.BRep import BRep_Builder
    from OCP.Geom import Geom_BezierSurface, Geom_BSplineCurve, Geom_BSplineSurface
    from OCP.Geom2d import Geom2d_BSplineCurve
    from OCP.gp import gp_Pnt, gp_Pnt2d
    from OCP.TopAbs import TopAbs_FORWARD, TopAbs_REVERSED
    from OCP.TopoDS import TopoDS_Compound, TopoDS_Edge, TopoDS_Face, TopoDS_Shell, TopoDS_Solid, TopoDS_Vertex, TopoDS_Wire

    try:  # cadquery-ocp 7.x
        from OCP.TColgp import TColgp_Array1OfPnt as Array1OfPnt
        from OCP.TColgp import TColgp_Array1OfPnt2d as Array1OfPnt2d
        from OCP.TColgp import TColgp_Array2OfPnt as Array2OfPnt
        from OCP.TColStd import TColStd_Array1OfInteger as Array1OfInt
        from OCP.TColStd import TColStd_Array1OfReal as Array1OfReal
        from OCP.TColStd import TColStd_Array2OfReal as Array2OfReal
    except ImportError:  # cadquery-ocp 8: NCollection arrays live in OCP.collections
        from OCP.collections import Array1_double as Array1OfReal
        from OCP.collections import Array1_gp_Pnt as Array1OfPnt
        from OCP.collections import Array1_gp_Pnt2d as Array1OfPnt2d
        from OCP.collections import Array1_int as Array1OfInt
        from OCP.collections import Array2_double as Array2OfReal
        from OCP.collections import Array2_gp_Pnt as Array2OfPnt
    return SimpleNamespace(
        Builder=BRep_Builder, BSplineCurve=Geom_BSplineCurve, Bezier=Geom_BezierSurface, BSpline=Geom_BSplineSurface,
        BSpline2d=Geom2d_BSplineCurve, Pnt=gp_Pnt, Pnt2d=gp_Pnt2d, FORWARD=TopAbs_FORWARD, REVERSED=TopAbs_REVERSED,
        Compound=TopoDS_Compound, Edge=TopoDS_Edge, Face=TopoDS_Face, Shell=TopoDS_Shell, Solid=TopoDS_Solid,
        Vertex=TopoDS_Vertex, Wire=TopoDS_Wire, Array1OfPnt=Array1OfPnt, Array1OfPnt2d=Array1OfPnt2d, Array2OfPnt=Array2OfPnt,
        Array1OfReal=Array1OfReal, Array2OfReal=Array2OfReal, Array1OfInt=Array1OfInt)


def occ_poles(occ, points: np.ndarray):
    """Control points (n, 3) or (nu, nv, 3) as an Open CASCADE array of gp_Pnt (1-based, first index with u)."""
    if points.ndim == 2:
        poles = occ.Array1OfPnt(1, points.shape[0])
        for i, (x, y, z) in enumerate(points.tolist()):
            poles.SetValue(i + 1, occ.Pnt(x, y, z))
        return poles
    nu, nv = points.shape[:2]
    poles = occ.Array2OfPnt(1, nu, 1, nv)
    for i, row in enumerate(points.tolist()):
        for j, (x, y, z) in enumerate(row):
            poles.SetValue(i + 1, j + 1, occ.Pnt(x, y, z))
    return poles


def occ_reals(occ, values: np.ndarray):
    """A (n,) or (nu, nv) float array as an Open CASCADE array of reals (1-based)."""
    if values.ndim == 1:
        out = occ.Array1OfReal(1, values.size)
        for i, x in enumerate(values.tolist()):
            out.SetValue(i + 1, x)
        return out
    out = occ.Array2OfReal(1, values.shape[0], 1, values.shape[1])
    for i, row in enumerate(values.tolist()):
        for j, x in enumerate(row):
            out.SetValue(i + 1, j + 1, x)
    return out


def occ_integers(occ, values: np.ndarray):
    """A (n,) int array as an Open CASCADE array of integers (1-based)."""
    out = occ.Array1OfInt(1, values.size)
    for i, x in enumerate(values.tolist()):
        out.SetValue(i + 1, int(x))
    return out


def bezier_surface(occ, points: np.ndarray, weights: np.ndarray | None = None):
    """The exact ``Geom_BezierSurface`` over [0, 1]^2 of one patch: points (du+1, dv+1, >= 3), weights (du+1, dv+1) or None."""
    poles = occ_poles(occ, np.asarray(points, np.float64)[..., :3])
    return occ.Bezier(poles) if weights is None else occ.Bezier(poles, occ_reals(occ, np.asarray(weights, np.float64)))


def bspline_surface(occ, piece):
    """The clamped ``Geom_BSplineSurface`` of degree (2, 2) of a merged piece (``evaluation.merge.MergedPiece``)."""
    knots, multiplicities = [], []
    for values in (piece.knots_u, piece.knots_v):
        distinct, counts = np.unique(values, return_counts=True)
        knots.append(occ_reals(occ, distinct))
        multiplicities.append(occ_integers(occ, counts))
    weights = np.ones(piece.points.shape[:2]) if piece.weights is None else piece.weights
    return occ.BSpline(occ_poles(occ, np.asarray(piece.points, np.float64)[..., :3]),
                       occ_reals(occ, np.asarray(weights, np.float64)), knots[0], knots[1], multiplicities[0],
                       multiplicities[1], 2, 2)


def brep_tolerance(points: np.ndarray) -> float:
    """The B-rep tolerance of a surface with control points ``points`` (N, 3): see the module docstring.

    1e-9 of the bounding-box diagonal, or 1e-12 of the largest coordinate
    magnitude where that is larger (a small surface far from the origin, whose
    coordinates carry round-off of that order); 1e-9 for an empty or flat-point set.
    """
    if not points.size:
        return RELATIVE_TOLERANCE
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    return max(RELATIVE_TOLERANCE * diagonal, ROUNDING_TOLERANCE * float(np.abs(points).max())) or RELATIVE_TOLERANCE


@dataclass(frozen=True)
class BRepShape:
    """The shape to write and what it is made of.

    shape : TopoDS_Shape, a solid or a shell for one component, else a compound of them
    closed : (C,) bool, component c is a closed shell made a solid
    component : (F,) int64, the component of each topology face
    tolerance : float, of every face, edge and vertex
    """

    shape: object
    closed: np.ndarray
    component: np.ndarray
    tolerance: float


def brep_shape(patch_set, topology: BRepTopology | None = None) -> BRepShape:
    """The B-rep of ``patch_set`` (``evaluation.patch_set.PatchSet``), from its topology (computed when not given).

    Raises OutputError (one line) without Open CASCADE.
    """
    topology = brep_topology(patch_set) if topology is None else topology
    occ = occ_classes()
    builder = occ.Builder()
    points = np.concatenate([np.asarray(g, np.float64)[..., :3].reshape(-1, 3) for g in patch_set.groups]
                            + [np.zeros((0, 3))])
    tolerance = brep_tolerance(points)
    faces = _faces(occ, builder, patch_set, topology, tolerance)
    chains = edge_chains(topology)
    edges = _edges(occ, builder, patch_set, topology, chains, tolerance)
    _pcurves(occ, builder, chains, faces, edges, tolerance)
    _wires(occ, builder, chains, faces, edges)
    component = face_components(topology)
    closed = closed_components(topology, component)
    volume = signed_volumes(patch_set, topology, component)
    return BRepShape(_assemble(occ, builder, faces, component, closed, volume < 0), closed, component, tolerance)


def _faces(occ, builder, patch_set, topology: BRepTopology, tolerance: float) -> list:
    """One TopoDS_Face (no wire yet) per topology face, on its exact surface."""
    first = np.cumsum([0] + [len(g) for g in patch_set.groups])
    faces = []
    for kind, index in zip(topology.face_kind.tolist(), topology.face_index.tolist()):
        if kind == FACE_PIECE:
            surface = bspline_surface(occ, patch_set.merged[index])
        else:
            k = int(np.searchsorted(first, index, side="right")) - 1
            weights = None if not patch_set.weights else patch_set.weights[k][index - first[k]]
            surface = bezier_surface(occ, patch_set.groups[k][index - first[k]], weights)
        face = occ.Face()
        builder.MakeFace(face, surface, tolerance)
        faces.append(face)
    return faces


def _edges(occ, builder, patch_set, topology: BRepTopology, chains: EdgeChains, tolerance: float) -> list:
    """One TopoDS_Edge per chain: its B-spline curve over [0, k], start vertex FORWARD, end vertex REVERSED.

    Vertices are made only where chains end (the topology vertices inside chains disappear).
    """
    vertices = {}
    for v in np.unique(chains.chain_vertices).tolist():
        vertices[v] = occ.Vertex()
        builder.MakeVertex(vertices[v], occ.Pnt(*topology.vertex_points[v].tolist()), tolerance)
    curves, weights = edge_curves(patch_set, topology)
    edges = []
    for c, (start, end) in enumerate(chains.chain_vertices.tolist()):
        run = chains.edges(c)
        degree, poles, pole_weights, _, _ = chain_curve(chains.chain_edges[run], chains.chain_forward[run], curves, weights)
        knots, multiplicities = knot_arrays(occ, run.stop - run.start, degree)
        if pole_weights is None:
            curve = occ.BSplineCurve(occ_poles(occ, poles), knots, multiplicities, degree)
        else:
            curve = occ.BSplineCurve(occ_poles(occ, poles), occ_reals(occ, pole_weights), knots, multiplicities, degree)
        edge = occ.Edge()
        builder.MakeEdge(edge, curve, tolerance)
        builder.Add(edge, vertices[start].Oriented(occ.FORWARD))
        builder.Add(edge, vertices[end].Oriented(occ.REVERSED))
        edges.append(edge)
    return edges


def _pcurves(occ, builder, chains: EdgeChains, faces: list, edges: list, tolerance: float) -> None:
    """Every chain's pcurve on each face that uses it (two on a face that uses it twice: a seam), then its flags.

    A use's pcurve is the straight segment of the face's domain from the (u, v)
    of the chain's start to that of its end (``chains.loop_uv``, turned for a
    use against the chain), k unit steps along u or v for a chain of k edges,
    run at unit speed: the chain's own parameter t in [0, k].
    """
    uv, forward = chains.loop_uv, chains.loop_forward
    start = np.where(forward[:, None], uv[:, 0], uv[:, 1])  # (M, 2): the chain's start in each use
    end = np.where(forward[:, None], uv[:, 1], uv[:, 0])
    length = np.diff(chains.chain_start)[chains.loop_chain]  # (M,) edges in the chain
    if not np.array_equal(np.abs(end - start).sum(axis=1), length) or np.any(np.all(end != start, axis=1)):
        raise ValueError("brep topology: a chain's pcurve is not as many unit steps along u or v as it has edges")
    face_of = np.repeat(np.arange(len(faces)), np.diff(chains.loop_start))
    order = np.lexsort((~forward, chains.loop_chain, face_of))  # by face and chain, FORWARD use first
    key = face_of[order] * chains.n_chains + chains.loop_chain[order]
    runs = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    lines = [_segment(occ, p, q, k) for p, q, k in zip(start.tolist(), end.tolist(), length.tolist())]
    for a, b in zip(runs.tolist(), np.r_[runs[1:], order.size].tolist()):
        uses = order[a:b].tolist()
        edge, face = edges[int(chains.loop_chain[uses[0]])], faces[int(face_of[uses[0]])]
        if len(uses) == 1:
            builder.UpdateEdge(edge, lines[uses[0]], face, tolerance)
        elif len(uses) == 2 and forward[uses[0]] and not forward[uses[1]]:
            builder.UpdateEdge(edge, lines[uses[0]], lines[uses[1]], face, tolerance)  # a seam: FORWARD, REVERSED
        else:
            raise ValueError(f"brep topology: face {int(face_of[uses[0]])} uses chain {int(chains.loop_chain[uses[0]])} "
                             f"{len(uses)} times, not once or as a seam (once each way)")
    for edge, k in zip(edges, np.diff(chains.chain_start).tolist()):
        builder.Range(edge, 0.0, float(k))  # the 3D curve and every pcurve
        builder.SameRange(edge, True)
        builder.SameParameter(edge, True)


def _segment(occ, start: list, end: list, length: int):
    """The pcurve from ``start`` to ``end`` (2 floats each) over [0, length]: a ``Geom2d_BSplineCurve`` of degree 1.

    Not an unbounded ``Geom2d_Line``: Open CASCADE's STEP reader projects each
    vertex onto its pcurve over the whole of an unbounded one, across every span
    of a large piece (spot: 48 s to read instead of 12 s, before chains).
    """
    poles = occ.Array1OfPnt2d(1, 2)
    poles.SetValue(1, occ.Pnt2d(*start))
    poles.SetValue(2, occ.Pnt2d(*end))
    key = ("segment", length)  # knots 0, length with multiplicities 2, 2: two poles, parameter = arc length
    if key not in _KNOT_ARRAYS:
        _KNOT_ARRAYS[key] = (occ_reals(occ, np.array([0.0, length])), occ_integers(occ, np.array([2, 2])))
    return occ.BSpline2d(poles, *_KNOT_ARRAYS[key], 1)


def knot_arrays(occ, spans: int, degree: int):
    """Open CASCADE arrays of the knots 0, 1, ..., spans and multiplicities degree + 1, degree, ..., degree + 1.

    Made once per (spans, degree) and shared (``_KNOT_ARRAYS``): the curve constructors copy them.
    """
    key = (spans, degree)
    if key not in _KNOT_ARRAYS:
        multiplicities = np.full(spans + 1, degree)
        multiplicities[[0, -1]] = degree + 1
        _KNOT_ARRAYS[key] = (occ_reals(occ, np.arange(spans + 1, dtype=np.float64)), occ_integers(occ, multiplicities))
    return _KNOT_ARRAYS[key]


def _wires(occ, builder, chains: EdgeChains, faces: list, edges: list) -> None:
    """Each face's one closed wire: its loop's chains in order, FORWARD where the loop runs along the chain."""
    orientation = [occ.REVERSED, occ.FORWARD]
    forward = chains.loop_forward.tolist()
    loop_chain = chains.loop_chain.tolist()
    for f, face in enumerate(faces):
        wire = occ.Wire()
        builder.MakeWire(wire)
        for k in range(int(chains.loop_start[f]), int(chains.loop_start[f + 1])):
            builder.Add(wire, edges[loop_chain[k]].Oriented(orientation[forward[k]]))
        wire.Closed(True)
        builder.Add(face, wire)


def _assemble(occ, builder, faces: list, component: np.ndarray, closed: np.ndarray, inward: np.ndarray):
    """One shell per component (a solid where closed, turned where its normals point inwards); one compound of
    them when there are several."""
    shells = [occ.Shell() for _ in closed]
    for shell in shells:
        builder.MakeShell(shell)
    for f, face in zip(component.tolist(), faces):
        builder.Add(shells[f], face)
    parts = []
    for shell, is_closed, is_inward in zip(shells, closed.tolist(), inward.tolist()):
        if not is_closed:
            parts.append(shell)
            continue
        shell.Closed(True)
        solid = occ.Solid()
        builder.MakeSolid(solid)
        builder.Add(solid, shell.Reversed() if is_inward else shell)
        parts.append(solid)
    if len(parts) == 1:
        return parts[0]
    compound = occ.Compound()
    builder.MakeCompound(compound)
    for part in parts:
        builder.Add(compound, part)
    return compound


__all__ = ["BRepShape", "brep_shape", "brep_tolerance", "occ_classes", "occ_poles", "occ_reals", "bezier_surface",
           "bspline_surface", "RELATIVE_TOLERANCE"]
