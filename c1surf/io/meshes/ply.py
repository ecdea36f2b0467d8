"""Reader for PLY polygon meshes (ASCII and binary), built on ``plyfile``.

Faces keep their sizes (never triangulated).  ``plyfile`` does the
parsing; this module turns its structured arrays into a
:class:`~c1surf.io.meshes.mesh_file.MeshFile`, checks the mesh, and translates
``plyfile``'s many exception types into one-line
:class:`~c1surf.io.errors.MeshInputError` messages.

Polygons come from a ``face`` element, a ``tristrips`` element (triangle
strips, -1 restarts a strip; read as triangles, the degenerate ones a strip
uses to turn dropped with a note), or both (faces first).  The index list is
``vertex_indices`` or ``vertex_index`` of any integer type.
"""

from __future__ import annotations

import os
import re
import warnings

import numpy as np
from plyfile import (PlyData, PlyElementParseError, PlyHeaderParseError,
                     PlyListProperty, PlyParseError)

from ..errors import MeshInputError
from .mesh_file import MeshFile, collapse_repeated_corners_or_refuse, refuse_repeated_vertex
from .tags.ply_tags import ply_tags
from .tags.record import check_tags

__all__ = ["read_ply"]

_INDEX_NAMES = ("vertex_indices", "vertex_index")
_UV_NAMES = (("u", "v"), ("s", "t"), ("texture_u", "texture_v"),
             ("texture_s", "texture_t"))
_RESERVED_VERTEX = {"x", "y", "z", "nx", "ny", "nz", "weight"}
_HEAD_BYTES = 1 << 16


def read_ply(path, *, keep_degenerate: bool = False) -> MeshFile:
    """Read a PLY polygon mesh (ASCII or binary) without triangulating it.

    Parameters
    ----------
    path : str or os.PathLike, an ASCII or binary PLY file
    keep_degenerate : keep faces that repeat a vertex as written (no collapse, no refusal;
        ``c1surf inspect`` reports them)

    Returns
    -------
    MeshFile
        ``points`` (V, 3), ``face_sizes`` (F,), ``face_vertices``
        (sum(face_sizes),); ``face_lines`` (F,) for ASCII files, None for
        binary ones; optional normals, uvs, ``weight`` and any other
        scalar vertex / face properties; ``tags`` from an ``edge`` element
        (``vertex1 vertex2 crease``) and vertex ``corner``/``sharpness``;
        ``reader_notes`` on dropped strip triangles.

    Raises
    ------
    MeshInputError
        The file cannot be read or is not a valid PLY polygon mesh.
    """
    path = os.fspath(path)
    ply, rows = _open(path)
    vertex = _vertex_data(path, ply["vertex"], rows)
    faces = _polygon_data(path, ply, vertex["points"].shape[0], rows, keep_degenerate)
    edges = ply["edge"].data if "edge" in ply else None
    tags = ply_tags(path, ply["vertex"].data, edges, rows.line)
    check_tags(tags, faces["face_sizes"], faces["face_vertices"], vertex["points"].shape[0], path)
    return MeshFile(path=path, **vertex, **faces, tags=tags)


class _Rows:
    """1-based lines of element rows (ASCII files with a header found: one row per line).

    text : bool, whether rows have lines at all
    first : dict element name -> line of its row 0
    """

    def __init__(self, ply: PlyData, header_lines: int):
        self.text = ply.text and header_lines > 0
        self.first, line = {}, header_lines + 1
        for element in ply.elements:
            self.first[element.name] = line
            line += element.count

    def line(self, name: str, row) -> int | None:
        """Line of row ``row`` of element ``name``, or None (binary file)."""
        return self.first[name] + int(row) if self.text else None


