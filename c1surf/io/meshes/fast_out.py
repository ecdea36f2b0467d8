"""Vectorized writers for large triangle meshes: text OBJ and plain binary PLY.

No Python object per vertex or face: numbers are turned into characters with
array arithmetic (digit by digit over whole columns), and lines are assembled
as one byte matrix per block whose padding is dropped with a mask.

Text precision: every coordinate is written in fixed point with the decimals
that resolve ``10**-15`` (float64) or ``10**-8`` (float32) of the largest
magnitude in its column group, trailing zeros dropped. That is float64 (or
float32) precision relative to the size of the model, for any model size.
"""
from __future__ import annotations

import numpy as np

__all__ = ["write_obj", "write_ply_plain", "format_fixed"]

_BLOCK = 1 << 17  # lines per block: bounds the byte matrices to some MB
_DIGITS = np.frombuffer(b"0123456789", dtype=np.uint8)
_MINUS, _DOT, _NEWLINE = ord("-"), ord("."), ord("\n")


def _decimals(values: np.ndarray, relative_digits: int) -> int:
    """Decimals that resolve 10**-relative_digits of the largest finite magnitude."""
    finite = np.abs(values[np.isfinite(values)])
    largest = float(finite.max()) if finite.size else 0.0
    if largest <= 0.0:
        return 1
    return int(max(0, relative_digits - np.ceil(np.log10(largest))))


_TABLE = np.array([list(f"{i:04d}".encode()) for i in range(10000)], dtype=np.uint8)  # "0000" .. "9999"
_TABLE32 = _TABLE.view(np.uint32).ravel()  # the same, one 4-byte entry per number


