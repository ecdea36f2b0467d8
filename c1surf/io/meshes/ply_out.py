"""A vectorized binary PLY writer for triangle meshes with extra per-vertex properties.

Used for tessellations that carry curvature (``convert --curvature``): besides
``x y z nx ny nz`` each vertex gets float properties (``kmax K H``), ``quality``
(a copy of one of them, the scalar MeshLab shows with "Colorize by vertex
quality") and ``red green blue`` colours, which most viewers display as they are.
"""
from __future__ import annotations

import numpy as np

__all__ = ["write_ply"]


def write_ply(path, points: np.ndarray, triangles: np.ndarray, normals: np.ndarray | None = None,
              properties: dict | None = None, colors: np.ndarray | None = None, comments=(), float32: bool = False) -> None:
    """Write a binary little-endian PLY file.

    Parameters
    ----------
    points : (V, 3) float; triangles : (T, 3) int; normals : (V, 3) float or None
    properties : dict name -> (V,) float, written as float32 vertex properties, in order
    colors : (V, 3) uint8 or None, written as ``red green blue``
    comments : iterable of str, header comment lines
    float32 : positions and normals as ``float`` (default ``double``, like the plain PLY writer)
    """
    points = np.asarray(points)
    triangles = np.asarray(triangles)
    v = points.shape[0]
    real = "<f4" if float32 else "<f8"
    fields = [("x", real), ("y", real), ("z", real)]
    if normals is not None:
        fields += [("nx", real), ("ny", real), ("nz", real)]
    properties = dict(properties or {})
    for name in properties:
        if not name.isidentifier():
            raise ValueError(f"bad PLY property name {name!r}")
        fields.append((name, "<f4"))
    if colors is not None:
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    vertex = np.empty(v, dtype=fields)
    for k, axis in enumerate("xyz"):
        vertex[axis] = points[:, k]
    if normals is not None:
        for k, axis in enumerate(("nx", "ny", "nz")):
            vertex[axis] = normals[:, k]
    for name, values in properties.items():
        vertex[name] = np.asarray(values).reshape(v)
    if colors is not None:
        for k, name in enumerate(("red", "green", "blue")):
            vertex[name] = colors[:, k]
    face = np.empty(triangles.shape[0], dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"] = 3
    face["i"] = triangles
    type_names = {"<f4": "float", "<f8": "double", "u1": "uchar"}
    header = ["ply", "format binary_little_endian 1.0"]
    header += [f"comment {c}" for c in comments]
    header.append(f"element vertex {v}")
    header += [f"property {type_names[t]} {name}" for name, t in fields]
    header += [f"element face {triangles.shape[0]}", "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode("ascii"))
        f.write(vertex.tobytes())
        f.write(face.tobytes())
