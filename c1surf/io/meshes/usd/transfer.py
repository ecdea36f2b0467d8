"""A USD MeshFile across the process boundary (``io.contained``): usd-core parses the file in a child process, so a
crash, a signal or a hang in its C++ parser on a damaged file is one line, and whatever it prints goes nowhere.

``mesh_arrays`` (the child: ``read.mesh_arrays``) turns the MeshFile into a JSON header and plain arrays;
``mesh_file`` rebuilds it in the parent.
"""
from __future__ import annotations

import numpy as np

from ..mesh_file import MeshFile
from ..tags.record import SharpTags
__all__ = ["mesh_arrays", "mesh_file"]

# the MeshFile's arrays, in the order they travel (face_groups an empty array when None)
_ARRAYS = ("points", "face_sizes", "face_vertices", "face_groups")
_TAG_ARRAYS = ("crease_edges", "crease_sharpness", "corner_vertices", "corner_sharpness", "hole_faces")


def mesh_arrays(mesh: MeshFile):
    """(header, arrays) of a MeshFile read in the child."""
    header = {"group_names": list(mesh.group_names), "reader_notes": list(mesh.reader_notes),
              "collapsed_corners": int(mesh.collapsed_corners), "grouped": mesh.face_groups is not None,
              "interpolate_boundary": mesh.tags.interpolate_boundary,
              "other": [[name, line] for name, line in mesh.tags.other]}
    groups = mesh.face_groups if mesh.face_groups is not None else np.zeros(0, np.int64)
    arrays = [mesh.points, mesh.face_sizes, mesh.face_vertices, groups]
    return header, arrays + [getattr(mesh.tags, name) for name in _TAG_ARRAYS]


def mesh_file(path: str, header: dict, arrays: list) -> MeshFile:
    """The MeshFile ``mesh_arrays`` sent, as the parent's."""
    mesh, tags = dict(zip(_ARRAYS, arrays)), dict(zip(_TAG_ARRAYS, arrays[len(_ARRAYS):]))
    tags = SharpTags(**tags, interpolate_boundary=header["interpolate_boundary"],
                     other=[(name, line) for name, line in header["other"]])
    return MeshFile(path=path, points=mesh["points"], face_sizes=mesh["face_sizes"],
                    face_vertices=mesh["face_vertices"],
                    face_groups=mesh["face_groups"] if header["grouped"] else None,
                    group_names=header["group_names"], tags=tags, reader_notes=header["reader_notes"],
                    collapsed_corners=header["collapsed_corners"])