def _open(path: str):
    """(PlyData, _Rows) of the file; refuses what is not a PLY file with vertices and faces."""
    head = _read_head(path)
    if not head or head.isspace():
        raise MeshInputError(
            path, "the file is empty: a PLY mesh starts with a 'ply' header")
    skip = 3 if head.startswith(b"\xef\xbb\xbf") else 0  # a UTF-8 byte order mark, skipped as in OBJ and OFF
    head = head[skip:]
    if not (head.startswith(b"ply\n") or head.startswith(b"ply\r")):
        raise MeshInputError(
            path, "not a PLY file (it does not start with a 'ply' line): "
            "check the file, or give it the suffix of its real format")
    header_lines, binary, sniffed = _sniff_header(head)
    negative = re.search(rb"^element[ \t]+\S+[ \t]+-", head[:head.find(b"end_header") + 1], re.M)
    if negative is not None:
        raise MeshInputError(path, "the header declares a negative element count: fix the header or re-export the "
                                   "file", head[:negative.start()].count(b"\n") + 1)
    _refuse_impossible_counts(path, head, skip)
    with warnings.catch_warnings():  # numpy's loadtxt on a truncated row: the error that follows says it
        warnings.simplefilter("ignore")
        ply = _load(path, binary, header_lines, sniffed, skip)
    if "vertex" not in ply:
        raise MeshInputError(
            path, "the PLY file has no 'vertex' element: c1surf needs "
            "vertices and faces")
    if "face" not in ply and "tristrips" not in ply:
        raise MeshInputError(
            path, "has vertices but no faces: c1surf needs polygon faces "
            "(the PLY file has no 'face' or 'tristrips' element)")
    return ply, _Rows(ply, header_lines)


def _vertex_data(path: str, vert, rows: _Rows) -> dict:
    """The MeshFile fields of the vertex element: points (V, 3), normals, uvs, weights, other scalar properties."""
    vdata = vert.data
    vnames = set(vdata.dtype.names or ())
    missing = [c for c in "xyz" if c not in vnames]
    if missing:
        raise MeshInputError(
            path, f"the 'vertex' element has no {'/'.join(missing)} "
            "property: vertices need x, y and z coordinates")
    if len(vdata) == 0:
        raise MeshInputError(
            path, "the PLY file has no vertices ('element vertex 0'): "
            "export the mesh with its vertices")
    points = np.empty((len(vdata), 3))
    for col, name in enumerate("xyz"):
        points[:, col] = _scalar(vdata, name, path)
    ok = np.isfinite(points).all(axis=1)
    if not ok.all():
        bad = int(np.argmin(ok))
        raise MeshInputError(
            path, f"vertex {bad} has a NaN or infinite coordinate: fix or "
            "remove it", rows.line("vertex", bad))
    normals = None
    if {"nx", "ny", "nz"} <= vnames:
        normals = np.stack([_scalar(vdata, c, path) for c in ("nx", "ny", "nz")], axis=1)
    uvs = None
    uv_pair = next((p for p in _UV_NAMES if set(p) <= vnames), None)
    if uv_pair is not None:
        uvs = np.stack([_scalar(vdata, c, path) for c in uv_pair], axis=1)
    weights = _scalar(vdata, "weight", path) if "weight" in vnames else None
    attributes = _extras(vert, vdata, _RESERVED_VERTEX | set(uv_pair or ()))
    return {"points": points, "vertex_normals": normals, "vertex_uvs": uvs, "vertex_weights": weights,
            "vertex_attributes": attributes}


def _polygon_data(path: str, ply: PlyData, n_vert: int, rows: _Rows, keep_degenerate: bool = False) -> dict:
    """The MeshFile face fields from the 'face' element, the 'tristrips' element, or both (faces first)."""
    has_strips = "tristrips" in ply
    parts = []
    if "face" in ply and (len(ply["face"].data) or not has_strips):
        parts.append(_face_data(path, ply["face"], n_vert, rows, keep_degenerate))
    if has_strips:
        parts.append(_strip_data(path, ply["tristrips"], n_vert, rows))
    return parts[0] if len(parts) == 1 else _concatenate(path, *parts)


