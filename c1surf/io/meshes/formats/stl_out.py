"""Binary STL by blocks of triangles: the bytes ``io.meshes.write.write_stl`` (trimesh) writes whole.

trimesh's binary STL (``trimesh.exchange.stl.export_stl``) is an 80-byte zero
header, the triangle count (uint32), then one record per triangle: the facet
normal and the three corners as float32, and a zero uint16. The facet normal
is the unit cross product of two edges of the float64 triangle
(``trimesh.triangles.normals``), zero for a triangle without one; every
number is rounded to float32 only when stored. Each record depends on its own
triangle only, so blocks of triangles give the same bytes as the whole mesh,
as long as the corners carry the same float64 bits (``triangle_point_blocks``
of ``evaluation.stream.StreamedTessellation``).
"""
from __future__ import annotations

import numpy as np

from ...finite import refuse_non_finite

__all__ = ["write_stl_stream", "stl_records"]

# trimesh.exchange.stl's _stl_dtype_header and _stl_dtype
_HEADER = np.dtype([("header", np.void, 80), ("face_count", "<u4")])
_RECORD = np.dtype([("normals", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attributes", "<u2")])


def stl_records(corners: np.ndarray) -> bytes:
    """The binary STL records of triangles with corners ``corners`` (t, 3, 3) float64, as trimesh writes them."""
    from trimesh.triangles import normals as facet_normals  # the function trimesh's export calls

    unit, valid = facet_normals(triangles=corners)
    packed = np.zeros(corners.shape[0], dtype=_RECORD)
    if valid.all():
        packed["normals"] = unit
    else:  # trimesh pads the facets without a normal with zeros
        padded = np.zeros((corners.shape[0], 3))
        padded[valid] = unit
        packed["normals"] = padded
    packed["vertices"] = corners
    return packed.tobytes()


def write_stl_stream(path, tessellation, float32: bool = False) -> None:
    """Write a tessellation by blocks (``evaluation.stream.StreamedTessellation``) as the binary STL trimesh writes.

    Parameters
    ----------
    path : str or os.PathLike
    tessellation : has ``n_triangles`` and ``triangle_point_blocks()``, yielding (t, 3, 3) float64 corners
        of the triangles in order
    float32 : ignored: STL stores float32 by definition (as ``write_stl``)
    """
    header = np.zeros(1, dtype=_HEADER)
    header["face_count"] = tessellation.n_triangles
    written = 0
    with open(path, "wb") as f:
        f.write(header.tobytes())
        for corners in tessellation.triangle_point_blocks():
            refuse_non_finite(corners, "vertex coordinates", path, np.float32)
            f.write(stl_records(corners))
            written += corners.shape[0]
    if written != tessellation.n_triangles:
        raise ValueError(f"internal: the blocks gave {written} triangles, the header says {tessellation.n_triangles}")