def format_fixed(values: np.ndarray, decimals: int):
    """Characters of ``values`` (m, k) in fixed point: a (m, k, width) uint8 array and its keep mask.

    Four digits at a time from a table; leading zeros of the integer part and
    trailing zeros of the fraction are masked out (the units digit stays).
    Non-finite values are written as 0, and so is negative zero.
    """
    values = np.where(np.isfinite(values), values, 0.0)
    scale = 10.0 ** decimals
    scaled = np.rint(np.abs(values) * scale)
    if scaled.size and scaled.max() >= 9e18:
        raise OverflowError("values too large for fixed-point text; use a binary format")
    scaled = scaled.astype(np.int64)
    m, k = values.shape
    largest = int(scaled.max()) if scaled.size else 0
    groups = max(1, -(-max(len(str(largest)), decimals + 1) // 4))
    packed = np.empty((m, k, groups), dtype=np.uint32)  # four characters per entry, most significant first
    rest = scaled
    for g in range(groups):
        rest, chunk = np.divmod(rest, 10000)
        packed[..., groups - 1 - g] = _TABLE32[chunk]
    digits = packed.view(np.uint8)
    integer = 4 * groups - decimals  # integer digit columns (with leading zeros)
    width = 1 + integer + (1 + decimals if decimals else 0)
    chars = np.empty((m, k, width), dtype=np.uint8)
    keep = np.empty((m, k, width), dtype=bool)
    chars[..., 0] = _MINUS
    keep[..., 0] = (values < 0) & (scaled > 0)
    chars[..., 1 : 1 + integer] = digits[..., :integer]
    # digits of the integer part: 1 + number of powers of ten it reaches
    powers = 10 ** np.arange(1, integer, dtype=np.int64)
    whole = scaled // 10**decimals if decimals < 19 else np.zeros_like(scaled)  # scaled < 9e18 < 10**decimals
    count = 1 + np.searchsorted(powers, whole, side="right")
    keep[..., 1 : 1 + integer] = np.arange(integer) >= (integer - count)[..., None]
    if decimals:
        fraction = digits[..., integer:]
        chars[..., 1 + integer] = _DOT
        chars[..., 2 + integer :] = fraction
        # a fraction digit stays when it or a digit right of it is not zero
        significant = np.logical_or.accumulate(fraction[..., ::-1] != ord("0"), axis=-1)[..., ::-1]
        keep[..., 2 + integer :] = significant
        keep[..., 1 + integer] = significant[..., 0]
    return chars, keep


def _lines(prefix: bytes, fields, separator: bytes = b" ") -> bytes:
    """Lines ``prefix f_1 sep f_2 ... f_k\n`` from the (chars, keep) of (m, k, w) fields, as bytes.

    ``fields`` is a list of (chars, keep) pairs written one after the other
    (without separator) in each of the k slots, e.g. ``a``, ``//``, ``a``.
    """
    m, k = fields[0][0].shape[:2]
    widths = [c.shape[2] for c, _ in fields]
    slot = sum(widths) + len(separator)
    line = len(prefix) + k * slot - len(separator) + 1
    chars = np.empty((m, line), dtype=np.uint8)
    keep = np.ones((m, line), dtype=bool)
    chars[:, : len(prefix)] = np.frombuffer(prefix, dtype=np.uint8)
    for j in range(k):
        at = len(prefix) + j * slot
        for (c, kp), w in zip(fields, widths):
            chars[:, at : at + w] = c[:, j]
            keep[:, at : at + w] = kp[:, j]
            at += w
        if j < k - 1:
            chars[:, at : at + len(separator)] = np.frombuffer(separator, dtype=np.uint8)
    chars[:, -1] = _NEWLINE
    return chars[keep].tobytes()


def _constant(text: bytes, m: int, k: int):
    """(chars, keep) of the same short text in every slot."""
    c = np.broadcast_to(np.frombuffer(text, dtype=np.uint8), (m, k, len(text)))
    return c, np.ones((m, k, len(text)), dtype=bool)


def write_obj(path, points: np.ndarray, triangles: np.ndarray, normals: np.ndarray | None = None,
              float32: bool = False) -> None:
    """Write a triangle mesh as Wavefront OBJ text (``v``, ``vn``, ``f a//a b//b c//c``).

    Parameters
    ----------
    points : (V, 3) float; triangles : (T, 3) int, 0-based
    normals : (V, 3) float or None, per-vertex unit normals (non-finite ones written as 0 0 0)
    float32 : write float32 precision (fewer digits, smaller file)
    """
    points = np.asarray(points)[:, :3]
    triangles = np.asarray(triangles)
    digits = 8 if float32 else 15
    with open(path, "wb") as f:
        f.write(b"# c1surf\n")
        for array, prefix in ((points, b"v "), (normals, b"vn ")):
            if array is None:
                continue
            array = np.asarray(array)[:, :3]
            decimals = _decimals(array, digits)
            for a in range(0, array.shape[0], _BLOCK):
                f.write(_lines(prefix, [format_fixed(np.asarray(array[a : a + _BLOCK], dtype=np.float64), decimals)]))
        for a in range(0, triangles.shape[0], _BLOCK):
            index = format_fixed(triangles[a : a + _BLOCK].astype(np.float64) + 1.0, 0)
            fields = [index] if normals is None else [index, _constant(b"//", *index[0].shape[:2]), index]
            f.write(_lines(b"f ", fields))


def write_ply_plain(path, points: np.ndarray, triangles: np.ndarray, normals: np.ndarray | None = None,
                    float32: bool = False) -> None:
    """Binary little-endian PLY: ``x y z [nx ny nz]`` as double (or float) and int triangles."""
    points = np.asarray(points)[:, :3]
    triangles = np.asarray(triangles)
    kind, name = ("<f4", "float") if float32 else ("<f8", "double")
    fields = [(a, kind) for a in ("x", "y", "z")] + ([(a, kind) for a in ("nx", "ny", "nz")] if normals is not None else [])
    header = ["ply", "format binary_little_endian 1.0", "comment c1surf", f"element vertex {points.shape[0]}"]
    header += [f"property {name} {a}" for a, _ in fields]
    header += [f"element face {triangles.shape[0]}", "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode("ascii"))
        for a in range(0, points.shape[0], _BLOCK * 4):
            z = min(points.shape[0], a + _BLOCK * 4)
            vertex = np.empty(z - a, dtype=fields)
            for k, axis in enumerate("xyz"):
                vertex[axis] = points[a:z, k]
            if normals is not None:
                for k, axis in enumerate(("nx", "ny", "nz")):
                    vertex[axis] = normals[a:z, k]
            f.write(vertex.tobytes())
        for a in range(0, triangles.shape[0], _BLOCK * 4):
            z = min(triangles.shape[0], a + _BLOCK * 4)
            face = np.empty(z - a, dtype=[("n", "u1"), ("i", "<i4", (3,))])
            face["n"] = 3
            face["i"] = triangles[a:z]
            f.write(face.tobytes())