def _index_name(path: str, element) -> str:
    """Name of the element's vertex index list property (``vertex_indices`` or ``vertex_index``)."""
    index_name = next((n for n in _INDEX_NAMES if n in (element.data.dtype.names or ())), None)
    if index_name is None or not isinstance(element.ply_property(index_name), PlyListProperty):
        raise MeshInputError(
            path, f"the '{element.name}' element has no 'vertex_indices' list "
            "property: c1surf needs faces given as lists of vertex indices")
    return index_name


def _face_data(path: str, face, n_vert: int, rows: _Rows, keep_degenerate: bool = False) -> dict:
    """The MeshFile fields of the face element: sizes (F,), vertices (sum(sizes),), lines, other properties."""
    fdata = face.data
    index_name = _index_name(path, face)
    if len(fdata) == 0:
        raise MeshInputError(
            path, "has vertices but no faces: c1surf needs polygon faces "
            "('element face 0')")
    sizes, face_vertices = _face_lists(fdata[index_name], path)
    small = np.flatnonzero(sizes < 3)
    if small.size:
        f = int(small[0])
        k = int(sizes[f])
        raise MeshInputError(
            path, f"face {f} has {k} {'vertex' if k == 1 else 'vertices'}: "
            "a polygon needs at least 3; remove it", rows.line("face", f))
    _check_indices(path, sizes, face_vertices, n_vert, rows)
    collapsed = 0
    if not keep_degenerate:
        sizes, face_vertices, _, collapsed = collapse_repeated_corners_or_refuse(
            sizes, face_vertices, path, lambda f: rows.line("face", f))
        refuse_repeated_vertex(sizes, face_vertices, path, lambda f: rows.line("face", f), lambda f: f"face {f}")
    face_lines = rows.first["face"] + np.arange(sizes.size, dtype=np.int64) if rows.text else None
    return {"face_sizes": sizes, "face_vertices": face_vertices, "face_lines": face_lines,
            "face_attributes": _extras(face, fdata, {index_name}), "collapsed_corners": collapsed, "reader_notes": []}


def _strip_data(path: str, strips, n_vert: int, rows: _Rows) -> dict:
    """The MeshFile face fields of a 'tristrips' element: its triangles (T,), degenerate ones dropped with a note.

    Each row is one or more strips (-1 restarts); a triangle's line and
    per-face properties are those of its row.
    """
    index_name = _index_name(path, strips)
    sizes, flat = _face_lists(strips.data[index_name], path)
    row_of = np.repeat(np.arange(sizes.size), sizes)
    bad = (flat < -1) | (flat >= n_vert)
    if bad.any():
        c = int(np.argmax(bad))
        raise MeshInputError(
            path, f"tristrips {int(row_of[c])} refers to vertex {int(flat[c])} but the file has {n_vert} vertices "
            f"(valid: 0..{n_vert - 1}, and -1 to restart a strip): fix the index", rows.line("tristrips", row_of[c]))
    triangles, tri_row = strip_triangles(flat, row_of)
    degenerate = ((triangles[:, 0] == triangles[:, 1]) | (triangles[:, 1] == triangles[:, 2])
                  | (triangles[:, 0] == triangles[:, 2]))
    if degenerate.all():
        raise MeshInputError(
            path, "the 'tristrips' element has no triangle with 3 distinct vertices: c1surf needs polygon faces")
    notes = []
    if degenerate.any():
        k = int(degenerate.sum())
        notes.append(f"{path}: dropped {k} degenerate strip triangle{'s' if k != 1 else ''} (a repeated vertex, "
                     "where a strip turns)")
    triangles, tri_row = triangles[~degenerate], tri_row[~degenerate]
    face_lines = rows.first["tristrips"] + tri_row if rows.text else None
    attributes = {name: col[tri_row] for name, col in _extras(strips, strips.data, {index_name}).items()}
    return {"face_sizes": np.full(tri_row.size, 3, dtype=np.int64), "face_vertices": triangles.reshape(-1),
            "face_lines": face_lines, "face_attributes": attributes, "collapsed_corners": 0, "reader_notes": notes}


