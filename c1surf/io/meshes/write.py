"""Writing tessellated triangle meshes.

OBJ and plain PLY (positions and normals) go through the vectorized writers of
``fast_out`` (float64 by default, float32 on request; PLY binary); STL, GLB and
OFF through trimesh (STL and GLB store float32 by definition).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

# suffix -> trimesh file type and export keyword arguments
MESH_FORMATS = {
    ".obj": ("obj", {"include_normals": True, "digits": 10}),
    ".ply": ("ply", {"encoding": "binary"}),
    ".stl": ("stl", {}),
    ".glb": ("glb", {}),
    ".off": ("off", {}),
}


def mesh_format(path) -> str:
    """Check ``path``'s suffix names a supported mesh format; return the suffix."""
    suffix = Path(path).suffix.lower()
    if suffix not in MESH_FORMATS:
        raise ValueError(f"unknown mesh format {suffix!r}; use one of {', '.join(sorted(MESH_FORMATS))}")
    return suffix


def write_triangle_mesh(path, points: np.ndarray, triangles: np.ndarray, normals: np.ndarray | None = None, suffix: str | None = None,
                        vertex_properties: dict | None = None, vertex_colors: np.ndarray | None = None,
                        float32: bool = False) -> None:
    """Write a triangle mesh; the format comes from ``suffix`` (default: the path's).

    Parameters
    ----------
    points : (V, 3) float
    triangles : (T, 3) int
    normals : (V, 3) float or None, per-vertex unit normals
    vertex_properties : dict name -> (V,) float, or None: extra per-vertex scalars
        (PLY only, written by ``ply_out.write_ply``)
    vertex_colors : (V, 3) uint8 or None, with ``vertex_properties`` (PLY only)
    float32 : write coordinates and normals as float32 (PLY ``float``, fewer OBJ digits)
    """
    suffix = suffix or mesh_format(path)
    if vertex_properties is not None or vertex_colors is not None:
        if suffix != ".ply":
            raise ValueError(f"per-vertex properties need a .ply output, not {suffix}")
        from .ply_out import write_ply

        write_ply(path, points[:, :3], triangles, normals, vertex_properties, vertex_colors, comments=["c1surf"],
                  float32=float32)
        return
    if suffix in (".obj", ".ply"):
        from .fast_out import write_obj, write_ply_plain

        (write_obj if suffix == ".obj" else write_ply_plain)(path, points[:, :3], triangles, normals, float32=float32)
        return
    file_type, kwargs = MESH_FORMATS[suffix]
    mesh = trimesh.Trimesh(vertices=points[:, :3], faces=triangles, vertex_normals=normals, process=False, validate=False)
    data = mesh.export(file_type=file_type, **kwargs)
    mode = "w" if isinstance(data, str) else "wb"
    with open(path, mode) as f:
        f.write(data)
