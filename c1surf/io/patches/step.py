"""Patch files in STEP (``.step`` / ``.stp``, AP214) through Open CASCADE (optional extra ``c1surf[cad]``).

Every patch becomes a face on an exact Bezier surface (``Geom_BezierSurface``,
written as a B-spline surface). The faces are sewn (``BRepBuilderAPI_Sewing``,
tolerance 1e-7 of the bounding-box diagonal); where that gives one closed
shell (closed input) the file holds the solid it bounds, otherwise the sewn
shell(s). The header's time stamp is fixed, so the output is reproducible.
"""
from __future__ import annotations

import contextlib
import os
import re

import numpy as np

SEWING_TOLERANCE = 1e-7  # relative to the bounding-box diagonal of the control points
_CAD_HINT = "STEP output needs Open CASCADE: pip install 'c1surf[cad]' (cadquery-ocp)"


def _ocp():
    try:
        import OCP  # noqa: F401
    except ImportError:
        from ..errors import OutputError

        raise OutputError("STEP", _CAD_HINT) from None
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.Geom import Geom_BezierSurface
    from OCP.gp import gp_Pnt

    try:  # cadquery-ocp 7.x
        from OCP.TColgp import TColgp_Array2OfPnt as Array2OfPnt
    except ImportError:  # cadquery-ocp 8: NCollection arrays live in OCP.collections
        from OCP.collections import Array2_gp_Pnt as Array2OfPnt
    return BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing, Geom_BezierSurface, gp_Pnt, Array2OfPnt


def bezier_faces(patch_groups) -> list:
    """One ``TopoDS_Face`` per patch (in order), on an exact ``Geom_BezierSurface`` over [0,1]^2."""
    MakeFace, _, _, BezierSurface, Pnt, Array2OfPnt = _ocp()
    faces = []
    for group in patch_groups:
        group = np.asarray(group, dtype=np.float64)
        nu, nv = group.shape[1], group.shape[2]
        for points in group[..., :3].tolist():
            poles = Array2OfPnt(1, nu, 1, nv)
            for i in range(nu):
                row = points[i]
                for j in range(nv):
                    x, y, z = row[j]
                    poles.SetValue(i + 1, j + 1, Pnt(x, y, z))
            faces.append(MakeFace(BezierSurface(poles), 1e-7).Face())
    return faces


def sewn_shape(patch_groups, relative_tolerance: float = SEWING_TOLERANCE):
    """Sew the patches' faces; return (shape, closed) where closed means one closed shell made solid."""
    _, MakeSolid, Sewing, *_ = _ocp()
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    pts = np.concatenate([np.asarray(g, dtype=np.float64)[..., :3].reshape(-1, 3) for g in patch_groups if len(g)])
    diagonal = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) or 1.0
    sew = Sewing(relative_tolerance * diagonal)
    for face in bezier_faces(patch_groups):
        sew.Add(face)
    sew.Perform()
    shape = sew.SewedShape()
    shells = []
    explorer = TopExp_Explorer(shape, TopAbs_SHELL)
    while explorer.More():
        shells.append((TopoDS.Shell_s if hasattr(TopoDS, "Shell_s") else TopoDS.Shell)(explorer.Current()))
        explorer.Next()
    if len(shells) == 1 and sew.NbFreeEdges() == 0 and BRep_Tool.IsClosed_s(shells[0]):
        return MakeSolid(shells[0]).Solid(), True
    return shape, False


def write_patches_step(path, surface, input_path: str | None = None, *, file_name: str | None = None, **_options) -> None:
    """Write ``surface``'s patches as STEP AP214: a solid when they close up, else the sewn shell(s)."""
    _ocp()
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TCollection import TCollection_HAsciiString

    from ..errors import OutputError

    groups = [g for g in (surface.biquadratic, surface.bicubic) if len(g)]
    shape, _ = sewn_shape(groups)
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
        status = writer.Write(os.fspath(path))
    if status != IFSelect_RetDone:
        raise OutputError(path, "Open CASCADE could not write the STEP file")
    _fix_header(path, name)


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


__all__ = ["write_patches_step", "bezier_faces", "sewn_shape", "SEWING_TOLERANCE"]
