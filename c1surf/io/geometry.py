"""``mesh.geometry_checks`` on a mesh read from a file: its refusals as the file's one-line error."""
from __future__ import annotations

from ..mesh.geometry_checks import GeometryError, check_geometry
from .errors import MeshInputError

__all__ = ["check_mesh_file_geometry"]


def check_mesh_file_geometry(mesh) -> None:
    """Raise ``MeshInputError`` (``PATH: reason``) when the positions of the vertices the faces of ``mesh``
    (an ``io.meshes.mesh_file.MeshFile``) use are out of the construction's range or span no surface."""
    try:
        check_geometry(mesh.points, mesh.face_vertices)
    except GeometryError as error:
        raise MeshInputError(mesh.path, error.message) from None
