"""Patch files in STEP (``.step`` / ``.stp``, AP214) through Open CASCADE (optional extra ``c1surf[cad]``).

Every patch becomes a face on an exact Bezier surface (``Geom_BezierSurface``,
rational with the patch weights when the surface has them, written as a
B-spline surface); every merged piece (the default; ``--no-merge`` writes
patches) a face on its B-spline surface (``Geom_BSplineSurface``), in place
of the patches it stands for. The faces' shared edges, vertices and shells
come from c1surf's own adjacency (``brep.step_brep``), not from a sewing by
tolerance: each closed component of the surface is one solid, each open one
a shell. The header's time stamp is fixed, so the output is reproducible.
Every real is written with 17 significant digits (``_write_step_text``), so the
doubles come back.

Reading (``read_patch_set_step``, ``c1surf check`` / ``measure`` / ``diff`` /
``tessellate``) takes every face back: a Bezier span is a patch of its
degree, a merged B-spline piece a ``PatchSet.merged`` entry with its patches
cut out again (as the IGES reader does), a reversed face has u and v
swapped; other surfaces and trimmed faces are refused with one line.
"""
from __future__ import annotations

import mmap
import os
import re

import numpy as np

from ...console import quiet_stdout
from ...evaluation.merge import MergedPiece
from ...evaluation.patch_set import PatchSet
from ..errors import MeshInputError
from ..finite import refuse_non_finite_patch_set
from .brep.step_brep import brep_shape, occ_classes
from .merged import cad_patch_set, is_piece_knots, piece_patches

_FACE_ENTITY = re.compile(rb"=\s*(?:ADVANCED_FACE|FACE_SURFACE)\s*\(")
_READ_HINT = "reading STEP needs Open CASCADE: pip install 'c1surf[cad]' (cadquery-ocp)"


def write_patch_set_step(path, patch_set, *, file_name: str | None = None, strips: bool = True,
                         **_options) -> None:
    """Write ``patch_set`` as STEP AP214: one solid per closed component, one shell per open one.

    The B-rep comes from c1surf's own topology (``brep.step_brep.brep_shape``):
    shared patch sides are shared edges, nothing is sewn. Weights make rational
    faces; merged pieces are written as B-spline faces in place of their
    patches; ``strips``: cut into strips one span wide first (``merged.cad_patch_set``, ``convert
    --cad-pieces`` turns it off). Other formats' options (IGES units, ...) do not apply.
    """
    points = np.concatenate([np.asarray(g, dtype=np.float64)[..., :3].reshape(-1, 3) for g in patch_set.groups if len(g)]
                            + [np.zeros((0, 3))])
    _check_range(path, points)
    refuse_non_finite_patch_set(patch_set, path)
    if strips:  # Open CASCADE's default mass properties exact (io.patches.merged.cad_patch_set)
        patch_set = cad_patch_set(patch_set)
    write_step_shape(path, brep_shape(patch_set).shape, file_name or os.path.basename(os.fspath(path)))


def write_step_shape(path, shape, name: str) -> None:
    """Write an Open CASCADE shape as STEP AP214 with full precision and a reproducible header named ``name``."""
    occ_classes()  # or an OutputError saying what to install
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TCollection import TCollection_HAsciiString

    from ..errors import OutputError

    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    with quiet_stdout():  # Open CASCADE prints transfer statistics on stdout
        writer = STEPControl_Writer()
        if writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone:
            raise OutputError(path, "Open CASCADE could not translate the surface to STEP")
        del shape  # the caller's B-rep may go now: the STEP model holds what is written
        header = APIHeaderSection_MakeHeader(writer.Model())
        header.SetName(TCollection_HAsciiString(name))
        header.SetTimeStamp(TCollection_HAsciiString("1970-01-01T00:00:00"))
        header.SetOriginatingSystem(TCollection_HAsciiString("c1surf"))
        with open(path, "wb") as f:
            written = _write_step_text(writer, f)
        del writer, header
    if not written:
        raise OutputError(path, "Open CASCADE could not write the STEP file")
    _fix_header(path, name)