def strip_triangles(flat: np.ndarray, row_of: np.ndarray):
    """The triangles of triangle strips, in strip order, alternate ones flipped to keep the orientation.

    Triangle k of a strip is (v_k, v_k+1, v_k+2), or (v_k+1, v_k, v_k+2)
    for odd k.  Degenerate triangles are kept (the caller drops them).

    Parameters
    ----------
    flat : ndarray, shape (N,), int64
        The strip rows' indices concatenated; -1 restarts a strip.
    row_of : ndarray, shape (N,), int64
        Row of each index (non-decreasing); each row starts a new strip.

    Returns
    -------
    triangles : ndarray, shape (T, 3), int64
    rows : ndarray, shape (T,), int64, the row of each triangle
    """
    new_row = np.flatnonzero(np.diff(row_of)) + 1
    seq = np.insert(flat, new_row, -1)
    seq_row = np.insert(row_of, new_row, -1)
    brk = seq < 0
    pos = np.arange(seq.size)
    start = np.maximum.accumulate(np.where(brk, pos + 1, 0)) if seq.size else pos
    i = np.flatnonzero(~brk[:-2] & ~brk[1:-1] & ~brk[2:])
    odd = (i - start[i]) % 2 == 1
    a, b = seq[i], seq[i + 1]
    triangles = np.stack([np.where(odd, b, a), np.where(odd, a, b), seq[i + 2]], axis=1)
    return triangles, seq_row[i]


def _concatenate(path: str, faces: dict, strips: dict) -> dict:
    """The face fields of the 'face' and 'tristrips' elements together (a property on only one is noted, not kept)."""
    names = faces["face_attributes"].keys() & strips["face_attributes"].keys()
    dropped = sorted((faces["face_attributes"].keys() | strips["face_attributes"].keys()) - names)
    notes = faces["reader_notes"] + strips["reader_notes"]
    if dropped:
        notes.append(f"{path}: per-face properties {', '.join(dropped)} were not kept: each is on only one of the "
                     "'face' and 'tristrips' elements")
    lines = None if faces["face_lines"] is None else np.concatenate([faces["face_lines"], strips["face_lines"]])
    return {"face_sizes": np.concatenate([faces["face_sizes"], strips["face_sizes"]]),
            "face_vertices": np.concatenate([faces["face_vertices"], strips["face_vertices"]]),
            "face_lines": lines, "collapsed_corners": faces["collapsed_corners"], "reader_notes": notes,
            "face_attributes": {n: np.concatenate([faces["face_attributes"][n], strips["face_attributes"][n]])
                                for n in sorted(names)}}


def _check_indices(path: str, sizes, face_vertices, n_vert: int, rows: _Rows) -> None:
    """Refuse the first face that names a vertex outside 0 .. n_vert - 1."""
    bad = (face_vertices < 0) | (face_vertices >= n_vert)
    if bad.any():
        c = int(np.argmax(bad))
        offs = np.zeros(sizes.size + 1, dtype=np.int64)
        np.cumsum(sizes, out=offs[1:])
        f = int(np.searchsorted(offs, c, side="right")) - 1
        raise MeshInputError(
            path, f"face {f} refers to vertex {int(face_vertices[c])} but "
            f"the file has {n_vert} vertices (valid: 0..{n_vert - 1}): fix "
            "the index", rows.line("face", f))


