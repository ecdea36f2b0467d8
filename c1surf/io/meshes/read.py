"""Read a polygon mesh file, choosing the reader from the suffix."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import MeshInputError
from .mesh_file import MeshFile
from .obj import read_obj
from .ply import read_ply

__all__ = ["read_mesh", "READERS", "SUPPORTED_SUFFIXES"]

READERS = {".obj": read_obj, ".ply": read_ply}
SUPPORTED_SUFFIXES = tuple(READERS)


def read_mesh(path) -> MeshFile:
    """Read an OBJ or PLY polygon mesh (suffix decides, any letter case).

    Parameters
    ----------
    path : str or os.PathLike

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
            "an .obj or .ply file")
    suffix = p.suffix.lower()
    reader = READERS.get(suffix)
    if reader is None:
        shown = f"suffix {p.suffix!r}" if p.suffix else "no suffix"
        raise MeshInputError(
            path_str, f"unsupported mesh format ({shown}): c1surf reads "
            f"{', '.join(SUPPORTED_SUFFIXES)} files; convert the mesh to one "
            "of them")
    if not os.access(path_str, os.R_OK):
        raise MeshInputError(
            path_str, "cannot read the file (permission denied): check its "
            "permissions")
    return reader(path_str)
