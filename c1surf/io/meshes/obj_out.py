"""The Wavefront OBJ writer for triangle meshes (tessellations), vectorized.

Records: ``v x y z [r g b]``, ``vt u v``, ``vn x y z``, then faces ``f a b c``
whose corners name the texture coordinate and the normal of the same number
(``a/a``, ``a//a`` or ``a/a/a``). Numbers become text a block of lines at a
time (``number_text``):

- fixed point at float64 precision relative to the model size, or float32
  precision with ``float32`` (fewer digits, smaller file);
- a mesh with texture coordinates or colours (``convert --attributes``) keeps,
  without ``float32``, the spelling c1surf has always given it: the shortest
  text that reads back to the same double (``repr``), normals with 9
  significant digits. Colours (0..1) always have 6 significant digits.

``write_obj_stream`` writes a tessellation given by blocks with the bytes
``write_obj`` gives it whole: the decimals depend on the largest position and
the largest normal, so a first pass over the vertex blocks finds them, and
every ``vn`` line comes after every ``v`` line: the blocks are evaluated once
and read back from a temporary file for the ``v`` and the ``vn`` lines.
"""
from __future__ import annotations

import os

import numpy as np

from ...evaluation.stream.spool import SpooledTessellation
from ..errors import OutputError
from ..finite import refuse_non_finite, refuse_non_finite_mesh, refuse_non_finite_vertices

from .number_text import (FLOAT32_DIGITS, FLOAT64_DIGITS, constant_field, decimals_for, format_fixed, join_columns,
                          printf_field, text_lines)

__all__ = ["write_obj", "write_obj_stream", "write_cage"]

_BLOCK = 1 << 17  # lines per block: bounds the byte matrices to some MB
_HEADER = b"# c1surf\n"
_ATTRIBUTE_HEADER = b"# c1surf: smooth surface with per-vertex attributes\n"


def _numbers(values: np.ndarray, exact: str | None, digits: int):
    """A function (start, stop) -> field of those rows of ``values`` (V, k).

    ``exact``: a ``%`` conversion ("%r") for every number, or None for fixed
    point with the decimals resolving 10**-digits of the largest |value|.
    """
    if exact:
        return lambda a, z: printf_field(values[a:z], exact)
    decimals = decimals_for(values, digits)
    return lambda a, z: format_fixed(np.asarray(values[a:z], dtype=np.float64), decimals)


def _vertex_records(mesh, float32: bool):
    """(prefix, [row formatters], rows) of the v, vt and vn records of ``mesh``."""
    exact = mesh.has_attributes and not float32
    digits = FLOAT32_DIGITS if float32 else FLOAT64_DIGITS
    positions = [_numbers(np.asarray(mesh.points)[:, :3], "%r" if exact else None, digits)]
    colours = mesh.colours
    if colours is not None and colours.shape[1] >= 3:  # OBJ's v x y z r g b has no alpha
        positions.append(_numbers(np.asarray(colours)[:, :3], "%.6g", digits))
    records = [(b"v ", positions, mesh.points.shape[0])]
    if mesh.uv is not None:
        records.append((b"vt ", [_numbers(np.asarray(mesh.uv), "%r" if exact else None, digits)], mesh.uv.shape[0]))
    if mesh.normals is not None:
        normals = np.asarray(mesh.normals)[:, :3]
        records.append((b"vn ", [_numbers(normals, "%.9g" if exact else None, digits)], normals.shape[0]))
    return records


def _corner_fields(index, uv: bool, normals: bool) -> list:
    """Fields of the face corners ``a``, ``a/a``, ``a//a`` or ``a/a/a`` from the field of the indices."""
    m, k = index[0].shape[:2]
    if uv and normals:
        slash = constant_field(b"/", m, k)
        return [index, slash, index, slash, index]
    if uv or normals:
        return [index, constant_field(b"/" if uv else b"//", m, k), index]
    return [index]


