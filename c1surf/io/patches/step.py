"""Patch files in STEP (``.step`` / ``.stp``, AP214) through Open CASCADE (optional extra ``c1surf[cad]``).

Every patch becomes a face on an exact Bezier surface (``Geom_BezierSurface``,
rational with the patch weights when the surface has them, written as a
B-spline surface); every merged piece (``convert --merge``) a face on its
B-spline surface (``Geom_BSplineSurface``), in place of the patches it
stands for. The faces are sewn (``BRepBuilderAPI_Sewing``, tolerance 1e-7
of the bounding-box diagonal); where that gives one closed shell (closed
input) the file holds the solid it bounds, otherwise the sewn shell(s). The
header's time stamp is fixed, so the output is reproducible.
"""
from __future__ import annotations

import contextlib
import os
import re
from types import SimpleNamespace

import numpy as np

from .merged import uncovered_groups

SEWING_TOLERANCE = 1e-7  # relative to the bounding-box diagonal of the control points
_CAD_HINT = "STEP output needs Open CASCADE: pip install 'c1surf[cad]' (cadquery-ocp)"


def _ocp() -> SimpleNamespace:
    """The Open CASCADE classes the writer uses (cadquery-ocp 7 or 8), or an OutputError saying what to install."""
    try:
        import OCP  # noqa: F401
    except ImportError:
        from ..errors import OutputError

        raise OutputError("STEP", _CAD_HINT) from None
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.Geom import Geom_BezierSurface, Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    try:  # cadquery-ocp 7.x
        from OCP.TColgp import TColgp_Array2OfPnt as Array2OfPnt
        from OCP.TColStd import TColStd_Array1OfInteger as Array1OfInt
        from OCP.TColStd import TColStd_Array1OfReal as Array1OfReal
        from OCP.TColStd import TColStd_Array2OfReal as Array2OfReal
    except ImportError:  # cadquery-ocp 8: NCollection arrays live in OCP.collections
        from OCP.collections import Array1_double as Array1OfReal
        from OCP.collections import Array1_int as Array1OfInt
        from OCP.collections import Array2_double as Array2OfReal
        from OCP.collections import Array2_gp_Pnt as Array2OfPnt
    return SimpleNamespace(MakeFace=BRepBuilderAPI_MakeFace, MakeSolid=BRepBuilderAPI_MakeSolid,
                           Sewing=BRepBuilderAPI_Sewing, Bezier=Geom_BezierSurface, BSpline=Geom_BSplineSurface, Pnt=gp_Pnt,
                           Array2OfPnt=Array2OfPnt, Array2OfReal=Array2OfReal, Array1OfReal=Array1OfReal,
                           Array1OfInt=Array1OfInt)


def _poles(occ, points: np.ndarray):
    """Control points (nu, nv, 3) as an Open CASCADE array of gp_Pnt (1-based, first index with u)."""
    nu, nv = points.shape[:2]
    poles = occ.Array2OfPnt(1, nu, 1, nv)
    for i, row in enumerate(points.tolist()):
        for j, (x, y, z) in enumerate(row):
            poles.SetValue(i + 1, j + 1, occ.Pnt(x, y, z))
    return poles


def _reals(occ, values: np.ndarray):
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


def bezier_faces(patch_groups, weights=None) -> list:
    """One ``TopoDS_Face`` per patch (in order), on an exact ``Geom_BezierSurface`` over [0,1]^2.

    Parameters
    ----------
    patch_groups : list of (p_k, du+1, dv+1, >= 3) float
    weights : None or a list parallel to ``patch_groups`` of (p_k, du+1, dv+1) float or None each (rational patches)
    """
    occ = _ocp()
    faces = []
    for group, group_weights in zip(patch_groups, weights or [None] * len(patch_groups)):
        group = np.asarray(group, dtype=np.float64)[..., :3]
        for k, points in enumerate(group):
            poles = _poles(occ, points)
            surface = occ.Bezier(poles) if group_weights is None else occ.Bezier(poles, _reals(occ, group_weights[k]))
            faces.append(occ.MakeFace(surface, 1e-7).Face())
    return faces


def bspline_faces(pieces) -> list:
    """One ``TopoDS_Face`` per merged piece, on its clamped ``Geom_BSplineSurface`` of degree (2, 2)."""
    occ = _ocp()
    faces = []
    for piece in pieces:
        knots, multiplicities = [], []
        for values in (piece.knots_u, piece.knots_v):
            distinct, counts = np.unique(values, return_counts=True)
            knots.append(_reals(occ, distinct))
            multiplicities.append(occ.Array1OfInt(1, distinct.size))
            for i, c in enumerate(counts.tolist()):
                multiplicities[-1].SetValue(i + 1, c)
        weights = np.ones(piece.points.shape[:2]) if piece.weights is None else piece.weights
        surface = occ.BSpline(_poles(occ, np.asarray(piece.points)[..., :3]), _reals(occ, np.asarray(weights, np.float64)),
                              knots[0], knots[1], multiplicities[0], multiplicities[1], 2, 2)
        faces.append(occ.MakeFace(surface, 1e-7).Face())
    return faces


