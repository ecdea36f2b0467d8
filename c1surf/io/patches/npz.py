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
    biquadratic_weights (Nq,3,3), bicubic_weights (Nc,4,4)  float64   rational patches only (A2a)
    merged_spans (K,2)       int64  (m, n) spans of each merged piece (convert --merge only), then
    merged_points, merged_weights, merged_knots_u, merged_knots_v, merged_patches, merged_rotation:
                                    the pieces' arrays flattened and concatenated (docs/patch-format.md)

Uncompressed and without pickles: ``numpy.load(path)`` reads it (lazily,
member by member), and the zip entries carry a fixed date, so the same
surface always gives the same bytes. ``write_patch_stream_npz`` writes those
bytes from a ``PatchStream`` (the streamed conversion): the coefficient
members by blocks of patches, the integers whole.
"""
from __future__ import annotations

import io
import json
import mmap
import os
import struct
import tokenize
import zipfile

import numpy as np

from ...evaluation.patch_set import FORMAT_NAME, SOURCE_KINDS, PatchSet
from ..errors import MeshInputError
from ..finite import refuse_non_finite
from .checks import check_crease_sides, check_header, checked_adjacency, checked_piece, checked_weights, whole_numbers

_DATE = (1980, 1, 1, 0, 0, 0)  # earliest zip date: no clock in the output
_MAX_RATIO = 100  # largest expansion of a compressed member read (float arrays compress 1-3 times)
_STREAM_BLOCK = 1 << 15  # patches per block of a streamed file (bicubic: 12 MB)


def _patch_groups(groups: list):
    """(biquadratic groups, bicubic groups) of a PatchSet's groups (or weights); refuses other degrees or orders."""
    quad, cubic = [], []
    seen_cubic = False
    for g in groups:
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
    quad, cubic = _patch_groups(patch_set.groups)
    yield "header", _header_member(patch_set.header)
    yield "biquadratic", _joined(quad, (0, 3, 3, 3))
    yield "bicubic", _joined(cubic, (0, 4, 4, 3))
    yield from _bookkeeping_members(patch_set.source_kind, patch_set.source, patch_set.adjacency)
    if patch_set.weights is not None:
        quad_w, cubic_w = _patch_groups(patch_set.weights)
        yield "biquadratic_weights", _joined(quad_w, (0, 3, 3))
        yield "bicubic_weights", _joined(cubic_w, (0, 4, 4))
    if patch_set.merged:
        yield from _merged_members(patch_set.merged)


def _merged_members(pieces):
    """(name, array) of the merged pieces: their (m, n) spans, then each array of all pieces flattened in turn."""
    yield "merged_spans", np.array([piece.patches.shape for piece in pieces], dtype=np.int64).reshape(-1, 2)
    yield "merged_points", np.concatenate([piece.points[..., :3].reshape(-1, 3) for piece in pieces])
    if pieces[0].weights is not None:
        yield "merged_weights", np.concatenate([piece.weights.ravel() for piece in pieces])
    for name in ("knots_u", "knots_v", "patches", "rotation"):
        yield f"merged_{name}", np.concatenate([np.ravel(getattr(piece, name)) for piece in pieces])


def _header_member(header: dict) -> np.ndarray:
    return np.array(json.dumps(header, separators=(",", ":")))


def _bookkeeping_members(source_kind, source, adjacency):
    """(name, array) of the sources and the adjacency (integers), those present."""
    if source_kind is not None:
        yield "source_kind", np.asarray(source_kind, dtype="<U6")
        yield "source", np.asarray(source, dtype=np.int64)
    if adjacency is not None:
        yield "corners", adjacency.corners.astype(np.int64, copy=False)
        yield "edges", adjacency.edges.astype(np.int64, copy=False)
        yield "reversed", adjacency.reversed.astype(bool, copy=False)
        yield "neighbours", adjacency.neighbours()


class _Blocks:
    """A member written by blocks: the .npy header of ``shape`` and ``dtype``, then each block's bytes in order.

    shape : tuple of int; dtype : numpy dtype; blocks : iterable of C-contiguous arrays of ``dtype``, rows of
    ``shape`` adding up to shape[0]
    """

    def __init__(self, shape: tuple, dtype, blocks):
        self.shape, self.dtype, self.blocks = tuple(int(n) for n in shape), np.dtype(dtype), blocks

    def write(self, f, path="output", name: str = "array") -> None:
        """The bytes ``np.lib.format.write_array`` writes for the whole array (a header of format 1.0); each
        block's numbers are finite (``refuse_non_finite``, naming ``path`` and the member ``name``)."""
        descr = np.lib.format.dtype_to_descr(self.dtype)
        np.lib.format.write_array_header_1_0(f, {"descr": descr, "fortran_order": False, "shape": self.shape})
        rows = 0
        for block in self.blocks:
            refuse_non_finite(block, f"'{name}' values", path)
            f.write(np.ascontiguousarray(block, dtype=self.dtype).tobytes())
            rows += block.shape[0]
        if rows != self.shape[0]:
            raise ValueError(f"internal: the blocks gave {rows} rows, the header says {self.shape[0]}")