def write_obj(path, mesh, float32: bool = False) -> None:
    """Write ``mesh`` (an ``io.meshes.write.TriangleMesh``) as Wavefront OBJ text.

    Parameters
    ----------
    path : str or os.PathLike
    mesh : TriangleMesh, points (V, 3), triangles (T, 3) int 0-based, optional normals (V, 3)
        (non-finite ones written as 0 0 0), uv (V, 2), colours (V, c) in 0..1
    float32 : write float32 precision (fewer digits, smaller file)
    """
    if mesh.properties:
        raise ValueError("per-vertex properties need a .ply output, not .obj")
    refuse_non_finite_mesh(mesh, path)
    _refuse_beyond_fixed_point(_largest(np.asarray(mesh.points)), path)
    triangles = np.asarray(mesh.triangles)
    with open(path, "wb") as f:
        f.write(_ATTRIBUTE_HEADER if mesh.has_attributes else _HEADER)
        for prefix, columns, rows in _vertex_records(mesh, float32):
            for a in range(0, rows, _BLOCK):
                f.write(text_lines(prefix, [join_columns(*(column(a, a + _BLOCK) for column in columns))]))
        for a in range(0, triangles.shape[0], _BLOCK):
            index = format_fixed(triangles[a : a + _BLOCK].astype(np.float64) + 1.0, 0)
            f.write(text_lines(b"f ", _corner_fields(index, mesh.uv is not None, mesh.normals is not None)))


_FIXED_POINT_LIMIT = 9e18  # number_text.format_fixed: int64 digits


def _refuse_beyond_fixed_point(largest: float, path) -> None:
    """OBJ numbers are written in fixed point from int64 digits: magnitudes of 9e18 and more do not fit."""
    if largest >= _FIXED_POINT_LIMIT:
        raise OutputError(path, f"coordinates reach {largest:.3g}: OBJ text is written in fixed point, up to "
                                f"{_FIXED_POINT_LIMIT:.0e}; write .ply, .stl or .glb, or scale the mesh down")


def _largest(values: np.ndarray) -> float:
    """The largest finite magnitude of ``values`` (0 when there is none), as ``decimals_for`` takes it."""
    finite = np.abs(values[np.isfinite(values)])
    return float(finite.max()) if finite.size else 0.0


def write_obj_stream(path, tessellation, float32: bool = False) -> None:
    """Write a tessellation by blocks (``evaluation.stream.StreamedTessellation``): the bytes of ``write_obj``
    for its points, normals and triangles.

    The vertex blocks are evaluated once, for the largest position and normal (the decimals), and kept in
    a temporary file beside ``path`` (``evaluation.stream.SpooledTessellation``) for the ``v`` and then the
    ``vn`` lines.

    Parameters
    ----------
    path : str or os.PathLike
    tessellation : has ``n_vertices``, ``n_triangles``, ``dim``, ``vertex_blocks()`` yielding (points (c, dim),
        normals (c, 3)) float in vertex order and ``triangle_blocks()`` yielding (t, 3) int 0-based in order
    float32 : write float32 precision (fewer digits, smaller file)
    """
    digits = FLOAT32_DIGITS if float32 else FLOAT64_DIGITS
    with SpooledTessellation(tessellation, os.path.dirname(os.path.abspath(path))) as spooled:
        largest = np.zeros(2)
        for points, normals in spooled.vertex_blocks():  # evaluated: the decimals of v and of vn
            refuse_non_finite_vertices(points, normals, path)
            largest = np.maximum(largest, [_largest(points[:, :3]), _largest(normals)])
        _refuse_beyond_fixed_point(largest[0], path)
        decimals = [decimals_for(np.array([value]), digits) for value in largest]
        with open(path, "wb") as f:
            f.write(_HEADER)
            for k, prefix in enumerate((b"v ", b"vn ")):  # positions, then normals: read back
                for block in spooled.vertex_blocks():
                    values = np.asarray(block[k][:, :3], dtype=np.float64)
                    f.write(text_lines(prefix, [format_fixed(values, decimals[k])]))
            for triangles in spooled.triangle_blocks():
                index = format_fixed(triangles.astype(np.float64) + 1.0, 0)
                f.write(text_lines(b"f ", _corner_fields(index, False, True)))