def _check_range(path, points: np.ndarray) -> None:
    """Refuse coordinates that are not finite or of magnitude 1e100 and more (a 3-digit exponent overflows Open CASCADE's number buffer)."""
    if points.size and not np.abs(points).max() < 1e100:  # also catches nan
        from ..errors import OutputError

        raise OutputError(path, "STEP output needs finite coordinates below 1e100 in magnitude")


def _write_step_text(writer, stream) -> bool:
    """Write the STEP file of ``writer``'s model to the binary ``stream``, every real with 17 significant digits.

    ``STEPControl_Writer.Write`` prints reals with 12 digits; this does what it
    does (``StepSelect_WorkLibrary::WriteFile``: a ``StepData_StepWriter`` on the
    model, ``SendModel``, ``Print``) with the float format ``%.16E``, so every
    double reads back to the same bits. Magnitudes below 1e-99 take ``%.15E``:
    their 3-digit exponent would not fit Open CASCADE's 24-character buffer.
    Printed straight into the file (not into memory first): spot's 150 MB of text is never held.
    """
    from OCP.StepData import StepData_StepWriter

    step_writer = StepData_StepWriter(writer.Model())
    floats = step_writer.FloatWriter()
    floats.SetFormat("%.16E")  # resets the range format and the zero suppression (which cuts long numbers)
    floats.SetFormatForRange("%.15E", 0.0, 1e-99)
    step_writer.SendModel(writer.WS().Protocol())
    return bool(step_writer.Print(stream))


# ----------------------------------------------------------------------------
# reading


def read_patch_set_step(path) -> PatchSet:
    """Read the faces of a STEP file as a PatchSet (``c1surf check``, ``measure``, ``diff``, ``tessellate``).

    Every face must be untrimmed (its parameter bounds those of its surface,
    one wire) on a Bezier surface or a B-spline surface that is one Bezier
    span (a patch of its degree) or a c1surf merged piece (degree (2, 2),
    knots 0 0 0 1 ... m m m: a ``PatchSet.merged`` entry, its patches cut out
    again into the biquadratic group, as the IGES reader does). A reversed
    face (``TopAbs_REVERSED``) has its u and v swapped, so every normal
    ``x_u x x_v`` points as the face's. Unequal weights make ``PatchSet.weights``.

    Returns
    -------
    PatchSet with groups ordered by degree: biquadratic (3, 3, 3), then
    bicubic (4, 4, 3), then any other degree; no adjacency or sources
    (``PatchSet.welding()`` finds the adjacency from the geometry)

    Raises
    ------
    MeshInputError
        one line: no Open CASCADE, no such file, not STEP, no faces, or a face
        c1surf does not read (other surface types, trimmed faces, other B-splines)
    """
    by_shape: dict = {(3, 3): ([], [])}  # (du + 1, dv + 1) -> (patches, weights), in face order
    pieces = []
    for number, (knots_u, knots_v, weights, points) in enumerate(_outward_nets(list(_face_nets(path))), 1):
        if _single_span(knots_u, points.shape[0]) and _single_span(knots_v, points.shape[1]):
            patches, patch_weights = by_shape.setdefault(points.shape[:2], ([], []))
            patches.append(points)
            patch_weights.append(weights)
            continue
        if not _is_piece(knots_u, knots_v, points):
            raise MeshInputError(str(path), f"face {number}: the B-spline surface has interior knots and is not a merged "
                                 "c1surf surface (degree (2, 2), knots 0 0 0 1 ... m m m): c1surf reads only such "
                                 "surfaces and single Bezier patches")
        quad, quad_weights = by_shape[(3, 3)]
        m, n = points.shape[0] - 2, points.shape[1] - 2
        piece = MergedPiece(points, weights, knots_u, knots_v, len(quad) + np.arange(m * n).reshape(m, n),
                            np.zeros((m, n), dtype=np.int64))
        cut, cut_weights = piece_patches(piece)
        pieces.append(piece)
        quad.extend(cut)
        quad_weights.extend(cut_weights)
    return _patch_set(path, by_shape, pieces)


