"""The binary PLY writer for triangle meshes (tessellations), vectorized.

One structured array per block of vertices: ``x y z`` (double, or float with
``float32``), ``nx ny nz``, then whatever the mesh carries:

- texture coordinates and colours (``convert --attributes``): ``s t`` (float)
  and ``red green blue [alpha]`` (uchar); such a mesh keeps the layout c1surf
  has always written for it: normals as float, no header comment;
- named scalar properties (``convert --curvature``: ``kmax K H quality`` as
  float, ``red green blue`` as uchar), in order; MeshLab shows ``quality`` with
  "Colorize by vertex quality", most viewers show the colours as they are.

Faces are ``property list uchar int vertex_indices``, binary little endian.
"""
from __future__ import annotations

import contextlib
import os
import threading

import numpy as np

from ..finite import refuse_non_finite_mesh, refuse_non_finite_vertices

__all__ = ["write_ply", "write_ply_blocks", "write_ply_stream", "vertex_columns"]

_BLOCK = 1 << 19  # rows per block: bounds the structured arrays to some MB
_TYPE_NAMES = {"<f4": "float", "<f8": "double", "u1": "uchar"}


def vertex_columns(mesh, float32: bool = False) -> list:
    """The vertex properties of ``mesh`` (an ``io.meshes.write.TriangleMesh``) as PLY columns.

    Returns
    -------
    list of (name, dtype, (V,) values), in file order; dtype one of "<f8", "<f4", "u1"
    """
    real = "<f4" if float32 else "<f8"
    columns = [(axis, real, mesh.points[:, k]) for k, axis in enumerate("xyz")]
    if mesh.normals is not None:
        normal = "<f4" if mesh.has_attributes else real
        columns += [(axis, normal, mesh.normals[:, k]) for k, axis in enumerate(("nx", "ny", "nz"))]
    if mesh.uv is not None:
        columns += [("s", "<f4", mesh.uv[:, 0]), ("t", "<f4", mesh.uv[:, 1])]
    for name, values in mesh.properties.items():
        if not name.isidentifier():
            raise ValueError(f"bad PLY property name {name!r}")
        values = np.asarray(values)
        columns.append((name, "u1" if values.dtype == np.uint8 else "<f4", values.reshape(-1)))
    if mesh.colours is not None:
        bytes_ = np.rint(np.asarray(mesh.colours) * 255).astype(np.uint8)
        columns += [(name, "u1", bytes_[:, k]) for k, name in enumerate(mesh.colour_names)]
    return columns


def _header(columns, n_vertices: int, n_triangles: int, comments) -> bytes:
    lines = ["ply", "format binary_little_endian 1.0"]
    lines += [f"comment {c}" for c in comments]
    lines.append(f"element vertex {n_vertices}")
    lines += [f"property {_TYPE_NAMES[dtype]} {name}" for name, dtype, _ in columns]
    lines += [f"element face {n_triangles}", "property list uchar int vertex_indices", "end_header"]
    return ("\n".join(lines) + "\n").encode("ascii")


def write_ply(path, mesh, float32: bool = False) -> None:
    """Write ``mesh`` (an ``io.meshes.write.TriangleMesh``) as binary little-endian PLY.

    Parameters
    ----------
    path : str or os.PathLike
    mesh : TriangleMesh, points (V, 3), triangles (T, 3) int, optional normals, uv, colours, properties
    float32 : positions (and normals) as ``float`` instead of ``double``
    """
    refuse_non_finite_mesh(mesh, path, float32)
    columns = vertex_columns(mesh, float32)
    triangles = np.asarray(mesh.triangles)
    n, t = mesh.points.shape[0], triangles.shape[0]
    comments = () if mesh.has_attributes else ("c1surf",)
    with open(path, "wb") as f:
        f.write(_header(columns, n, t, comments))
        for a in range(0, n, _BLOCK):
            f.write(_vertex_bytes([(name, dtype, values[a : a + _BLOCK]) for name, dtype, values in columns]))
        for a in range(0, t, _BLOCK):
            f.write(_face_bytes(triangles[a : a + _BLOCK]))