def _read_head(path: str) -> bytes:
    """First bytes of the file (enough for any sane header)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(_HEAD_BYTES)
    except OSError as exc:
        raise MeshInputError(
            path, f"cannot read the file ({exc.strerror or exc}): check the "
            "path and its permissions") from None


def _sniff_header(head: bytes):
    """Header line count, data format and element sizes, roughly.

    Only locates ``end_header``, the ``format`` word and the ``element``
    lines, for line numbers and the binary fast path; ``plyfile`` does the
    real parsing and reports header errors.

    Returns
    -------
    header_lines : int
        Lines up to and including ``end_header`` (0 if not found).
    binary : bool
    elements : list of (str, int)
        Element names and counts in header order.
    """
    text = head.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    m = re.search(rb"^end_header[ \t]*$", text, re.M)
    if m is None:
        return 0, False, []
    header = text[:m.end()]
    binary = re.search(rb"^format[ \t]+binary", header, re.M) is not None
    elements = [(name.decode("ascii", "replace"), int(count)) for name, count
                in re.findall(rb"^element[ \t]+(\S+)[ \t]+(\d+)", header,
                              re.M)]
    return header.count(b"\n") + 1, binary, elements


def _load_known_face_size(path: str, skip: int) -> PlyData | None:
    """The fast path of a binary file: telling plyfile the face size lets it memory-map the faces instead
    of reading them one by one in Python (about 100x faster for 1M quads). A wrong guess fails or leaves
    bytes unread: None, and ``_load``'s general read reports."""
    for k in (4, 3):
        hint = {"face": {name: k for name in _INDEX_NAMES}}
        try:
            with open(path, "rb") as fh:
                fh.seek(skip)
                ply = PlyData.read(fh, known_list_len=hint)
                if fh.tell() == os.fstat(fh.fileno()).st_size:
                    return ply
        except Exception:  # noqa: BLE001 - the general read reports
            pass
    return None


def _load(path: str, binary: bool, header_lines: int, elements, skip: int = 0) -> PlyData:
    """Read with plyfile, mapping its errors to MeshInputError.

    ``header_lines`` and ``elements`` (name, count) come from
    :func:`_sniff_header` and only serve to give ASCII errors a line;
    ``skip``: bytes before the header (a byte order mark).
    """
    if binary:
        ply = _load_known_face_size(path, skip)
        if ply is not None:
            return ply
    try:
        if not skip:
            return PlyData.read(path)
        with open(path, "rb") as fh:
            fh.seek(skip)
            return PlyData.read(fh)
    except PlyHeaderParseError as exc:
        raise MeshInputError(
            path, f"bad PLY header: {exc.message}: fix the header or "
            "re-export the file", exc.line) from None
    except PlyElementParseError as exc:
        line = None
        name = exc.element.name if exc.element is not None else None
        names = [n for n, _ in elements]
        if not binary and header_lines and exc.row is not None \
                and name in names:
            above = sum(c for _, c in elements[:names.index(name)])
            line = header_lines + above + int(exc.row) + 1
        raise MeshInputError(path, _element_error(exc), line) from None
    except PlyParseError as exc:
        raise MeshInputError(path, f"cannot read the PLY data ({exc}): "
                             "re-export the file") from None
    except UnicodeDecodeError:
        raise MeshInputError(
            path, "the ASCII PLY data contains non-ASCII bytes: re-export "
            "the file (or check that the header's format line is right)"
            ) from None
    except MemoryError:
        raise MeshInputError(
            path, "the PLY header declares more elements than fit in "
            "memory: the header counts are probably wrong") from None
    except OSError as exc:
        raise MeshInputError(
            path, f"cannot read the file ({exc.strerror or exc})") from None
    except (ValueError, TypeError, OverflowError, IndexError) as exc:
        found = None if binary else _misfit_value(path)  # the line of a list length of 300 as a 'uchar', or -1
        if found is not None:
            raise MeshInputError(path, found[1], found[0]) from None
        if "out of bounds" in str(exc) or isinstance(exc, OverflowError):  # numpy: 300 as a uchar list length
            raise MeshInputError(path, "a value does not fit the type the header declares for it (such as a face "
                                       "of 300 corners with a 'uchar' count): fix the value or the header") from None
        raise MeshInputError(path, f"cannot read the PLY data ({exc}): "
                             "re-export the file") from None


_PLY_TYPES = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8", "uint8", "int16", "uint16",
              "int32", "uint32", "float32", "float64"}
_INTEGER_RANGES = {name: (int(np.iinfo(t).min), int(np.iinfo(t).max)) for names, t in (
    (("char", "int8"), np.int8), (("uchar", "uint8"), np.uint8), (("short", "int16"), np.int16),
    (("ushort", "uint16"), np.uint16), (("int", "int32"), np.int32), (("uint", "uint32"), np.uint32)) for name in names}