def _is_piece(knots_u: np.ndarray, knots_v: np.ndarray, points: np.ndarray) -> bool:
    """Whether knots and net (nu, nv, 3) are those of a c1surf merged piece (degree (2, 2), knots 0 0 0 1 ... m m m)."""
    return (points.shape[0] >= 3 and is_piece_knots(knots_u) and is_piece_knots(knots_v)
            and knots_u.size == points.shape[0] + 3 and knots_v.size == points.shape[1] + 3)


def _outward_nets(faces: list) -> list:
    """The faces' (knots_u, knots_v, weights, points) with every solid turned outwards by c1surf's own volume.

    ``faces``: (knots_u, knots_v, weights (nu, nv), points (nu, nv, 3), solid) per face, ``solid`` the index of
    the solid it bounds (-1: none). Open CASCADE's STEP reader heals every solid
    (``ShapeFix_Solid::SolidFromShell``) and reverses its shell where its ray
    classifier (``BRepClass3d_SolidClassifier::PerformInfinitePoint``) finds the
    point at infinity inside; that classifier errs on some closed B-reps (boot
    fitted at 300 faces, written in strips: every face came back transposed).
    Here a solid whose faces, as read, enclose a negative volume (Gauss rules
    exact for polynomial nets, :func:`_face_volumes`) has every face's u and v
    swapped back, so each solid's normals point out as the file's shell says.
    """
    solid = np.array([f[4] for f in faces], dtype=np.int64)
    if not np.any(solid >= 0):
        return [f[:4] for f in faces]
    volume = np.bincount(solid[solid >= 0], _face_volumes(faces)[solid >= 0])
    flipped = np.r_[volume < 0, False][solid].tolist()  # solid -1 is the appended False
    return [(kv, ku, w.T.copy(), p.transpose(1, 0, 2).copy()) if flip else (ku, kv, w, p)
            for (ku, kv, w, p, _), flip in zip(faces, flipped)]


