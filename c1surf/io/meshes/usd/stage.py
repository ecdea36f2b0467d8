"""What the USD reader and writers share: usd-core imported on first use (one line saying what to install when it
is missing), a stage opened with usd-core's errors as one line, the reader's options and c1surf's own primvars."""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ...errors import MeshInputError, OutputError

__all__ = ["UsdReadOptions", "pxr_modules", "require_usd", "open_stage", "POINTS_PRIMVAR", "PATCH_PRIMVAR", "INSTALL",
           "USD_SUFFIXES", "SHARPNESS_ATTRIBUTES", "exact_where_rounded"]

USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")

# The positions as float64 (USD's points are float32): ``c1surf convert`` of a cage or tessellation written by c1surf
# reads these bits wherever they round to the file's float points (a point moved in another tool does not).
POINTS_PRIMVAR = "c1surf:points"
# The sharpness as float64 (USD's creaseSharpnesses and cornerSharpnesses are float32), read likewise.
SHARPNESS_ATTRIBUTES = {"crease": "c1surf:creaseSharpnesses", "corner": "c1surf:cornerSharpnesses"}
# The patch of each triangle of a tessellation (uniform interpolation: one value a face).
PATCH_PRIMVAR = "c1surf:patch"
INSTALL = "USD files need usd-core: pip install 'c1surf[usd]' (or pip install usd-core)"


@dataclass(frozen=True)
class UsdReadOptions:
    """Which meshes of a USD stage become the polygon mesh, and where.

    prim : str or None, a prim path: the ``UsdGeom.Mesh`` prims at or below it (one mesh, or the meshes of one
        Xform); None: every mesh of the stage, as one surface (as an OBJ file's objects are)
    world : True: each mesh's points through its local-to-world transform (where the meshes sit in the scene, as a
        DCC shows them and as several meshes must be to form one surface); False: the points as the prim stores them
    """

    prim: str | None = None
    world: bool = True


def pxr_modules(path, writing: bool = False):
    """(Usd, UsdGeom, Sdf, Vt, Tf) of usd-core; MeshInputError (OutputError when ``writing``) saying what to install."""
    try:
        from pxr import Sdf, Tf, Usd, UsdGeom, Vt
    except ImportError:
        raise (OutputError(path, INSTALL) if writing else MeshInputError(path, INSTALL)) from None
    return Usd, UsdGeom, Sdf, Vt, Tf


def exact_where_rounded(floats, doubles):
    """``floats`` (N, ...) as float64, with the rows of ``doubles`` whose rounding to ``floats``' type gives them:
    (values, rows taken from ``doubles``); ``doubles`` of another shape, or None, are not used."""
    values = np.asarray(floats).astype(np.float64)
    if doubles is None or np.shape(doubles) != values.shape:
        return values, None
    doubles = np.asarray(doubles, dtype=np.float64)
    same = (doubles.astype(np.asarray(floats).dtype) == np.asarray(floats)).reshape(len(values), -1).all(axis=1)
    values[same] = doubles[same]
    return values, same


def require_usd(outputs) -> None:
    """OutputError naming the first of ``outputs`` (paths to be written as USD) when usd-core is missing."""
    if outputs:
        pxr_modules(outputs[0], writing=True)


def usd_message(error) -> str:
    """The first of usd-core's error lines (``Error in 'Class::Method' at line N in file F : 'message'``)."""
    try:
        said = str(error)
    except UnicodeError:  # usd-core's message quotes the file's damaged bytes
        return "usd-core's message about it is not text"
    found = re.findall(r": '(.*?)'\s*(?:\n|$)", said)
    text = found[0] if found else " ".join(said.split())
    return text.rstrip(".")


def open_stage(path: str):
    """(The USD stage of ``path``, read afresh (a layer usd-core still holds is reloaded from the disk), notes):
    usd-core's warnings while composing it (a reference to a missing file, ...) become ``c1surf: note:`` lines
    instead of its own stderr lines.

    Raises
    ------
    MeshInputError
        The file is not USD (usd-core's own reason, one line), or names no stage.
    """
    Usd, _, Sdf, _, Tf = pxr_modules(path)
    from pxr import UsdUtils

    collected = UsdUtils.CoalescingDiagnosticDelegate()  # while it lives, usd-core prints nothing itself
    try:
        held = Sdf.Layer.Find(path)
        if held:
            held.Reload(force=True)
        stage = Usd.Stage.Open(path, Usd.Stage.LoadAll)
    except Tf.ErrorException as error:
        raise MeshInputError(path, f"not a USD file usd-core can read ({usd_message(error)}): export the scene as "
                                   ".usd, .usda, .usdc or .usdz") from None
    if stage is None:
        raise MeshInputError(path, "usd-core opened no stage from this file: export the scene as .usd, .usda, .usdc "
                                   "or .usdz")
    warnings = [re.sub(r"\s*\(instantiating stage on stage .*\)$", "", " ".join(d.commentary.split()))
                for d in collected.TakeUncoalescedDiagnostics()]  # without the stage's memory address
    shown = "; ".join(warnings[:3]) + (f" and {len(warnings) - 3} more" if len(warnings) > 3 else "")
    return stage, [f"{path}: usd-core: {shown}"] if warnings else []
