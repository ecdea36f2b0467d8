"""The preparation stage: a mesh as read (``io``'s MeshFile) to the construction's input, in one order.

``prepare_mesh`` gathers the extension data (``extension_data.surface_data``), then welds, drops repeated faces,
dissolves interior valence-2 vertices and, for exact creases, cuts non-manifold edges into sheets and merges
crease sectors (``prepare_surface_input``). Orientation and pinched vertices are repaired by the construction's
topology (``mesh.repair``, through ``construction.topology``), which every ``Surface`` runs on any arrays.
"""
from __future__ import annotations

import numpy as np

from ..construction.features import INFINITELY_SHARP
from ..errors import MeshInputError
from ..mesh.points.geometry_checks import GeometryError, check_geometry
from .extension_data import Sidecars, SurfaceData, surface_data
from .options import InputOptions
from .renumber import dissolve_surface_input, drop_repeated_surface_faces, weld_surface_input
from .sheets import merge_surface_sectors, split_surface_sheets

__all__ = ["prepare_mesh", "prepare_surface_input"]


def prepare_mesh(mesh, options: InputOptions, exact_creases: bool, sidecars: Sidecars | None = None):
    """``mesh`` (a MeshFile) and its SurfaceData, ready for ``construction.surface.Surface``.

    Parameters
    ----------
    mesh : MeshFile as read (``io.meshes.read.read_mesh``)
    options : InputOptions (checked here)
    exact_creases : bool, ``SurfaceOptions.exact_creases`` as ``InputOptions.surface_options`` resolved it
    sidecars : Sidecars, what ``options``' sidecar files say (``io.meshes.sidecars``), or None

    Raises MeshInputError for coordinates out of the construction's range or a mesh spanning no surface
    (``mesh.points.geometry_checks``), and for data the options ask for that the file lacks.

    Returns
    -------
    (MeshFile, SurfaceData): the edited mesh (its report fields say what changed) and the data that follows it
    """
    options.check()
    try:  # coordinates the construction can take, spanning a surface
        check_geometry(mesh.points, mesh.face_vertices)
    except GeometryError as error:
        raise MeshInputError(mesh.path, error.message) from None
    data = surface_data(mesh, options, exact_creases, sidecars)
    return prepare_surface_input(mesh, data, options.weld, exact_creases)


def prepare_surface_input(mesh, data: SurfaceData | None, weld: float | None, exact_creases: bool = False):
    """``mesh`` and ``data`` as the construction takes them: welded (``weld_surface_input``), without
    repeated faces (``drop_repeated_surface_faces``), with its interior valence-2 vertices dissolved
    (``dissolve_surface_input``) and, with ``exact_creases``, its non-manifold edges cut into sheets
    (``split_surface_sheets``, unless ``data.non_manifold`` is "refuse") and the faces of crease sectors
    too large for an exact C0 crease merged (``merge_surface_sectors``), then dissolved again where that
    left an interior vertex in two faces."""
    prepared = dissolve_surface_input(*drop_repeated_surface_faces(*weld_surface_input(mesh, data, weld)))
    if not exact_creases:
        return prepared
    sheets = data is None or data.non_manifold == "sheets"
    merged = merge_surface_sectors(*(split_surface_sheets(*prepared) if sheets else prepared))
    if merged[0].sector_merge is None:
        return merged
    # merging may leave an interior vertex next to a corner in two faces: dissolved too (not the seams')
    f = merged[1].features
    seam = np.zeros(merged[0].n_vertices, dtype=bool)
    seam[f.crease_edges[f.crease_sharpness >= INFINITELY_SHARP].ravel()] = True
    seam[f.corner_vertices] = True
    return dissolve_surface_input(*merged, keep=seam)