def sewn_shape(faces: list, points: np.ndarray, relative_tolerance: float = SEWING_TOLERANCE):
    """Sew ``faces``; return (shape, closed) where closed means one closed shell made solid.

    ``points`` (N, 3): control points whose bounding-box diagonal scales the tolerance.
    """
    occ = _ocp()
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) or 1.0
    sew = occ.Sewing(relative_tolerance * diagonal)
    for face in faces:
        sew.Add(face)
    sew.Perform()
    shape = sew.SewedShape()
    shells = []
    explorer = TopExp_Explorer(shape, TopAbs_SHELL)
    while explorer.More():
        shells.append((TopoDS.Shell_s if hasattr(TopoDS, "Shell_s") else TopoDS.Shell)(explorer.Current()))
        explorer.Next()
    if len(shells) == 1 and sew.NbFreeEdges() == 0 and BRep_Tool.IsClosed_s(shells[0]):
        return occ.MakeSolid(shells[0]).Solid(), True
    return shape, False


def write_patch_set_step(path, patch_set, *, file_name: str | None = None, **_options) -> None:
    """Write ``patch_set`` as STEP AP214: a solid when its faces close up, else the sewn shell(s).

    Weights make rational faces; merged pieces are written as B-spline faces
    in place of their patches. Other formats' options (IGES units, ...) do not apply.
    """
    _ocp()
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TCollection import TCollection_HAsciiString

    from ..errors import OutputError

    faces = bspline_faces(patch_set.merged) + bezier_faces(*uncovered_groups(patch_set))
    points = np.concatenate([np.asarray(g, dtype=np.float64)[..., :3].reshape(-1, 3) for g in patch_set.groups if len(g)])
    _check_range(path, points)
    shape, _ = sewn_shape(faces, points)
    name = file_name or os.path.basename(os.fspath(path))
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    with _quiet_stdout():  # Open CASCADE prints transfer statistics on stdout
        writer = STEPControl_Writer()
        if writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone:
            raise OutputError(path, "Open CASCADE could not translate the surface to STEP")
        header = APIHeaderSection_MakeHeader(writer.Model())
        header.SetName(TCollection_HAsciiString(name))
        header.SetTimeStamp(TCollection_HAsciiString("1970-01-01T00:00:00"))
        header.SetOriginatingSystem(TCollection_HAsciiString("c1surf"))
        text = _step_text(writer)
    if text is None:
        raise OutputError(path, "Open CASCADE could not write the STEP file")
    with open(path, "wb") as f:
        f.write(text)
    _fix_header(path, name)


def _check_range(path, points: np.ndarray) -> None:
    """Refuse coordinates that are not finite or of magnitude 1e100 and more (a 3-digit exponent overflows Open CASCADE's number buffer)."""
    if points.size and not np.abs(points).max() < 1e100:  # also catches nan
        from ..errors import OutputError

        raise OutputError(path, "STEP output needs finite coordinates below 1e100 in magnitude")


def _step_text(writer) -> bytes | None:
    """The STEP file of ``writer``'s model, every real with 17 significant digits (None if Open CASCADE fails).

    ``STEPControl_Writer.Write`` prints reals with 12 digits; this does what it
    does (``StepSelect_WorkLibrary::WriteFile``: a ``StepData_StepWriter`` on the
    model, ``SendModel``, ``Print``) with the float format ``%.16E``, so every
    double reads back to the same bits. Magnitudes below 1e-99 take ``%.15E``:
    their 3-digit exponent would not fit Open CASCADE's 24-character buffer.
    """
    import io

    from OCP.StepData import StepData_StepWriter

    step_writer = StepData_StepWriter(writer.Model())
    floats = step_writer.FloatWriter()
    floats.SetFormat("%.16E")  # resets the range format and the zero suppression (which cuts long numbers)
    floats.SetFormatForRange("%.15E", 0.0, 1e-99)
    step_writer.SendModel(writer.WS().Protocol())
    buffer = io.BytesIO()
    return buffer.getvalue() if step_writer.Print(buffer) else None


@contextlib.contextmanager
def _quiet_stdout():
    """Send file descriptor 1 to /dev/null for the block (C++ output included)."""
    import sys

    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError, AttributeError):
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _fix_header(path, name: str) -> None:
    """Pin FILE_NAME's name and time stamp and the product name.

    Open CASCADE may put the clock and the temporary file name in the header,
    and numbers product names with a per-process counter; neither belongs in
    a reproducible file.
    """
    with open(path, "r", encoding="latin-1", newline="") as f:
        text = f.read()
    quoted = _step_string(name)
    fixed = re.sub(r"FILE_NAME\('(?:[^']|'')*','[^']*'", lambda m: f"FILE_NAME({quoted},'1970-01-01T00:00:00'", text, count=1)
    product = _step_string(os.path.splitext(name)[0] or "c1surf")
    fixed = re.sub(r"= PRODUCT\('(?:[^']|'')*',\s*'(?:[^']|'')*'", lambda m: f"= PRODUCT({product},{product}", fixed, count=1)
    if fixed != text:
        with open(path, "w", encoding="latin-1", newline="") as f:
            f.write(fixed)


def _step_string(text: str) -> str:
    """A STEP string literal (ASCII, apostrophes doubled)."""
    text = text.encode("ascii", "replace").decode("ascii").replace("'", "''")
    return f"'{text}'"


__all__ = ["write_patch_set_step", "bezier_faces", "bspline_faces", "sewn_shape", "SEWING_TOLERANCE"]
