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

_BLOCK = 1 << 18  # lines per block: bounds the byte matrices to some tens of MB
_DIGITS = np.frombuffer(b"0123456789", dtype=np.uint8)
_MINUS, _DOT, _NEWLINE = ord("-"), ord("."), ord("\n")


def _decimals(values: np.ndarray, relative_digits: int) -> int:
    """Decimals that resolve 10**-relative_digits of the largest finite magnitude."""
    finite = np.abs(values[np.isfinite(values)])
    largest = float(finite.max()) if finite.size else 0.0
    if largest <= 0.0:
        return 1
    return int(max(0, relative_digits - np.ceil(np.log10(largest))))


def format_fixed(values: np.ndarray, decimals: int):
    """Characters of ``values`` (m, k) in fixed point: a (m, k, width) uint8 array and its keep mask.

    Non-finite values are written as 0. Negative zero is written as 0.
    """
    values = np.where(np.isfinite(values), values, 0.0)
    scale = 10.0 ** decimals
    scaled = np.rint(np.abs(values) * scale)
    if scaled.size and scaled.max() >= 9e18:
        raise OverflowError("values too large for fixed-point text; use a binary format")
    scaled = scaled.astype(np.int64)
    integer_digits = max(1, len(str(int(scaled.max() // int(scale))))) if scaled.size else 1
    ndigits = integer_digits + decimals
    width = 1 + integer_digits + (1 + decimals if decimals else 0)
    m, k = values.shape
    chars = np.empty((m, k, width), dtype=np.uint8)
    keep = np.ones((m, k, width), dtype=bool)
    negative = (values < 0) & (scaled > 0)
    chars[..., 0] = _MINUS
    keep[..., 0] = negative
    # digit j (0 = least significant) goes to column width - 1 - j, skipping the dot
    rest = scaled.copy()
    significant = np.zeros((m, k), dtype=bool)  # a nonzero digit at or right of this one (fraction)
    for j in range(ndigits):
        digit = rest % 10
        rest //= 10
        column = width - 1 - j if j < decimals else width - 2 - j if decimals else width - 1 - j
        chars[..., column] = _DIGITS[digit]
        if j < decimals:  # trailing zeros of the fraction are dropped
            significant |= digit != 0
            keep[..., column] = significant
    if decimals:
        chars[..., width - 1 - decimals] = _DOT
        keep[..., width - 1 - decimals] = significant
    # leading zeros of the integer part are dropped, the units digit is kept
    first_integer_column = 1
    units_column = width - 2 - decimals if decimals else width - 1
    power = scaled // int(scale)
    for column in range(first_integer_column, units_column):
        digits_right = units_column - column  # this column holds 10**digits_right
        keep[..., column] = power >= 10 ** digits_right
    return chars, keep


def _lines(prefix: bytes, fields: list, separator: bytes = b" ") -> np.ndarray:
    """Assemble lines ``prefix f1 sep f2 ... \\n`` from (chars, keep) fields of m rows; 1-D uint8."""
    parts, masks = [], []
    m = fields[0][0].shape[0]
    if prefix:
        p = np.frombuffer(prefix, dtype=np.uint8)
        parts.append(np.broadcast_to(p, (m, p.size)))
        masks.append(np.ones((m, p.size), dtype=bool))
    for i, (chars, keep) in enumerate(fields):
        if i:
            s = np.frombuffer(separator, dtype=np.uint8)
            parts.append(np.broadcast_to(s, (m, s.size)))
            masks.append(np.ones((m, s.size), dtype=bool))
        parts.append(chars.reshape(m, -1))
        masks.append(keep.reshape(m, -1))
    parts.append(np.full((m, 1), _NEWLINE, dtype=np.uint8))
    masks.append(np.ones((m, 1), dtype=bool))
    return np.concatenate(parts, axis=1)[np.concatenate(masks, axis=1)]


def _interleave(chars: np.ndarray, keep: np.ndarray, between: bytes):
    """Join the k fields of each row (m, k, w) with ``between``: one (m, 1, w') field."""
    m, k, w = chars.shape
    b = np.frombuffer(between, dtype=np.uint8)
    out = np.empty((m, k, w + b.size), dtype=np.uint8)
    mask = np.ones((m, k, w + b.size), dtype=bool)
    out[..., :w], mask[..., :w] = chars, keep
    out[..., w:] = b
    mask[:, -1, w:] = False  # no separator after the last field
    return out.reshape(m, 1, -1), mask.reshape(m, 1, -1)


def write_obj(path, points: np.ndarray, triangles: np.ndarray, normals: np.ndarray | None = None,
              float32: bool = False) -> None:
    """Write a triangle mesh as Wavefront OBJ text (``v``, ``vn``, ``f a//a b//b c//c``).

    Parameters
    ----------
    points : (V, 3) float; triangles : (T, 3) int, 0-based
    normals : (V, 3) float or None, per-vertex unit normals (non-finite ones written as 0 0 0)
    float32 : write float32 precision (fewer digits, smaller file)
    """
    points = np.asarray(points, dtype=np.float64)[:, :3]
    triangles = np.asarray(triangles)
    digits = 8 if float32 else 15
    with open(path, "wb") as f:
        f.write(b"# c1surf\n")
        for array, prefix in ((points, b"v "), (normals, b"vn ")):
            if array is None:
                continue
            array = np.asarray(array, dtype=np.float64)[:, :3]
            decimals = _decimals(array, digits)
            for a in range(0, array.shape[0], _BLOCK):
                chars, keep = format_fixed(array[a : a + _BLOCK], decimals)
                f.write(_lines(prefix, [_interleave(chars, keep, b" ")]).tobytes())
        for a in range(0, triangles.shape[0], _BLOCK):
            block = triangles[a : a + _BLOCK].astype(np.int64) + 1
            chars, keep = format_fixed(block.astype(np.float64), 0)
            if normals is not None:  # a//a: the vertex's own normal
                m, k, w = chars.shape
                both = np.concatenate([chars, np.broadcast_to(np.frombuffer(b"//", np.uint8), (m, k, 2)), chars], axis=2)
                mask = np.concatenate([keep, np.ones((m, k, 2), dtype=bool), keep], axis=2)
                chars, keep = both, mask
            f.write(_lines(b"f ", [_interleave(chars, keep, b" ")]).tobytes())


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
