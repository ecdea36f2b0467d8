"""Binary glTF (GLB) by blocks: the bytes ``io.meshes.write.write_glb`` (trimesh) writes whole.

trimesh's GLB of a triangle mesh with vertex normals
(``trimesh.exchange.gltf.export_glb``) is a 20-byte header, a JSON chunk
and a binary chunk holding three buffer views: the triangles as uint32, the
positions as float32 and the normals, made unit again in float64
(``trimesh.util.unitize``), as float32. The JSON comes first and names each
view's minimum and maximum, so a first pass over the vertex blocks collects
them (and keeps the blocks in a temporary file, ``SpooledTessellation``); the
second reads them back and writes the views (their lengths are known, so
positions and normals go to their own offsets in one pass). trimesh stores one view for
equal bytes: normals whose float32 bytes equal the positions' share their
view, as here.
"""
from __future__ import annotations

import json
import os

import numpy as np

from ....arrays import column_bounds
from ....evaluation.stream.spool import SpooledTessellation
from ...finite import refuse_non_finite_vertices

__all__ = ["write_glb_stream"]

_GLTF, _JSON, _BIN = 0x46546C67, 0x4E4F534A, 0x004E4942  # chunk magics: "glTF", "JSON", "BIN\0"
_GENERATOR = "https://github.com/mikedh/trimesh"
_NAME = "geometry_0"  # trimesh's name of the one mesh of its scene


class _Bounds:
    """Per-column minimum and maximum of float32 positions and normals over the vertex blocks, and of the indices."""

    def __init__(self):
        self.low, self.high = [None, None], [None, None]
        self.index = None
        self.same = True  # float32 normals equal to the positions, byte for byte (trimesh then stores one view)

    def add_vertices(self, positions: np.ndarray, normals: np.ndarray) -> None:
        for k, values in enumerate((positions, normals)):
            if values.shape[0]:
                low, high = column_bounds(values)
                self.low[k] = low if self.low[k] is None else np.minimum(self.low[k], low)
                self.high[k] = high if self.high[k] is None else np.maximum(self.high[k], high)
        self.same = self.same and np.array_equal(positions.view(np.uint32), normals.view(np.uint32))

    def add_triangles(self, indices: np.ndarray) -> None:
        if indices.size:
            low, high = indices.min(), indices.max()
            self.index = (low, high) if self.index is None else (min(self.index[0], low), max(self.index[1], high))


def _vertex_arrays(points: np.ndarray, normals: np.ndarray):
    """(positions (c, 3) float32, normals (c, 3) float32) as trimesh stores them."""
    from trimesh.util import unitize  # trimesh's export makes the normals unit again with it

    return points[:, :3].astype(np.float32), unitize(normals).astype(np.float32)


def _document(bounds: _Bounds, n_vertices: int, n_indices: int) -> tuple:
    """(JSON chunk bytes, binary chunk length): trimesh's tree for this mesh, with its key order and padding."""
    index_bytes, vertex_bytes = 4 * n_indices, 12 * n_vertices
    faces = {"componentType": 5125, "type": "SCALAR", "bufferView": 0, "count": n_indices,
             "max": [int(bounds.index[1])], "min": [int(bounds.index[0])]}
    positions = {"componentType": 5126, "type": "VEC3", "byteOffset": 0, "bufferView": 1, "count": n_vertices,
                 "max": bounds.high[0].tolist(), "min": bounds.low[0].tolist()}
    normals = {"componentType": 5126, "count": n_vertices, "type": "VEC3", "byteOffset": 0,
               "bufferView": 1 if bounds.same else 2, "max": bounds.high[1].tolist(), "min": bounds.low[1].tolist()}
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": index_bytes},
             {"buffer": 0, "byteOffset": index_bytes, "byteLength": vertex_bytes}]
    if not bounds.same:
        views.append({"buffer": 0, "byteOffset": index_bytes + vertex_bytes, "byteLength": vertex_bytes})
    length = sum(view["byteLength"] for view in views)
    tree = {"scene": 0, "scenes": [{"nodes": [0]}], "asset": {"version": "2.0", "generator": _GENERATOR},
            "accessors": [faces, positions, normals],
            "meshes": [{"name": _NAME, "extras": {},
                        "primitives": [{"attributes": {"POSITION": 1, "NORMAL": 2}, "indices": 0, "mode": 4}]}],
            "nodes": [{"name": _NAME, "mesh": 0}], "buffers": [{"byteLength": length}], "bufferViews": views}
    content = json.dumps(tree, separators=(",", ":"))
    content += (4 - ((len(content) + 20) % 4)) * " "  # trimesh pads 1 to 4 spaces, never 0
    return content.encode("utf-8"), length


def write_glb_stream(path, tessellation, float32: bool = False) -> None:
    """Write a tessellation by blocks (``evaluation.stream.StreamedTessellation``) as the GLB trimesh writes.

    Two passes over the vertex blocks (bounds, then bytes; evaluated once) and two over the triangle blocks.

    Parameters
    ----------
    path : str or os.PathLike, a regular file (written at two offsets)
    tessellation : has ``n_vertices``, ``n_triangles``, ``dim``, ``vertex_blocks()`` yielding (points (c, dim),
        normals (c, 3)) float in vertex order, ``triangle_blocks()`` yielding (t, 3) int in order
    float32 : ignored: glTF stores float32 by definition (as ``write_glb``)
    """
    n, t = tessellation.n_vertices, tessellation.n_triangles
    if n == 0 or t == 0:
        raise ValueError("an empty mesh has no GLB by blocks")
    with SpooledTessellation(tessellation, os.path.dirname(os.path.abspath(path))) as spooled:
        bounds = _Bounds()
        for points, normals in spooled.vertex_blocks():  # evaluated once, kept for the second pass
            refuse_non_finite_vertices(points[:, :3], normals, path, np.float32)
            bounds.add_vertices(*_vertex_arrays(points, normals))
        for triangles in spooled.triangle_blocks():
            bounds.add_triangles(triangles.astype(np.uint32))
        content, length = _document(bounds, n, 3 * t)
        header = np.array([_GLTF, 2, len(content) + length + 28, len(content), _JSON], dtype="<u4").tobytes()
        with open(path, "wb") as f:
            f.write(header + content + np.array([length, _BIN], dtype="<u4").tobytes())
            start = f.tell()
            for triangles in spooled.triangle_blocks():
                f.write(triangles.astype(np.uint32).tobytes())
            at = [start + 12 * t, start + 12 * t + 12 * n]  # where the next positions and normals go
            for points, normals in spooled.vertex_blocks():
                positions, unit = _vertex_arrays(points, normals)
                for k, values in enumerate((positions, unit) if not bounds.same else (positions,)):
                    f.seek(at[k])
                    f.write(values.tobytes())
                    at[k] += values.nbytes
            f.seek(0, 2)
            if f.tell() != 28 + len(content) + length:
                raise ValueError(f"internal: the GLB holds {f.tell()} bytes, its header says {28 + len(content) + length}")
