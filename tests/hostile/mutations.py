"""Seeded mutations of a valid input file (issue 42): what an attacker or a broken disk makes of it.

Every mutation is a function ``(rng, data: bytes, suffix) -> (bytes, label)`` of a ``random.Random``; the
label says what was done, so a failing case reads as ``cube.step: number 1e308 at byte 5121`` and is
reproduced from its seed alone. Kinds: bits flipped, truncated, a chunk deleted or inserted (random bytes or a
copy of another part), a number replaced by a hostile value (text), a binary number overwritten (binary PLY
and STL), a line repeated (twice or a thousand times), two lines swapped, a line deleted; NPZ and JSON also by
value (an array element, a shape, a dtype, a member; a JSON leaf or key).
"""
from __future__ import annotations

import io
import json
import random
import re
import struct
import warnings
import zipfile

import numpy as np

HOSTILE_NUMBERS = [b"1e308", b"-1e308", b"1e309", b"-0", b"0x10", b"nan", b"-nan", b"inf", b"18446744073709551617",
                   b"-18446744073709551617", b"9223372036854775807", b"2147483648", b"4294967296", b"1e-320",
                   b"0", b"-1", b"1e22", b"99999999", b"", b"x", b"1e", b"--1", b"1.5.5", b"3e38", b"1e100"]
_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_BINARY_VALUES = [struct.pack("<f", v) for v in (float("nan"), float("inf"), -float("inf"), 3e38, -0.0, 1e-45)] + [
    struct.pack("<i", v) for v in (-1, 2**31 - 1, -2**31, 2**24, 0)] + [struct.pack("<d", v) for v in (1e308,)]
_JSON_VALUES = [float("nan"), float("inf"), 1e308, -1e308, 18446744073709551617, -1, 0, 2**63, 1.5, "x", None,
                [], {}, True, [[[[[]]]]], [1e308] * 3, "18446744073709551617"]
_NPZ_VALUES = [np.nan, np.inf, -np.inf, 1e308, -1e308, 1e-320, -0.0, 2**62, -1, 0, 18446744073709551615]


def mutate(seed: int, data: bytes, suffix: str) -> tuple[bytes, str]:
    """One seeded mutation of ``data`` (the bytes of a ``suffix`` file): (mutated bytes, what was done)."""
    rng = random.Random(seed)
    kinds = list(BYTE_MUTATIONS)
    if suffix in (".obj", ".off", ".json", ".igs", ".step", ".ply", ".stl", ".usda"):
        kinds += [number_replaced] * 4 + [line_repeated, lines_swapped, line_deleted]
    if suffix in (".ply", ".stl"):
        kinds += [binary_number] * 2
    if suffix == ".npz":
        kinds += [npz_value] * 6
    if suffix == ".json":
        kinds += [json_value] * 4
    return rng.choice(kinds)(rng, data, suffix)


def bits_flipped(rng, data, suffix):
    out = bytearray(data)
    count = rng.choice([1, 1, 2, 8])
    where = [rng.randrange(len(out)) for _ in range(count)]
    for k in where:
        out[k] ^= 1 << rng.randrange(8)
    return bytes(out), f"{count} bit(s) flipped at byte {where[0]}"


def truncated(rng, data, suffix):
    k = rng.randrange(len(data))
    return data[:k], f"truncated at byte {k}"


def chunk_deleted(rng, data, suffix):
    k, n = rng.randrange(len(data)), rng.choice([1, 4, 16, 64, 512])
    return data[:k] + data[k + n:], f"{n} bytes deleted at byte {k}"


def chunk_inserted(rng, data, suffix):
    k, n = rng.randrange(len(data) + 1), rng.choice([1, 4, 16, 64, 512])
    if rng.random() < 0.5:
        chunk = bytes(rng.randrange(256) for _ in range(n))
        what = "random"
    else:
        start = rng.randrange(len(data))
        chunk = data[start:start + n]
        what = f"copied from byte {start}"
    return data[:k] + chunk + data[k:], f"{len(chunk)} bytes ({what}) inserted at byte {k}"


BYTE_MUTATIONS = [bits_flipped, truncated, chunk_deleted, chunk_inserted]


def number_replaced(rng, data, suffix):
    """A number of the text (of the text header of a binary file) replaced by a hostile value."""
    numbers = list(_NUMBER.finditer(data))
    if not numbers:
        return bits_flipped(rng, data, suffix)
    match, value = rng.choice(numbers), rng.choice(HOSTILE_NUMBERS)
    return data[:match.start()] + value + data[match.end():], f"number {value.decode() or '(empty)'} at byte {match.start()}"


