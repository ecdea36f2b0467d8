"""The c1surf patch file as NumPy arrays (``.npz``): the JSON content, for large surfaces.

Members (see docs/patch-format.md; P patches, biquadratic first, then bicubic)::

    header       ()          str    JSON of everything but the patches (format, version,
                                    c1surf_version, options, input, counts)
    biquadratic  (Nq,3,3,3)  float64
    bicubic      (Nc,4,4,3)  float64
    source_kind  (P,)        str    "face" | "edge" | "vertex"
    source       (P,2)       int64  (face, -1) | (vertex, -1) | (a, b) for an edge
    corners      (P,4)       int64  corner ids
    edges        (P,4)       int64  side edge ids
    reversed     (P,4)       bool
    neighbours   (P,4,2)     int64  (patch, side) across each side, (-1, -1) on a boundary

Uncompressed and without pickles: ``numpy.load(path)`` reads it (lazily,
member by member), and the zip entries carry a fixed date, so the same
surface always gives the same bytes.
"""
from __future__ import annotations

import io
import json
import mmap
import os
import struct
import zipfile

import numpy as np

from ...evaluation.adjacency import PatchAdjacency
from ..errors import MeshInputError
from ...evaluation.patch_set import FORMAT_NAME, FORMAT_VERSION, PatchSet, surface_patch_set

_DATE = (1980, 1, 1, 0, 0, 0)  # earliest zip date: no clock in the output


def _patch_groups(patch_set: PatchSet):
    """(biquadratic groups, bicubic groups) of a PatchSet; refuses other degrees or orders."""
    quad, cubic = [], []
    seen_cubic = False
    for g in patch_set.groups:
        shape = g.shape[1:3]
        if shape == (3, 3) and not seen_cubic:
            quad.append(g)
        elif shape == (4, 4):
            cubic.append(g)
            seen_cubic = True
        else:
            raise ValueError("the NPZ patch format holds biquadratic patches followed by bicubic ones only")
    return quad, cubic


def _joined(groups, empty_shape) -> np.ndarray:
    """One array of the groups (no copy for a single group)."""
    if not groups:
        return np.zeros(empty_shape)
    return groups[0] if len(groups) == 1 else np.concatenate(groups)


def _members(patch_set: PatchSet):
    """Yield (name, array) of the NPZ members in file order, each made when needed.

    One member at a time: a large surface never holds all of them as copies at once.
    """
    quad, cubic = _patch_groups(patch_set)
    yield "header", np.array(json.dumps(patch_set.header, separators=(",", ":")))
    yield "biquadratic", _joined(quad, (0, 3, 3, 3))
    yield "bicubic", _joined(cubic, (0, 4, 4, 3))
    if patch_set.source_kind is not None:
        yield "source_kind", np.asarray(patch_set.source_kind, dtype="<U6")
        yield "source", np.asarray(patch_set.source, dtype=np.int64)
    if patch_set.adjacency is not None:
        a = patch_set.adjacency
        yield "corners", a.corners.astype(np.int64, copy=False)
        yield "edges", a.edges.astype(np.int64, copy=False)
        yield "reversed", a.reversed.astype(bool, copy=False)
        yield "neighbours", a.neighbours()


def patch_set_arrays(patch_set: PatchSet) -> dict:
    """The NPZ members of a PatchSet (c1surf surfaces: degrees (2, 2) and (3, 3) only)."""
    return dict(_members(patch_set))


def write_patch_set_npz(path, patch_set: PatchSet) -> None:
    """Write a PatchSet as an uncompressed, byte-reproducible ``.npz``."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name, array in _members(patch_set):
            info = zipfile.ZipInfo(name + ".npy", date_time=_DATE)
            info.compress_type = zipfile.ZIP_STORED
            info.external_attr = 0o644 << 16
            with zf.open(info, "w", force_zip64=True) as f:
                np.lib.format.write_array(f, np.ascontiguousarray(array), allow_pickle=False)
            del array


def write_patches_npz(path, surface, input_path: str | None = None, adjacency=None, **_options) -> None:
    """Write ``surface``'s patches to ``path`` as c1surf-patches NPZ (same content as the JSON)."""
    write_patch_set_npz(path, surface_patch_set(surface, input_path, adjacency))


