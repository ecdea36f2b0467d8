"""Python API: read a mesh file, build its surface, tessellate, check.

    >>> from c1surf.api import surface_from_file
    >>> surface, mesh = surface_from_file("sample_meshes/cube.obj", blend=0.5)
    >>> surface.bicubic.shape            # (Nc, 4, 4, 3) Bezier coefficients
    >>> surface.update_points(mesh.points * 2)   # same connectivity, new geometry
    >>> S = surface.stencil()            # the whole construction as one sparse matrix: S @ points
"""
from __future__ import annotations

from .evaluation.smoothness import measure_smoothness
from .construction.surface import Surface, SurfaceOptions, build_surface
from .evaluation.adjacency import patch_adjacency
from .evaluation.tessellate import tessellate
from .evaluation.tolerance import tessellate_to_tolerance
from .io.meshes.read import read_mesh
from .io.meshes.surface_data import prepare_surface_input, surface_data


def surface_from_file(path, blend_file=None, weights=None, normals: bool = False, attributes: bool = False,
                      creases_file=None, crease_angle=None, ignore_tags: bool = False, weld: float | None = 0.0,
                      **options):
    """Read ``path`` (OBJ, PLY, OFF, STL), weld it and build its surface.

    Parameters
    ----------
    path : str or Path
    blend_file : sidecar JSON of per-cell / per-vertex blend ratios (PLY "blend" properties are always used)
    weights : None (use the file's vertex weights if some differ from 1), True or False: rational patches (A2a)
    normals : interpolate the file's vertex normals (A1a; sets interpolate_vertices)
    attributes : carry texture coordinates and colours as extra point columns
    creases_file : sidecar JSON of creases, corners and holes (the file's own tags are always used)
    crease_angle : degrees: edges with a larger dihedral angle become infinitely sharp creases
    ignore_tags : build the smooth surface, without the file's sharp-feature tags
    weld : welding tolerance relative to the bounding-box diagonal (0: equal positions), or None: the file's vertices
    **options : SurfaceOptions fields (blend, alpha, beta, tangent_rule, interpolate_vertices, triangles,
        exact_creases: as ``convert``, C0 creases unless vertices are interpolated)

    Returns
    -------
    (Surface, MeshFile): the MeshFile as welded (``MeshFile.weld`` says what changed)
    """
    mesh = read_mesh(path)
    if normals:
        options["interpolate_vertices"] = True
    options.setdefault("exact_creases", not options.get("interpolate_vertices", False))  # as convert
    data = surface_data(mesh, blend_file=blend_file, use_weights=weights, normals=normals, attributes=attributes,
                        creases_file=creases_file, crease_angle=crease_angle, ignore_tags=ignore_tags)
    mesh, data = prepare_surface_input(mesh, data, weld, options.get("exact_creases", False))
    surface = Surface(mesh.face_sizes, mesh.face_vertices, data.points, SurfaceOptions(**options), **data.surface_kwargs())
    return surface, mesh


def tessellate_surface(surface: Surface, resolution: int = 8, tolerance: float | None = None):
    """Welded N x N sampling of every patch of ``surface`` (a ``Tessellation``); with ``tolerance``, a
    ``ToleranceTessellation`` whose chordal error is at most that fraction of the bounding-box diagonal."""
    groups = [surface.biquadratic, surface.bicubic]
    if tolerance is not None:
        return tessellate_to_tolerance(groups, patch_adjacency(surface.refined, surface.frames), tolerance,
                                       surface.patch_weights)
    return tessellate(groups, surface.refined, surface.frames, resolution, surface.patch_weights)


def check_surface(surface: Surface, samples: int = 11):
    """Independent G1 measurement of ``surface`` (a ``SmoothnessReport``); C0 crease pieces are measured for
    their gap, G1 everywhere else."""
    return measure_smoothness([surface.biquadratic, surface.bicubic], samples=samples, weights=surface.patch_weights,
                              crease_sides=surface.crease_sides)


__all__ = ["surface_from_file", "tessellate_surface", "check_surface", "build_surface", "Surface", "SurfaceOptions"]