def _stream_members(stream, size: int):
    """(name, array or _Blocks) of the NPZ members of a ``PatchStream``: every array by blocks of ``size`` patches."""
    yield "header", _header_member(stream.header)
    for kind, (name, k) in enumerate((("biquadratic", 3), ("bicubic", 4))):
        yield name, _Blocks((stream.counts[kind], k, k, 3), np.float64, (c for _, c in stream.blocks(kind, size)))
    p = stream.n_patches
    for name, row, dtype in stream.INTEGERS:
        rows = (stream.integers(name, a, min(a + size, p)) for a in range(0, p, size))
        yield name, _Blocks((p, *row), dtype, rows)


def write_patch_set_npz(path, patch_set: PatchSet, **_options) -> None:
    """Write a PatchSet as an uncompressed, byte-reproducible ``.npz`` (weights and merged pieces included).

    The options of other formats (IGES units, ...) do not apply.
    """
    _write_members(path, _members(patch_set))


def write_patch_stream_npz(path, stream, **_options) -> None:
    """Write a ``evaluation.patch_set.PatchStream``: the bytes ``write_patch_set_npz`` writes for the surface's
    ``PatchSet`` (no weights, no merged pieces), the coefficients by blocks, never all held."""
    _write_members(path, _stream_members(stream, _STREAM_BLOCK))