def _mapped_members(path) -> dict:
    """Arrays of an uncompressed ``.npz`` mapped straight from the file (no copy, no CRC pass).

    Members that are compressed (e.g. re-saved with ``numpy.savez_compressed``)
    are read the ordinary way.
    """
    arrays = {}
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        mapped = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) if size else None
        with zipfile.ZipFile(f) as zf:
            for info in zf.infolist():
                if not info.filename.endswith(".npy"):
                    continue
                name = info.filename[:-4]
                if info.compress_type != zipfile.ZIP_STORED or mapped is None:
                    with zf.open(info) as member:
                        arrays[name] = np.lib.format.read_array(member, allow_pickle=False)
                    continue
                local = info.header_offset
                if mapped[local : local + 4] != b"PK\x03\x04":
                    raise ValueError(f"bad local header for {info.filename}")
                name_len, extra_len = struct.unpack("<HH", mapped[local + 26 : local + 30])
                start = local + 30 + name_len + extra_len
                head = io.BytesIO(mapped[start : start + min(info.file_size, 65536)])
                version = np.lib.format.read_magic(head)
                if version == (1, 0):
                    shape, fortran, dtype = np.lib.format.read_array_header_1_0(head)
                else:
                    shape, fortran, dtype = np.lib.format.read_array_header_2_0(head)
                if dtype.hasobject:
                    raise ValueError(f"{name} holds Python objects (pickles are not read)")
                count = int(np.prod(shape, dtype=np.int64))
                offset = start + head.tell()
                if offset + count * dtype.itemsize > start + info.file_size:
                    raise ValueError(f"{name} is truncated")
                flat = np.frombuffer(mapped, dtype=dtype, count=count, offset=offset)
                arrays[name] = flat.reshape(shape, order="F" if fortran else "C")
    return arrays


def read_patch_set_npz(path) -> PatchSet:
    """Read a c1surf-patches ``.npz``: patches in file order, sources, adjacency, header.

    The arrays are memory-mapped read-only views of the file (uncompressed
    members), so opening even a large surface takes milliseconds.
    """
    try:
        data = _mapped_members(path)
    except FileNotFoundError:
        raise MeshInputError(str(path), "no such file") from None
    except IsADirectoryError:
        raise MeshInputError(str(path), "is a directory, not a patch file") from None
    except (OSError, ValueError, EOFError, struct.error, zipfile.BadZipFile) as e:
        raise MeshInputError(str(path), f"not an NPZ patch file ({e})") from None
    names = set(data)
    if "header" not in names:
        raise MeshInputError(str(path), f'not a c1surf patch file (no "header" member with "format": "{FORMAT_NAME}")')
    try:
        header = json.loads(str(data["header"].item()))
    except (ValueError, TypeError) as e:
        raise MeshInputError(str(path), f"damaged header ({e})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT_NAME:
        raise MeshInputError(str(path), f'not a c1surf patch file (missing "format": "{FORMAT_NAME}")')
    if header.get("version") != FORMAT_VERSION:
        raise MeshInputError(str(path), f"patch file version {header.get('version')} is not supported (this c1surf reads version {FORMAT_VERSION})")
    quad = data.get("biquadratic", np.zeros((0, 3, 3, 3)))
    cubic = data.get("bicubic", np.zeros((0, 4, 4, 3)))
    for name, g, n in (("biquadratic", quad, 3), ("bicubic", cubic, 4)):
        if g.dtype != np.float64 or g.ndim != 4 or g.shape[1:] != (n, n, 3):
            raise MeshInputError(str(path), f"{name} must be float64 of shape (N, {n}, {n}, 3), got {g.dtype} {g.shape}")
        if not np.isfinite(g).all():
            raise MeshInputError(str(path), f"{name} holds NaN or infinite coordinates")
    p = len(quad) + len(cubic)
    source_kind = source = adjacency = None
    if {"source_kind", "source"} <= names:
        source_kind, source = data["source_kind"], data["source"]
        if source_kind.shape != (p,) or source.shape != (p, 2) or source.dtype.kind != "i":
            raise MeshInputError(str(path), f"source_kind / source must have shapes ({p},) / ({p}, 2)")
    if {"corners", "edges", "reversed"} <= names:
        try:
            adjacency = PatchAdjacency(np.asarray(data["corners"], dtype=np.int64), np.asarray(data["edges"], dtype=np.int64),
                                       np.asarray(data["reversed"], dtype=bool))
            adjacency.validate(p)
        except (TypeError, ValueError) as e:
            raise MeshInputError(str(path), f"malformed patch adjacency ({e})") from None
    groups = [g for g in (quad, cubic) if len(g)]
    return PatchSet(groups, adjacency, source_kind, source, header)


__all__ = ["write_patches_npz", "write_patch_set_npz", "read_patch_set_npz", "patch_set_arrays"]