def _face_volumes(faces: list) -> np.ndarray:
    """(F,) float: each face's share of its solid's signed volume, 1/3 of the integral of (x - o) . (x_u x x_v)
    over its Bezier spans (a B-spline face cut at its knots), o the centre of the nets' bounding box."""
    from ...evaluation.measure import gauss_rule, patch_frames

    nets = {}  # (nu, nv) -> (face numbers, nets, weights)
    for k, (knots_u, knots_v, weights, points, _) in enumerate(faces):
        if _single_span(knots_u, points.shape[0]) and _single_span(knots_v, points.shape[1]):
            cut, cut_weights = [points], [weights]
        elif _is_piece(knots_u, knots_v, points):
            m, n = points.shape[0] - 2, points.shape[1] - 2
            numbers, turns = np.arange(m * n).reshape(m, n), np.zeros((m, n), dtype=np.int64)
            cut, cut_weights = piece_patches(MergedPiece(points, weights, knots_u, knots_v, numbers, turns))
        else:
            continue  # refused with its own line afterwards
        entry = nets.setdefault(np.shape(cut[0])[:2], ([], [], []))
        entry[0].extend([k] * len(cut))
        entry[1].extend(cut)
        entry[2].extend(cut_weights)
    flat = np.concatenate([np.reshape(f[3], (-1, 3)) for f in faces])
    origin = 0.5 * (flat.min(axis=0) + flat.max(axis=0))
    volume = np.zeros(len(faces))
    for (nu, nv), (owner, points, weights) in nets.items():
        u, w = gauss_rule((3 * (max(nu, nv) - 1) + 1) // 2)
        for a in range(0, len(owner), _VOLUME_CHUNK):  # chunks of patches: bounded memory
            chunk = slice(a, a + _VOLUME_CHUNK)
            x, xu, xv = patch_frames(np.stack(points[chunk]), np.stack(weights[chunk]), u, u)
            flux = np.einsum("pabi,pabi->pab", x - origin, np.cross(xu, xv))
            volume += np.bincount(owner[chunk], np.einsum("pab,a,b->p", flux, w, w) / 3.0,
                                  minlength=len(faces))
    return volume


_VOLUME_CHUNK = 1 << 14  # patches per Gauss evaluation in _face_volumes


def _single_span(knots: np.ndarray, n_poles: int) -> bool:
    """Clamped knots of one Bezier span over ``n_poles`` poles: n_poles equal values, then n_poles equal values."""
    return knots.size == 2 * n_poles and np.all(knots[:n_poles] == knots[0]) and np.all(knots[n_poles:] == knots[-1])


def _patch_set(path, by_shape: dict, pieces: list) -> PatchSet:
    """The PatchSet of the patches by shape (biquadratic first, then by degree) and the merged pieces."""
    shapes = [(3, 3)] + sorted(k for k in by_shape if k != (3, 3) and by_shape[k][0])
    groups = [np.stack(by_shape[k][0]) for k in shapes if by_shape[k][0]]
    weights = [np.stack(by_shape[k][1]) for k in shapes if by_shape[k][0]]
    if not groups:
        raise MeshInputError(str(path), "the STEP file holds no faces: c1surf reads B-spline and Bezier faces")
    rational = any(not np.all(w == w.flat[0]) for w in weights)
    if not rational:
        pieces = [MergedPiece(p.points, None, p.knots_u, p.knots_v, p.patches, p.rotation) for p in pieces]
    header = {"format": "step", "input": {"path": str(path)}, "counts": {"patches": int(sum(len(g) for g in groups))},
              "ordered": False}  # faces come in shell order, not in patch order: diff pairs them by their centres
    return PatchSet(groups, None, None, None, header, weights if rational else None, pieces)


def _face_nets(path):
    """(knots_u, knots_v, weights (nu, nv), points (nu, nv, 3), solid) of every face of a STEP file: the faces of
    each solid in explorer order (``solid`` its index), then those in no solid (``solid`` -1).

    Knots are the full sequences (each value repeated by its multiplicity);
    a reversed face comes with u and v swapped.
    """
    shape, reader = _read_shape(path)
    transfer = reader.WS().TransferReader()
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopoDS import TopoDS

    to_face = TopoDS.Face_s if hasattr(TopoDS, "Face_s") else TopoDS.Face
    number = 0
    for solid, explorer in _face_explorers(shape):
        while explorer.More():
            number += 1
            face = to_face(explorer.Current())
            knots_u, knots_v, weights, points = _surface_net(path, number, BRep_Tool.Surface_s(face),
                                                             lambda: _file_net(transfer, face))
            _check_untrimmed(path, number, face, knots_u, knots_v)
            if face.Orientation() == TopAbs_REVERSED:
                knots_u, knots_v, weights, points = knots_v, knots_u, weights.T, points.transpose(1, 0, 2)
            yield knots_u, knots_v, np.ascontiguousarray(weights), np.ascontiguousarray(points), solid
            explorer.Next()
    declared = _declared_faces(path)
    if number < declared:  # Open CASCADE drops what it cannot translate, without failing
        raise MeshInputError(str(path), f"Open CASCADE read only {number} of the file's {declared} faces: some face or "
                             "its surface is damaged; c1surf refuses an incomplete surface (re-export the file)")


def _face_explorers(shape):
    """(solid index, face explorer) of every solid of ``shape``, then (-1, explorer of the faces in no solid)."""
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer

    solids = TopExp_Explorer(shape, TopAbs_SOLID)
    k = 0
    while solids.More():
        yield k, TopExp_Explorer(solids.Current(), TopAbs_FACE)
        k += 1
        solids.Next()
    yield -1, TopExp_Explorer(shape, TopAbs_FACE, TopAbs_SOLID)


def _read_shape(path):
    """The shape of a STEP file (Open CASCADE's ``STEPControl_Reader``, every root transferred) and the
    reader (its transfer reader knows which entity each face came from)."""
    try:
        import OCP  # noqa: F401
    except ImportError:
        raise MeshInputError(str(path), _READ_HINT) from None
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_Reader

    if not os.path.exists(path):
        raise MeshInputError(str(path), "no such file")
    if os.path.isdir(path):
        raise MeshInputError(str(path), "is a directory, not a patch file")
    with quiet_stdout():  # Open CASCADE prints its load statistics on stdout
        reader = STEPControl_Reader()
        if reader.ReadFile(os.fspath(path)) != IFSelect_RetDone:
            raise MeshInputError(str(path), "not a STEP file Open CASCADE can read")
        reader.TransferRoots()
        _refuse_failed_faces(path, reader)
        return reader.OneShape(), reader


def _refuse_failed_faces(path, reader) -> None:
    """Refuse, naming it, the first surface or face entity Open CASCADE failed to translate (it would drop the
    face and go on: a corrupt surface, such as a degree of 1e9, would leave a surface with a hole)."""
    checks = reader.WS().TransferReader().TransientProcess().CheckList(False)
    checks.Start()
    while checks.More():
        check, number = checks.Value(), checks.Number()
        entity = check.Entity()
        kind = entity.DynamicType().Name() if entity is not None else ""
        if check.NbFails() and kind.startswith(("StepGeom_", "StepShape_")) and ("Surface" in kind or "Face" in kind):
            raise MeshInputError(str(path), f"entity #{number} ({kind.split('_', 1)[1]}) cannot be read: "
                                 f"{check.CFail(1).strip()}; its face would be missing, so c1surf refuses the file "
                                 "(re-export it)")
        checks.Next()


def _declared_faces(path) -> int:
    """How many ADVANCED_FACE and FACE_SURFACE entities the file's text declares (a regular expression over
    the memory-mapped file: no copy)."""
    with open(path, "rb") as f:
        if os.fstat(f.fileno()).st_size == 0:
            return 0
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as text:
            return sum(1 for _ in _FACE_ENTITY.finditer(text))


def _surface_net(path, number: int, surface, file_net=lambda: None):
    """Full knot sequences, weights (nu, nv) and control points (nu, nv, 3) of a Bezier or B-spline surface.

    A periodic B-spline surface comes in its clamped form (:func:`_clamped_seam`), with the file's own net
    where ``file_net()`` (the face's entity's (points, weights), or None) agrees with it (:func:`_closing_rows`).
    """
    from OCP.Geom import Geom_BezierSurface, Geom_BSplineSurface

    if isinstance(surface, Geom_BezierSurface):
        du, dv = surface.UDegree(), surface.VDegree()
        knots_u, knots_v = np.repeat([0.0, 1.0], du + 1), np.repeat([0.0, 1.0], dv + 1)
    elif not isinstance(surface, Geom_BSplineSurface):
        raise MeshInputError(str(path), f"face {number} is on a {type(surface).__name__} surface: c1surf reads only "
                             "Bezier and B-spline faces (a single Bezier span or a merged c1surf piece)")
    nu, nv = surface.NbUPoles(), surface.NbVPoles()
    poles = [[surface.Pole(i, j) for j in range(1, nv + 1)] for i in range(1, nu + 1)]
    points = np.array([[(p.X(), p.Y(), p.Z()) for p in row] for row in poles], dtype=np.float64).reshape(nu, nv, 3)
    rational = surface.IsURational() or surface.IsVRational()
    weights = np.array([[surface.Weight(i, j) if rational else 1.0 for j in range(1, nv + 1)] for i in range(1, nu + 1)])
    if isinstance(surface, Geom_BSplineSurface):
        sides = []
        for axis, (name, periodic, degree, count, knot, mult) in enumerate((
                ("u", surface.IsUPeriodic(), surface.UDegree(), surface.NbUKnots(), surface.UKnot, surface.UMultiplicity),
                ("v", surface.IsVPeriodic(), surface.VDegree(), surface.NbVKnots(), surface.VKnot, surface.VMultiplicity))):
            values = np.array([knot(i) for i in range(1, count + 1)], dtype=np.float64)
            mults = np.array([mult(i) for i in range(1, count + 1)], dtype=np.int64)
            if periodic:
                mults, points, weights = _clamped_seam(path, number, name, degree, mults, points, weights, axis)
            sides.append(np.repeat(values, mults))
        knots_u, knots_v = sides
        if surface.IsUPeriodic() or surface.IsVPeriodic():
            points, weights = _closing_rows(points, weights, (nu, nv), file_net())
    return np.asarray(knots_u, np.float64), np.asarray(knots_v, np.float64), weights, points


def _clamped_seam(path, number: int, name: str, degree: int, mults: np.ndarray, points: np.ndarray,
                  weights: np.ndarray, axis: int):
    """The clamped form along ``axis`` of a B-spline surface periodic along it, whose seam is a knot of
    multiplicity = degree: the end multiplicities raised to degree + 1 and the first row of the net
    (``points`` (nu, nv, 3), ``weights`` (nu, nv)) copied after the last; the same surface over the period.

    Open CASCADE's STEP reader makes every B-spline surface that closes on
    itself within its precision periodic, whatever the file's ``u_closed`` /
    ``v_closed`` flags say (``ShapeCustom_Surface::ConvertToPeriodic``: "Surface
    forced to be periodic"): a clamped net whose first and last rows coincide
    loses its last row and its end knots drop to multiplicity = degree. Each
    basis function over the period is then the clamped one; the copied row is the
    surface Open CASCADE reads, and :func:`_closing_rows` puts the file's own in
    its place where it can. A knot vector periodic through the seam
    (multiplicity below the degree: the surface smooth across it) is refused
    with its own line: no c1surf surface is one.

    Returns
    -------
    mults : (k,) int, points : (nu', nv', 3) float, weights : (nu', nv') float
    """
    if mults[0] != degree or mults[-1] != degree:
        raise MeshInputError(str(path), f"face {number} is on a B-spline surface periodic in {name} through its seam "
                             f"(seam knot multiplicity {int(mults[0])}, degree {degree}): c1surf reads clamped B-spline "
                             "faces (a single Bezier span or a merged c1surf piece), closed ones too, not periodic ones")
    mults = mults.copy()
    mults[[0, -1]] += 1
    first = (slice(None),) * axis + (slice(0, 1),)
    return mults, np.concatenate([points, points[first]], axis=axis), np.concatenate([weights, weights[first]], axis=axis)


def _closing_rows(points: np.ndarray, weights: np.ndarray, kept: tuple, file_net):
    """The file's own net in place of ``points`` (nu', nv', 3) and ``weights`` (nu', nv'), the clamped form of a
    periodic surface whose first ``kept`` (nu, nv) rows and columns Open CASCADE kept, when the file's net
    ``file_net`` ((nu', nv', 3), (nu', nv')) holds them bit for bit: the rows Open CASCADE dropped (equal to the
    first within its 1e-7: round-off in c1surf's own files) then come back as written. Otherwise (another length
    unit, no such entity) the copies of the first rows stand, the surface Open CASCADE reads."""
    if file_net is None:
        return points, weights
    file_points, file_weights = file_net
    nu, nv = kept
    if (file_points.shape == points.shape and np.array_equal(file_points[:nu, :nv], points[:nu, :nv])
            and np.array_equal(file_weights[:nu, :nv], weights[:nu, :nv])):
        return file_points, file_weights
    return points, weights


def _file_net(transfer, face):
    """(points (ni, nj, 3), weights (ni, nj)) of the B-spline surface entity ``face`` was read from, as the file
    writes them, or None (no such entity). Only for the few faces that close on themselves: Python calls per point."""
    from OCP.StepGeom import StepGeom_BSplineSurface, StepGeom_BSplineSurfaceWithKnotsAndRationalBSplineSurface

    entity = transfer.EntityFromShapeResult(face, 1)
    geometry = entity.FaceGeometry() if entity is not None and hasattr(entity, "FaceGeometry") else None
    if not isinstance(geometry, StepGeom_BSplineSurface):
        return None
    ni, nj = geometry.NbControlPointsListI(), geometry.NbControlPointsListJ()
    points = np.array([[[geometry.ControlPointsListValue(i, j).CoordinatesValue(k) for k in (1, 2, 3)]
                        for j in range(1, nj + 1)] for i in range(1, ni + 1)], dtype=np.float64).reshape(ni, nj, 3)
    weights = np.ones((ni, nj))
    if isinstance(geometry, StepGeom_BSplineSurfaceWithKnotsAndRationalBSplineSurface):
        weights = np.array([[geometry.WeightsDataValue(i, j) for j in range(1, nj + 1)] for i in range(1, ni + 1)],
                           dtype=np.float64).reshape(ni, nj)
    return points, weights


def _check_untrimmed(path, number: int, face, knots_u: np.ndarray, knots_v: np.ndarray) -> None:
    """Refuse a face that covers less than its surface: parameter bounds inside the knot range, or inner wires."""
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_WIRE
    from OCP.TopExp import TopExp_Explorer

    full = np.array([knots_u[0], knots_u[-1], knots_v[0], knots_v[-1]])
    bounds = np.array(BRepTools.UVBounds_s(face))
    span = np.repeat([knots_u[-1] - knots_u[0], knots_v[-1] - knots_v[0]], 2)
    wires, explorer = 0, TopExp_Explorer(face, TopAbs_WIRE)
    while explorer.More():
        wires += 1
        explorer.Next()
    if wires != 1 or not np.all(np.abs(bounds - full) <= 1e-9 * span):
        shown = ", ".join(f"{x:.6g}" for x in bounds)
        raise MeshInputError(str(path), f"face {number} is trimmed (parameter bounds {shown}, {wires} wire(s)): c1surf "
                             "reads only untrimmed faces, each on the whole of its surface")


_HEAD_BYTES = 1 << 16  # the header and the first entities (the PRODUCT) of a STEP file


def _fix_header(path, name: str) -> None:
    """Pin FILE_NAME's name and time stamp and the product name.

    Open CASCADE may put the clock and the temporary file name in the header,
    and numbers product names with a per-process counter; neither belongs in
    a reproducible file. Both are near the top: the first 64 KiB are fixed
    and the rest copied after them by blocks (never the whole file in memory).
    """
    import shutil

    with open(path, "rb") as f:
        head = f.read(_HEAD_BYTES)
    text = head.decode("latin-1")
    quoted = _step_string(name)
    fixed = re.sub(r"FILE_NAME\('(?:[^']|'')*','[^']*'", lambda m: f"FILE_NAME({quoted},'1970-01-01T00:00:00'", text, count=1)
    product = _step_string(os.path.splitext(name)[0] or "c1surf")
    fixed = re.sub(r"= PRODUCT\('(?:[^']|'')*',\s*'(?:[^']|'')*'", lambda m: f"= PRODUCT({product},{product}", fixed, count=1)
    if fixed == text:
        return
    fixed_path = os.fspath(path) + ".h"
    try:
        with open(path, "rb") as source, open(fixed_path, "wb") as target:
            target.write(fixed.encode("latin-1"))
            source.seek(len(head))
            shutil.copyfileobj(source, target, 1 << 20)
        os.replace(fixed_path, path)
    finally:
        if os.path.exists(fixed_path):
            os.remove(fixed_path)


def _step_string(text: str) -> str:
    """A STEP string literal (ASCII, apostrophes doubled)."""
    text = text.encode("ascii", "replace").decode("ascii").replace("'", "''")
    return f"'{text}'"


__all__ = ["write_patch_set_step", "read_patch_set_step", "write_step_shape"]