def binary_number(rng, data, suffix):
    """A 4-byte (or 8-byte) word past the header overwritten by a hostile float or integer."""
    start = data.find(b"end_header") + 11 if suffix == ".ply" else 80
    if start >= len(data) - 8 or b"end_header" not in data and suffix == ".ply":
        return bits_flipped(rng, data, suffix)
    k = start + 4 * rng.randrange((len(data) - start - 8) // 4)
    value = rng.choice(_BINARY_VALUES)
    return data[:k] + value + data[k + len(value):], f"binary word {value.hex()} at byte {k}"


def _lines(data):
    return data.splitlines(keepends=True)


def line_repeated(rng, data, suffix):
    lines = _lines(data)
    k, n = rng.randrange(len(lines)), rng.choice([2, 3, 1000])
    return b"".join(lines[:k] + [lines[k]] * n + lines[k + 1:]), f"line {k + 1} repeated {n} times"


def lines_swapped(rng, data, suffix):
    lines = _lines(data)
    a, b = rng.randrange(len(lines)), rng.randrange(len(lines))
    lines[a], lines[b] = lines[b], lines[a]
    return b"".join(lines), f"lines {a + 1} and {b + 1} swapped"


def line_deleted(rng, data, suffix):
    lines = _lines(data)
    k = rng.randrange(len(lines))
    return b"".join(lines[:k] + lines[k + 1:]), f"line {k + 1} deleted"


def npz_value(rng, data, suffix):
    """An NPZ member changed by value: an element, its shape, its dtype; or a member dropped or added."""
    with np.load(io.BytesIO(data), allow_pickle=False) as archive:
        members = {name: archive[name] for name in archive.files}
    name = rng.choice(sorted(members))
    array = members[name]
    how = rng.choice(["element", "element", "element", "shape", "dtype", "drop", "add", "empty"])
    if how == "element" and array.size:
        array = array.copy()
        value = rng.choice(_NPZ_VALUES)
        if array.dtype.kind in "iu" and isinstance(value, float) and not np.isfinite(value):
            array = array.astype(np.float64)
        try:
            array.flat[rng.randrange(array.size)] = value
        except (OverflowError, ValueError):
            array = array.astype(np.float64)
            array.flat[rng.randrange(array.size)] = value
        what = f"{name}[.] = {value}"
    elif how == "shape" and array.size:
        array = array.reshape(-1)[: max(0, array.size - rng.choice([1, 3]))]
        what = f"{name} cut to {array.size} elements"
    elif how == "dtype":
        dtype = rng.choice([np.float32, np.int8, np.uint64, np.complex128, np.bool_])
        try:
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore")
                array = array.astype(dtype)
        except (TypeError, ValueError):  # a header string has no such type: given as a number array instead
            array = np.zeros(3, dtype)
        what = f"{name} as {np.dtype(dtype).name}"
    elif how == "drop":
        del members[name]
        return _npz(members), f"member {name} dropped"
    elif how == "add":
        members[f"x{rng.randrange(9)}"] = np.full(3, np.nan)
        return _npz(members), "a member of NaN added"
    else:
        array = array[:0]
        what = f"{name} emptied"
    members[name] = array
    return _npz(members), what


def _npz(members: dict) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as archive:
        for name, array in members.items():
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, np.asarray(array), allow_pickle=False)
            archive.writestr(name + ".npy", buffer.getvalue())
    return out.getvalue()


def json_value(rng, data, suffix):
    """A JSON leaf or list element replaced by a hostile value, or a key deleted."""
    try:
        document = json.loads(data)
    except ValueError:
        return number_replaced(rng, data, suffix)
    paths = list(_json_paths(document, ()))
    if not paths:
        return number_replaced(rng, data, suffix)
    path = rng.choice(paths)
    parent = document
    for key in path[:-1]:
        parent = parent[key]
    if isinstance(parent, dict) and rng.random() < 0.2:
        del parent[path[-1]]
        what = f"key {'/'.join(map(str, path))} deleted"
    else:
        value = rng.choice(_JSON_VALUES)
        parent[path[-1]] = value
        what = f"{'/'.join(map(str, path))} = {json.dumps(value)[:40]}"
    return json.dumps(document).encode(), what


def _json_paths(node, path, depth=0):
    """The paths to every leaf and container of a JSON document (long lists sampled: at most 8 elements)."""
    if depth > 40:
        return
    if isinstance(node, dict):
        items = list(node.items())
    elif isinstance(node, list):
        items = list(enumerate(node))[:8]
    else:
        return
    for key, value in items:
        yield path + (key,)
        yield from _json_paths(value, path + (key,), depth + 1)
