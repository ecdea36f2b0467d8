"""Triangle meshes with per-vertex texture coordinates and colours (``convert --attributes``).

trimesh keeps one "visual" per mesh (texture coordinates *or* colours), so
the two formats that hold both are written here directly:

- PLY (binary little endian): ``x y z`` (double), ``nx ny nz`` (float),
  ``s t`` (float, texture coordinates), ``red green blue [alpha]`` (uchar);
- OBJ: ``v x y z [r g b]`` (colours in 0..1), ``vt u v``, ``vn``, ``f a/a/a``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from plyfile import PlyData, PlyElement

ATTRIBUTE_FORMATS = (".ply", ".obj")


def _split(attributes: np.ndarray, names: list):
    uv = None
    colours, colour_names = None, []
    if "u" in names:
        i = names.index("u")
        uv = attributes[:, i : i + 2]
    picked = [k for k, name in enumerate(names) if name in ("red", "green", "blue", "alpha")]
    if picked:
        colours = attributes[:, picked]
        colour_names = [names[k] for k in picked]
    return uv, colours, colour_names


def write_attribute_mesh(path, points, triangles, normals, attributes, names, colour_scale: float = 255.0,
                         suffix: str | None = None) -> None:
    """Write a triangle mesh with texture coordinates and/or colours.

    Parameters
    ----------
    points : (V, 3) float; triangles : (T, 3) int; normals : (V, 3) float or None
    attributes : (V, k) float, columns named by ``names`` ("u", "v", "red", ...)
    colour_scale : 255 when colours are 0..255, 1 when 0..1
    suffix : ".ply" or ".obj" (default: the path's)
    """
    suffix = (suffix or Path(path).suffix).lower()
    if suffix not in ATTRIBUTE_FORMATS:
        raise ValueError(f"texture coordinates and colours are written to {', '.join(ATTRIBUTE_FORMATS)} files only")
    points = np.asarray(points, dtype=np.float64)[:, :3]
    triangles = np.asarray(triangles, dtype=np.int64)
    uv, colours, colour_names = _split(np.asarray(attributes, dtype=np.float64), list(names))
    if colours is not None:
        colours = np.clip(colours / colour_scale, 0.0, 1.0)  # 0..1
    if suffix == ".ply":
        fields = [("x", "f8"), ("y", "f8"), ("z", "f8")]
        if normals is not None:
            fields += [("nx", "f4"), ("ny", "f4"), ("nz", "f4")]
        if uv is not None:
            fields += [("s", "f4"), ("t", "f4")]
        fields += [(name, "u1") for name in colour_names]
        vertex = np.empty(points.shape[0], dtype=fields)
        for k, name in enumerate("xyz"):
            vertex[name] = points[:, k]
        if normals is not None:
            for k, name in enumerate(("nx", "ny", "nz")):
                vertex[name] = normals[:, k]
        if uv is not None:
            vertex["s"], vertex["t"] = uv[:, 0], uv[:, 1]
        for k, name in enumerate(colour_names):
            vertex[name] = np.rint(colours[:, k] * 255).astype(np.uint8)
        face = np.empty(triangles.shape[0], dtype=[("vertex_indices", "i4", (3,))])
        face["vertex_indices"] = triangles
        PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")], byte_order="<").write(str(path))
        return
    lines = ["# c1surf: smooth surface with per-vertex attributes"]
    rgb = colours[:, :3] if colours is not None and colours.shape[1] >= 3 else None
    for k in range(points.shape[0]):
        v = "v " + " ".join(repr(float(c)) for c in points[k])
        if rgb is not None:
            v += " " + " ".join(f"{c:.6g}" for c in rgb[k])
        lines.append(v)
    if uv is not None:
        lines += [f"vt {u!r} {w!r}" for u, w in uv.tolist()]
    if normals is not None:
        lines += [f"vn {a:.9g} {b:.9g} {c:.9g}" for a, b, c in np.asarray(normals).tolist()]
    one = triangles + 1
    if uv is not None and normals is not None:
        lines += [f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}" for a, b, c in one.tolist()]
    elif uv is not None:
        lines += [f"f {a}/{a} {b}/{b} {c}/{c}" for a, b, c in one.tolist()]
    elif normals is not None:
        lines += [f"f {a}//{a} {b}//{b} {c}//{c}" for a, b, c in one.tolist()]
    else:
        lines += [f"f {a} {b} {c}" for a, b, c in one.tolist()]
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")


__all__ = ["write_attribute_mesh", "ATTRIBUTE_FORMATS"]