def _header_elements(head: bytes) -> tuple[list, int]:
    """The elements a PLY header declares, and the bytes up to the end of its ``end_header`` line.

    Returns
    -------
    elements : list of (name, count, line, properties); count an int (any size, any sign), line 1-based,
        properties a list of (name, count type or None for a scalar, value type)
    header_bytes : int (0 when there is no end_header line in ``head``, or a line plyfile would refuse:
        its own error says more)
    """
    elements, end = [], re.search(rb"end_header[ \t]*(\r\n|\r|\n|$)", head)
    if end is None:
        return [], 0
    lines = head[:end.start()].replace(b"\r\n", b"\n").replace(b"\r", b"\n").split(b"\n")
    for number, words in enumerate((line.split() for line in lines), 1):
        if len(words) == 3 and words[0] == b"element" and re.fullmatch(rb"[+-]?\d+", words[2]):
            elements.append((words[1].decode("ascii", "replace"), int(words[2]), number, []))
        elif elements and words[:1] == [b"property"]:
            typed = [w.decode("ascii", "replace") for w in words[1:]]
            listed = typed[:1] == ["list"]
            if len(typed) != (4 if listed else 2) or not set(typed[1:3] if listed else typed[:1]) <= _PLY_TYPES:
                return [], 0
            elements[-1][3].append((typed[-1], typed[1] if listed else None, typed[2] if listed else typed[0]))
        elif words[:1] not in ([], [b"ply"], [b"format"], [b"comment"], [b"obj_info"]):
            return [], 0
    return elements, end.end()


def _refuse_impossible_counts(path: str, head: bytes, skip: int) -> None:
    """Refuse, naming its header line, an element count the file cannot hold: every row of an element with a
    property takes at least one byte after the header, so rows beyond the bytes there are impossible (a count of
    99999999999 over a 3-line body; also counts beyond 64 bits)."""
    elements, header_bytes = _header_elements(head[skip:])
    if not header_bytes:
        return
    body = max(os.path.getsize(path) - skip - header_bytes, 0)
    rows = 0
    for name, count, line, properties in elements:
        rows += max(count, 0) if properties else 0
        if rows > body:
            raise MeshInputError(path, f"the header declares {count:,} '{name}' elements, more than the {body:,} "
                                       "bytes after the header can hold (a row takes at least one): the count is "
                                       "wrong; fix the header or re-export the file", line)


def _misfit_value(path: str):
    """(line, message) of the first value of an ASCII PLY body outside the integer type the header declares for
    it (a list length of 300 with a 'uchar' count, -1 as a 'uint', a negative list length), or None. Python over the lines: it runs only
    after the read failed on such a value, to name the line (as the OBJ reader does)."""
    with open(path, "rb") as fh:
        head = fh.read(_HEAD_BYTES)
        skip = 3 if head.startswith(b"\xef\xbb\xbf") else 0
        elements, header_bytes = _header_elements(head[skip:])
        fh.seek(skip + header_bytes)
        body = fh.read().replace(b"\r\n", b"\n").replace(b"\r", b"\n").split(b"\n")
    first = head[skip:skip + header_bytes].replace(b"\r\n", b"\n").replace(b"\r", b"\n").rstrip(b"\n").count(b"\n") + 2
    if not header_bytes:
        return None
    at = 0  # body line of the element's first row
    for name, count, _, properties in elements:
        for row in range(at, min(at + max(count, 0), len(body))):
            words, k, found = body[row].split(), 0, None
            for prop, count_type, value_type in properties:
                if count_type is not None:
                    wider = f"'property list int {value_type} {prop}'"
                    found = _misfit(words, k, count_type, f"the list length {{}} of property '{prop}'", wider, 0)
                    if found is not None or k >= len(words) or not re.fullmatch(rb"[+-]?\d+", words[k]):
                        break
                    n = int(words[k])
                    checks, k = range(k + 1, k + 1 + n), k + 1 + n
                else:
                    checks, k = range(k, k + 1), k + 1
                what, wider = f"the value {{}} of property '{prop}'", f"'property int {prop}'"
                found = next((f for f in (_misfit(words, j, value_type, what, wider) for j in checks)
                              if f is not None), None)
                if found is not None:
                    break
            if found is not None:
                return first + row, f"{name} {row - at}: {found}"
        at += max(count, 0)
    return None