def write_ply_blocks(path, n_vertices: int, n_triangles: int, vertex_blocks, triangle_blocks,
                     float32: bool = False, triangles_first: bool = False) -> None:
    """Write a tessellation given by blocks as ``write_ply`` writes it whole: the same bytes.

    Parameters
    ----------
    n_vertices, n_triangles : int, the counts the blocks will add up to (the header comes first)
    vertex_blocks : iterable of (points (c, >= 3), normals (c, 3)) float, in vertex order
    triangle_blocks : iterable of (t, 3) int, in order
    float32 : positions and normals as ``float``
    triangles_first : the triangle blocks do not depend on the vertex blocks having run: the faces are
        written at their place after the vertices' room by a thread of their own (``_FaceWriter``: the two
        iterables are then read on different threads) while the caller's thread computes and writes the
        vertices, or before them where there is no ``os.pwrite``
    """
    real = "<f4" if float32 else "<f8"
    names = [(axis, real) for axis in ("x", "y", "z", "nx", "ny", "nz")]
    written = [0, 0]
    with open(path, "wb") as f:
        f.write(_header([(name, dtype, None) for name, dtype in names], n_vertices, n_triangles, ("c1surf",)))
        f.flush()
        faces, faces_at = None, f.tell() + n_vertices * 6 * np.dtype(real).itemsize
        if triangles_first and hasattr(os, "pwrite"):  # integers only: by a thread of their own meanwhile
            faces = _FaceWriter(f.fileno(), faces_at, triangle_blocks)
            faces.start()
        elif triangles_first:  # no os.pwrite (Windows): the faces first, then the vertices in the room left
            vertices_at = f.tell()
            f.seek(faces_at)
            for triangles in triangle_blocks:
                f.write(_face_bytes(triangles))
                written[1] += triangles.shape[0]
            f.seek(vertices_at)
        try:
            for points, normals in vertex_blocks:
                refuse_non_finite_vertices(points, normals, path, real)
                records = None if float32 else _records(points, normals)
                if records is None:
                    values = [points[:, 0], points[:, 1], points[:, 2], normals[:, 0], normals[:, 1], normals[:, 2]]
                    records = _vertex_bytes([(name, dtype, v) for (name, dtype), v in zip(names, values)])
                f.write(records)
                written[0] += points.shape[0]
        except BaseException:
            if faces is not None:
                faces.finish(stop=True)  # an error or an interrupt here: the faces stop too, before the file closes
            raise
        if faces is not None:
            faces.finish(stop=False)
            written[1] = faces.count
        for triangles in () if triangles_first else triangle_blocks:
            f.write(_face_bytes(triangles))
            written[1] += triangles.shape[0]
    if written != [n_vertices, n_triangles]:
        raise ValueError(f"internal: the blocks gave {written[0]} vertices and {written[1]} triangles, "
                         f"the header says {n_vertices} and {n_triangles}")


class _FaceWriter(threading.Thread):
    """Write the face records of ``triangle_blocks`` from byte ``offset`` of the open file ``fd`` (``os.pwrite``:
    the file position stays the caller's), beside the vertex blocks the caller computes meanwhile (0.1-0.15 s of
    the 180,000-quad torus's conversion at -r 2 no longer comes after the vertices). Then have the kernel start
    writing those pages to the disk (``_start_writeback``)."""

    def __init__(self, fd: int, offset: int, triangle_blocks):
        super().__init__(name="ply faces", daemon=True)
        self.fd, self.offset, self.blocks = fd, offset, triangle_blocks
        self.count, self.error, self._halt = 0, None, threading.Event()

    def run(self) -> None:
        try:
            at = self.offset
            for triangles in self.blocks:
                if self._halt.is_set():
                    return
                data = memoryview(_face_bytes(triangles))
                while data.nbytes:
                    n = os.pwrite(self.fd, data, at)
                    at, data = at + n, data[n:]
                self.count += triangles.shape[0]
            _start_writeback(self.fd, self.offset)
        except BaseException as exc:  # given to the caller by ``finish``
            self.error = exc

    def finish(self, stop: bool) -> None:
        """Wait for the thread (told to stop after its current block if ``stop``); raise its error, if any."""
        if stop:
            self._halt.set()
        try:
            self.join()
        except BaseException:  # interrupted while waiting: it stops after its block (it must not outlive the file)
            self._halt.set()
            self.join()
            raise
        if self.error is not None and not stop:
            raise self.error


def write_ply_stream(path, tessellation, float32: bool = False) -> None:
    """Write a tessellation by blocks (``evaluation.stream.StreamedTessellation``): the bytes of ``write_ply``."""
    write_ply_blocks(path, tessellation.n_vertices, tessellation.n_triangles, tessellation.vertex_blocks(),
                     tessellation.triangle_blocks(), float32, triangles_first=True)


def _start_writeback(fd: int, start: int) -> None:
    """Have the kernel start writing the file's pages from ``start`` on to the disk, without waiting (Linux), so
    that ``atomic_output``'s flush before the rename finds less to do."""
    advise = getattr(os, "posix_fadvise", None)
    if advise is not None:
        with contextlib.suppress(OSError):
            advise(fd, start, 0, os.POSIX_FADV_DONTNEED)


def _records(points: np.ndarray, normals: np.ndarray):
    """The double records ``x y z nx ny nz`` of a block as they lie in memory, or None: when ``points`` (c, 3) and
    ``normals`` (c, 3) are the two halves of the rows of one C-contiguous (c, 6) little-endian float64 array (the
    streamed tessellation's corner table), its bytes are the file's, written without a copy."""
    if points.shape[1:] != (3,) or points.dtype != np.dtype("<f8") or normals.dtype != np.dtype("<f8"):
        return None
    if not (points.strides == normals.strides == (48, 8) and normals.ctypes.data == points.ctypes.data + 24):
        return None
    rows = np.lib.stride_tricks.as_strided(points, shape=(points.shape[0], 6), strides=(48, 8), writeable=False)
    return memoryview(rows.reshape(-1))


def _vertex_bytes(columns) -> bytes:
    """The records of one block of vertices: columns [(name, dtype, (c,) values)]."""
    vertex = np.empty(len(columns[0][2]), dtype=[(name, dtype) for name, dtype, _ in columns])
    for name, _, values in columns:
        vertex[name] = values
    return vertex.tobytes()


def _face_bytes(triangles: np.ndarray) -> bytes:
    """The records of one block of (t, 3) triangles: ``3 a b c`` as uchar and three int32."""
    face = np.empty(triangles.shape[0], dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"] = 3
    face["i"] = triangles
    return face.tobytes()
