"""The Open CASCADE side of reading STEP: the face nets of a file as plain arrays (issue 42).

Runs in the child process of ``io.contained`` (``face_arrays``, called by ``step.read_patch_set_step``): Open
CASCADE crashes the process on some damaged files, and only this child goes down with it. ``face_nets`` is
the same reading in the calling process (tests that replace ``_read_shape``).
"""
from __future__ import annotations

import mmap
import os
import re

import numpy as np

from ....console import quiet_stdout
from ...errors import MeshInputError

_FACE_ENTITY = re.compile(rb"=\s*(?:ADVANCED_FACE|FACE_SURFACE)\s*\(")
READ_HINT = "reading STEP needs Open CASCADE: pip install 'c1surf[cad]' (cadquery-ocp)"


def face_arrays(path):
    """``face_nets(path)`` packed for the parent: ({"faces": F}, [table (F, 5) int64: knot counts u and v, poles
    nu and nv, solid; knots (sum of both counts,) float; weights (sum nu nv,); points (sum nu nv, 3)])."""
    faces = face_nets(path)
    table = np.array([(ku.size, kv.size, *w.shape, solid) for ku, kv, w, _, solid in faces], np.int64).reshape(-1, 5)
    knots = np.concatenate([np.r_[ku, kv] for ku, kv, *_ in faces] + [np.zeros(0)])
    weights = np.concatenate([w.ravel() for _, _, w, _, _ in faces] + [np.zeros(0)])
    points = np.concatenate([p.reshape(-1, 3) for *_, p, _ in faces] + [np.zeros((0, 3))])
    return {"faces": len(faces)}, [table, knots, weights, points]


def unpack_faces(table: np.ndarray, knots: np.ndarray, weights: np.ndarray, points: np.ndarray) -> list:
    """The list of (knots_u, knots_v, weights (nu, nv), points (nu, nv, 3), solid) ``face_arrays`` packed."""
    faces, k, w = [], 0, 0
    for ku, kv, nu, nv, solid in table.tolist():
        faces.append((knots[k:k + ku], knots[k + ku:k + ku + kv], weights[w:w + nu * nv].reshape(nu, nv),
                      points[w:w + nu * nv].reshape(nu, nv, 3), solid))
        k, w = k + ku + kv, w + nu * nv
    return faces


def refuse_huge_reals(path) -> None:
    """Refuse a STEP file with a real of magnitude 1e50 or more (an exponent of 50 or more), naming its line:
    beyond c1surf's coordinate range (``mesh.points.geometry_checks.MAX_COORDINATE``), and Open CASCADE's reading
    of a surface with a pole at 1e100 runs for minutes. Vectorized over the memory-mapped bytes (``_huge_exponent``:
    30 ms for 10 MB, where a regular expression took 0.5 s)."""
    with open(path, "rb") as f:
        if os.fstat(f.fileno()).st_size == 0:
            return
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as text:
            at = _huge_exponent(np.frombuffer(text, dtype=np.uint8))
            if at is not None:
                start = at
                while start > 0 and text[start - 1:start] in b"+-.0123456789":
                    start -= 1
                end = at + 1
                while end < len(text) and text[end:end + 1] in b"+-0123456789":
                    end += 1
                line = text[:start].count(b"\n") + 1
                number = text[start:end].decode("latin-1").strip()
                raise MeshInputError(str(path), f"the number {number} is beyond 1e50, the largest coordinate c1surf "
                                     "reads: fix the number or scale the model down", line)


def _huge_exponent(b: np.ndarray):
    """The position of the first exponent marker (E or e after a digit or a point) whose exponent is 50 or more
    (two digits from 5, or three digits), or None. ``b``: the file's bytes."""
    padded = np.concatenate([b, np.zeros(4, np.uint8)])
    digit = (padded >= 48) & (padded <= 57)
    marker = np.flatnonzero(((b == 69) | (b == 101)) & np.r_[False, digit[:b.size - 1] | (b[:-1] == 46)])
    if not marker.size:
        return None
    first = marker + 1 + (padded[marker + 1] == 43)  # past an optional "+"
    two_digits = digit[first] & digit[first + 1]
    huge = np.flatnonzero(two_digits & (digit[first + 2] | (padded[first] >= 53)) & (padded[first] >= 49))
    # 50-99, or 100 and more (three digits, the first not 0)
    return int(marker[huge[0]]) if huge.size else None


def face_nets(path) -> list:
    """Every face of a STEP file as (knots_u, knots_v, weights, points, solid) (``_face_nets``), read here."""
    return list(_face_nets(path))


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
        raise MeshInputError(str(path), READ_HINT) from None
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


__all__ = ["READ_HINT", "face_arrays", "face_nets", "refuse_huge_reals", "unpack_faces"]