def _misfit(words: list, k: int, type_name: str, what: str, wider: str, least: int | None = None):
    """The complaint about token ``k`` of ``words`` when it is a whole number outside ``type_name``'s range (or
    below ``least``: a list length), naming ``what`` it is and a ``wider`` declaration; else None."""
    if type_name not in _INTEGER_RANGES or k >= len(words) or not re.fullmatch(rb"[+-]?\d+", words[k]):
        return None
    low, high = _INTEGER_RANGES[type_name]
    low = low if least is None else max(low, least)
    value = int(words[k])
    if low <= value <= high:
        return None
    return (what.format(value) + f" is outside {low}..{high}, what the header's '{type_name}' allows: fix the "
            f"line, or declare a wider type in the header (such as {wider})")


# plyfile's element error messages -> what to tell the user
_ELEMENT_ERRORS = {
    "early end-of-file": "the file ends early, inside {where} of {count}: it is truncated; re-export or re-download it",
    "early end-of-line": "{where} has too few values{prop}: every line must list all properties declared in the header",
    "expected end-of-line": "{where} has more values than the header declares: fix the line or the header",
    "malformed input": "cannot read {where}{prop}: the value is not a number of the declared type",
}


def _element_error(exc: PlyElementParseError) -> str:
    """One line for a plyfile element error (row numbers are 0-based)."""
    elt = exc.element.name if exc.element is not None else "element"
    count = exc.element.count if exc.element is not None else "?"
    row = exc.row
    prop = f" (property '{exc.prop.name}')" if exc.prop is not None else ""
    where = f"{elt} {row}" if row is not None else elt
    template = _ELEMENT_ERRORS.get(exc.message)
    if template is not None:
        return template.format(where=where, count=count, prop=prop)
    return f"cannot read {where}{prop}: {exc.message}"


def _scalar(data: np.ndarray, name: str, path: str) -> np.ndarray:
    """One scalar property as a native float64 copy.

    Returns
    -------
    ndarray, shape (N,), float64
    """
    col = data[name]
    if col.dtype == object:
        raise MeshInputError(
            path, f"property '{name}' is a list, expected a single number: "
            "fix the header")
    return np.array(col, dtype=np.float64)


def _extras(element, data: np.ndarray, skip) -> dict:
    """Remaining scalar properties as native-endian copies.

    Returns
    -------
    dict of str to ndarray, shape (N,)
    """
    out = {}
    for prop in element.properties:
        if prop.name in skip or isinstance(prop, PlyListProperty):
            continue
        col = data[prop.name]
        # np.array copies (no memory map kept alive) and makes it native.
        out[prop.name] = np.array(col, dtype=col.dtype.newbyteorder("="))
    return out


def _face_lists(col: np.ndarray, path: str):
    """Flatten plyfile's face index lists.

    Parameters
    ----------
    col : ndarray, shape (F,) of objects (each a 1-D index array), or
        shape (F, k) when plyfile memory-mapped fixed-size faces.

    Returns
    -------
    sizes : ndarray, shape (F,), int64
    face_vertices : ndarray, shape (sum(sizes),), int64
    """
    if col.dtype != object:
        sizes = np.full(col.shape[0], col.shape[1], dtype=np.int64)
        flat = np.asarray(col).reshape(-1)
    else:
        sizes = np.fromiter(map(len, col), dtype=np.int64, count=len(col))
        flat = np.concatenate(col) if len(col) else np.empty(0, np.int64)
    if not np.issubdtype(flat.dtype, np.integer):
        # e.g. "property list uchar float vertex_indices"
        if not np.all(np.isfinite(flat)) or np.any(flat != np.round(flat)):
            raise MeshInputError(
                path, "face vertex indices are not whole numbers: declare "
                "them as an integer list (e.g. 'list uchar int')")
    return sizes, flat.astype(np.int64)