def write_cage(path, points, face_sizes, face_vertices, features=None, comments=()) -> None:
    """Write a polygon control mesh (a SubD cage) as OBJ with OpenSubdiv ``t`` tags, for editing and for
    ``c1surf convert`` (``fit --cage``).

    Every coordinate and sharpness is Python's ``repr`` (the shortest text that reads back to the same double:
    the OBJ reader's ``strtod`` gives the very bits back); vertices and faces keep their order, faces their
    corner order, indices from 1. Tags (indices from 0, as OpenSubdiv writes them): one ``t crease 2/1/0 a b s``
    per crease edge, ``t corner 1/1/0 v s`` per corner, ``t hole k/0/0 f ...`` for the hole faces.

    Parameters
    ----------
    path : str or os.PathLike
    points : (V, 3) float
    face_sizes : (F,) int; face_vertices : (sum(face_sizes),) int, 0-based
    features : has ``crease_edges`` (E, 2), ``crease_sharpness`` (E,), ``corner_vertices`` (C,),
        ``corner_sharpness`` (C,), ``hole_faces`` (H,) (a ``construction.features.SharpFeatures``), or None
    comments : lines written first, each after ``# ``
    """
    points = np.asarray(points, dtype=np.float64)
    refuse_non_finite_vertices(points, np.zeros((0, 3)), path)
    sizes = np.asarray(face_sizes, dtype=np.int64)
    corners = np.asarray(face_vertices, dtype=np.int64)
    with open(path, "wb") as f:
        f.write(b"".join(b"# " + line.encode("utf-8") + b"\n" for line in comments))
        if points.shape[0]:
            f.write(text_lines(b"v ", [printf_field(points[:, :3], "%r")]))
        f.write(_polygon_lines(sizes, corners))
        f.write(_tag_text(features, path).encode("ascii"))


def _polygon_lines(sizes: np.ndarray, corners: np.ndarray) -> bytes:
    """``f a b c ...`` lines (indices from 1) of faces of any sizes, in order: one join over all corners."""
    if sizes.size == 0:
        return b""
    starts = np.zeros(corners.size, dtype=bool)
    starts[np.cumsum(sizes)[:-1]] = True
    separators = np.where(starts, "\nf ", " ").astype(object)
    separators[0] = "f "
    tokens = np.empty(2 * corners.size, dtype=object)
    tokens[0::2], tokens[1::2] = separators, (corners + 1).astype(str)
    return ("".join(tokens) + "\n").encode("ascii")


def _tag_text(features, path) -> str:
    """The OpenSubdiv tag lines of ``features`` (``write_cage``), "" for None."""
    if features is None:
        return ""
    edges, sharpness = np.asarray(features.crease_edges).reshape(-1, 2), np.asarray(features.crease_sharpness)
    corners, corner_sharpness = np.asarray(features.corner_vertices), np.asarray(features.corner_sharpness)
    holes = np.asarray(features.hole_faces).ravel()
    refuse_non_finite(np.r_[sharpness, corner_sharpness], "sharpness values", path)
    creases = [None] * (3 * len(edges))
    creases[0::3], creases[1::3], creases[2::3] = edges[:, 0].tolist(), edges[:, 1].tolist(), sharpness.tolist()
    rows = [v for pair in zip(corners.tolist(), corner_sharpness.tolist()) for v in pair]
    text = ("t crease 2/1/0 %d %d %r\n" * len(edges)) % tuple(creases)
    text += ("t corner 1/1/0 %d %r\n" * len(corners)) % tuple(rows)
    if holes.size:
        text += f"t hole {holes.size}/0/0 " + " ".join(map(str, holes.tolist())) + "\n"
    return text
