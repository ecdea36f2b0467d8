"""Read a polygon mesh file, choosing the reader from the suffix (``io.registry.MESH_READERS``)."""

from __future__ import annotations

import inspect
import os
from pathlib import Path

from ..errors import MeshInputError
from ..registry import MESH_READERS, UnsupportedFormat, suffix_list, suffix_of
from .mesh_file import MeshFile

__all__ = ["read_mesh", "read_mesh_in_range"]


def read_mesh(path, *, keep_degenerate: bool = False, usd=None) -> MeshFile:
    """Read a polygon mesh of a format in ``MESH_READERS`` (OBJ, PLY, STL, OFF, USD; suffix decides, any letter case).

    The vertices are as in the file; welding is a separate step of the input preparation (``prepare.mesh_edits.weld_mesh_file``).

    Parameters
    ----------
    path : str or os.PathLike, a mesh file whose suffix names its format
    keep_degenerate : keep faces that repeat a vertex as written: no collapse of repeated
        corners and no refusal (``c1surf inspect`` counts them; every other caller refuses)
    usd : io.meshes.usd.stage.UsdReadOptions or None (the reader's defaults): which meshes of a USD stage, and where;
        refused for a file of another format

    Returns
    -------
    MeshFile

    Raises
    ------
    MeshInputError
        Missing file, a directory, unreadable file, unknown suffix, or a
        file that is not a valid mesh of its format.
    """
    path_str = os.fspath(path)
    p = Path(path_str)
    if not p.exists():
        hint = ""
        if p.parent != Path("") and not p.parent.is_dir():
            hint = f" (folder {str(p.parent)!r} does not exist either)"
        raise MeshInputError(
            path_str, f"no such file{hint}: check the path")
    if p.is_dir():
        raise MeshInputError(
            path_str, "is a directory, not a mesh file: give the path of "
            f"a {suffix_list(MESH_READERS)} file")
    try:
        suffix = suffix_of(path_str, MESH_READERS)
    except UnsupportedFormat as e:
        raise MeshInputError(path_str, f"{e.message}; convert the mesh to one of them") from None
    if not os.access(path_str, os.R_OK):
        raise MeshInputError(
            path_str, "cannot read the file (permission denied): check its "
            "permissions")
    reader = MESH_READERS[suffix].function
    if usd is None:
        return reader(path_str, keep_degenerate=keep_degenerate)
    if "usd" not in inspect.signature(reader).parameters:
        raise MeshInputError(path_str, "the USD options (--usd-prim, --usd-local) apply to .usd, .usda, .usdc and "
                                       ".usdz files only: drop them for this file")
    return reader(path_str, keep_degenerate=keep_degenerate, usd=usd)


def read_mesh_in_range(path) -> MeshFile:
    """``read_mesh``, then refuse coordinates out of the range c1surf computes with
    (``mesh.points.geometry_checks.check_coordinate_range``: a vertex at 1e308 would make a comparison's
    differences overflow): ``c1surf diff`` of two meshes, which builds no surface (the commands that do check
    it in the input preparation)."""
    from ...mesh.points.geometry_checks import GeometryError, check_coordinate_range

    mesh = read_mesh(path)
    if len(mesh.points):
        try:
            check_coordinate_range(mesh.points)
        except GeometryError as error:
            raise MeshInputError(os.fspath(path), error.message) from None
    return mesh