def _write_members(path, members) -> None:
    """Write (name, array or ``_Blocks``) members into a zip of stored ``name.npy`` entries with a fixed date."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name, array in members:
            info = zipfile.ZipInfo(name + ".npy", date_time=_DATE)
            info.compress_type = zipfile.ZIP_STORED
            info.external_attr = 0o644 << 16
            with zf.open(info, "w", force_zip64=True) as f:
                if isinstance(array, _Blocks):
                    array.write(f, path, name)
                else:
                    refuse_non_finite(array, f"'{name}' values", path)
                    np.lib.format.write_array(f, np.ascontiguousarray(array), allow_pickle=False)
            del array


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
                    if info.file_size > _MAX_RATIO * info.compress_size + (1 << 20):  # real arrays: 1-3 times
                        raise ValueError(f"member {info.filename} would expand {info.compress_size} bytes into "
                                         f"{info.file_size}: refused as a zip bomb")
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
    """Read a c1surf-patches ``.npz``: patches in file order, weights, sources, adjacency, merged pieces, header.

    The arrays are memory-mapped read-only views of the file (uncompressed
    members), so opening even a large surface takes milliseconds.
    """
    data = _open(path)
    header = _header(path, data)
    quad, cubic = _patches(path, data, "biquadratic", 3), _patches(path, data, "bicubic", 4)
    p = len(quad) + len(cubic)
    source_kind = source = adjacency = None
    if {"source_kind", "source"} <= set(data):
        source_kind, source = data["source_kind"], data["source"]
        if source_kind.shape != (p,) or source.shape != (p, 2) or source.dtype.kind != "i":
            raise MeshInputError(str(path), f"source_kind / source must have shapes ({p},) / ({p}, 2)")
        if not np.isin(source_kind, SOURCE_KINDS).all():
            raise MeshInputError(str(path), f"source_kind must be one of {', '.join(SOURCE_KINDS)}")
    if {"corners", "edges", "reversed"} <= set(data):
        adjacency = checked_adjacency(path, data["corners"], data["edges"], data["reversed"], p)
    weights = None
    if "biquadratic_weights" in data or "bicubic_weights" in data:
        weights = [checked_weights(path, f"{name}_weights", data.get(f"{name}_weights"), g.shape[:3])
                   for name, g in (("biquadratic", quad), ("bicubic", cubic)) if len(g)]
    groups = [g for g in (quad, cubic) if len(g)]
    check_crease_sides(path, header, len(quad) + len(cubic))
    return PatchSet(groups, adjacency, source_kind, source, header, weights, _merged(path, data, len(quad)))


def _open(path) -> dict:
    """The members of the NPZ file ``path`` (see ``_mapped_members``), or a one-line refusal."""
    try:
        return _mapped_members(path)
    except FileNotFoundError:
        raise MeshInputError(str(path), "no such file") from None
    except IsADirectoryError:
        raise MeshInputError(str(path), "is a directory, not a patch file") from None
    except zipfile.BadZipFile as e:
        raise MeshInputError(str(path), f"not an NPZ patch file: not a readable zip archive ({e})") from None
    except (SyntaxError, tokenize.TokenError):  # numpy parses a member's .npy header as a Python literal
        raise MeshInputError(str(path), "not an NPZ patch file (the .npy header of a member is damaged)") from None
    except (OSError, ValueError, EOFError, struct.error) as e:
        text = str(e)
        if "header" in text.lower() and ("parse" in text.lower() or "magic" in text.lower()):
            text = "the .npy header of a member is damaged"  # numpy quotes the damaged bytes
        raise MeshInputError(str(path), f"not an NPZ patch file ({text[:120]})") from None


def _header(path, data: dict) -> dict:
    """The "header" member, checked to be a c1surf patch file of a version this c1surf reads."""
    if "header" not in data:
        raise MeshInputError(str(path), f'not a c1surf patch file (no "header" member with "format": "{FORMAT_NAME}")')
    try:
        header = json.loads(str(data["header"].item()))
    except (ValueError, TypeError, OverflowError) as e:
        raise MeshInputError(str(path), f"damaged header ({e})") from None
    except RecursionError:  # json's decoder recurses once per level
        raise MeshInputError(str(path), "damaged header: its JSON is nested too deeply to read") from None
    check_header(path, header)
    return header


def _patches(path, data: dict, name: str, n: int) -> np.ndarray:
    """Member ``name``: (N, n, n, 3) float64 finite control points (empty when absent)."""
    g = data.get(name, np.zeros((0, n, n, 3)))
    if g.dtype != np.float64 or g.ndim != 4 or g.shape[1:] != (n, n, 3):
        raise MeshInputError(str(path), f"{name} must be float64 of shape (N, {n}, {n}, 3), got {g.dtype} {g.shape}")
    if not np.isfinite(g).all():
        raise MeshInputError(str(path), f"{name} holds NaN or infinite coordinates")
    return g


_PIECE_MEMBERS = ("merged_points", "merged_knots_u", "merged_knots_v", "merged_patches", "merged_rotation")


def _merged(path, data: dict, n_biquadratic: int) -> list:
    """The merged pieces of the "merged_*" members (``_merged_members``), each checked."""
    if "merged_spans" not in data:
        return []
    missing = [name for name in _PIECE_MEMBERS if name not in data]
    try:
        spans = whole_numbers(data["merged_spans"])
    except (ValueError, TypeError, OverflowError):
        spans = np.zeros(0, dtype=np.int64)  # refused below
    if missing or spans.ndim != 2 or spans.shape[1] != 2 or np.any(spans < 1) or np.any(spans > 1 << 24):
        raise MeshInputError(str(path), f"merged pieces need merged_spans (K, 2) of spans in [1, 2**24] and {', '.join(_PIECE_MEMBERS)}")
    m, n = spans[:, 0], spans[:, 1]
    sizes = {"merged_points": (m + 2) * (n + 2), "merged_weights": (m + 2) * (n + 2), "merged_knots_u": m + 5,
             "merged_knots_v": n + 5, "merged_patches": m * n, "merged_rotation": m * n}
    parts = {}
    for name, size in sizes.items():
        if name in data:
            ends = np.cumsum(size)
            if len(data[name]) != (ends[-1] if ends.size else 0):
                raise MeshInputError(str(path), f"{name} holds {len(data[name])} rows, the spans need {ends[-1]}")
            parts[name] = np.split(data[name], ends[:-1])
    try:
        return [checked_piece(path, k, parts["merged_points"][k].reshape(mk + 2, nk + 2, 3),
                              parts["merged_weights"][k].reshape(mk + 2, nk + 2) if "merged_weights" in parts else None,
                              (parts["merged_knots_u"][k], parts["merged_knots_v"][k]),
                              parts["merged_patches"][k].reshape(mk, nk), parts["merged_rotation"][k].reshape(mk, nk),
                              n_biquadratic)
                for k, (mk, nk) in enumerate(spans.tolist())]
    except ValueError as e:  # members of the wrong shape
        raise MeshInputError(str(path), f"malformed merged pieces ({e})") from None


__all__ = ["write_patch_set_npz", "write_patch_stream_npz", "read_patch_set_npz"]
