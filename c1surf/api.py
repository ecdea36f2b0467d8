"""Python API: read a mesh file, build its surface, tessellate, check.

    >>> from c1surf.api import surface_from_file
    >>> surface, mesh = surface_from_file("sample_meshes/cube.obj", blend=0.5)
    >>> surface.bicubic.shape            # (Nc, 4, 4, 3) Bezier coefficients
    >>> surface.update_points(mesh.points * 2)   # same connectivity, new geometry
"""
from __future__ import annotations

from .core.smoothness import measure_smoothness
from .core.surface import Surface, SurfaceOptions, build_surface
from .core.tessellate import tessellate
from .io.read import read_mesh


def surface_from_file(path, **options):
    """Read ``path`` (OBJ or PLY) and build its surface.

    Parameters
    ----------
    path : str or Path
    **options : SurfaceOptions fields (blend, alpha, beta, tangent_rule)

    Returns
    -------
    (Surface, MeshFile)
    """
    mesh = read_mesh(path)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(**options))
    return surface, mesh


def tessellate_surface(surface: Surface, resolution: int = 8):
    """Welded N x N sampling of every patch of ``surface`` (a ``Tessellation``)."""
    return tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, resolution)


def check_surface(surface: Surface, samples: int = 11):
    """Independent G1 measurement of ``surface`` (a ``SmoothnessReport``)."""
    return measure_smoothness([surface.biquadratic, surface.bicubic], samples=samples)


__all__ = ["surface_from_file", "tessellate_surface", "check_surface", "build_surface", "Surface", "SurfaceOptions"]
