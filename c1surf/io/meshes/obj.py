"""Vectorized reader for Wavefront OBJ polygon meshes.

``obj_text.ObjText`` finds lines, tokens and record kinds with array
operations and parses all numbers of one record kind at once; this module
turns the records into a :class:`MeshFile`: vertices, faces (corner indices
resolved, repeated corners collapsed, checked), per-vertex texture
coordinates and normals from the face corners, and groups.

Records used: ``v`` (x y z [w], or x y z r g b), ``vt``, ``vn``, ``f``
(``v``, ``v/vt``, ``v//vn``, ``v/vt/vn``, negative = relative), ``g`` and
``o`` (face groups), and OpenSubdiv ``t`` tags (``tags.obj_tags``: creases,
corners, holes, ... into ``MeshFile.tags``).  Everything else (``s``,
``usemtl``, ``mtllib``, ``l``, ``p``, ...) and ``#`` comments are ignored;
ignored geometry (``l``, ``p``, ``curv``, ``curv2``, ``surf``) is named in
one of ``MeshFile.reader_notes``.  Lines ending in ``\\`` continue on the
next line.  Face corners whose ``vt``/``vn`` index names no record are read
without it, with one note; a bad vertex index is refused.
"""

from __future__ import annotations

import os

import numpy as np

from ..errors import MeshInputError
from .mesh_file import MeshFile, collapse_repeated_corners_or_refuse, refuse_repeated_vertex
from .obj_text import ABSENT, F, OTHER, V, VN, VT, WHITESPACE, ObjText
from .tags.obj_tags import parse_tag_lines
from .tags.record import check_tags

__all__ = ["read_obj", "parse_obj"]

_KEYWORD = {V: "v", VT: "vt", VN: "vn"}


def read_obj(path, *, keep_degenerate: bool = False) -> MeshFile:
    """Read a Wavefront OBJ polygon mesh without triangulating it.

    Parameters
    ----------
    path : str or os.PathLike, an OBJ text file
    keep_degenerate : keep faces that repeat a vertex as written (no collapse, no refusal;
        ``c1surf inspect`` reports them)

    Returns
    -------
    MeshFile
        ``points`` (V, 3), ``face_sizes`` (F,), ``face_vertices``
        (sum(face_sizes),), ``face_lines`` (F,) and, when present,
        weights, per-vertex normals/uvs and groups.

    Raises
    ------
    MeshInputError
        The file cannot be read or is not a valid OBJ polygon mesh; the
        error names the line where possible.
    """
    path_str = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise MeshInputError(
            path_str,
            f"cannot read the file ({exc.strerror or exc}): check the path "
            "and its permissions") from None
    return parse_obj(data, path_str, keep_degenerate)


def parse_obj(data: bytes, path="<memory>", keep_degenerate: bool = False) -> MeshFile:
    """Parse OBJ text given as bytes; see :func:`read_obj`.

    Parameters
    ----------
    data : bytes
        The complete file contents.
    path : str
        Name used in error messages and stored in the result.
    keep_degenerate : bool
        As in :func:`read_obj`.
    """
    path = os.fspath(path)
    _check_text(data, path)
    text = ObjText(data, path)
    v_lines, f_lines = _record_lines(text, path)
    points, weights, vertex_attributes = _vertices(text, v_lines, path)
    corners = _FaceCorners(text, f_lines, _face_sizes(text, f_lines, path))
    raw_v, raw_vt, raw_vn = text.face_corners(f_lines, corners.sizes)
    face_vertices = _resolve(raw_v, v_lines.size, corners, V, "vertex", path)
    if keep_degenerate:
        sizes, collapsed = corners.sizes, 0
    else:
        sizes, face_vertices, kept, collapsed = collapse_repeated_corners_or_refuse(
            corners.sizes, face_vertices, path, lambda f: int(f_lines[f]) + 1)
        refuse_repeated_vertex(sizes, face_vertices, path, lambda f: int(f_lines[f]) + 1, lambda f: "face", vertex_base=1)
    if collapsed:  # the texture and normal indices of the corners that remain
        raw_vt = None if raw_vt is None else raw_vt[kept]
        raw_vn = None if raw_vn is None else raw_vn[kept]
        corners = _FaceCorners(text, f_lines, sizes)
    uvs, dangling_vt = _corner_attribute(text, raw_vt, corners, face_vertices, v_lines.size, VT, path)
    normals, dangling_vn = _corner_attribute(text, raw_vn, corners, face_vertices, v_lines.size, VN, path)
    face_groups, group_names = text.groups(f_lines)
    tags = parse_tag_lines(_tag_lines(text), path)
    check_tags(tags, sizes, face_vertices, v_lines.size, path)
    notes = [n for n in (_dangling_note(text, dangling_vt, dangling_vn, path), _ignored_geometry_note(text, path)) if n]
    return MeshFile(path=path, points=points, face_sizes=sizes.astype(np.int64, copy=False),
                    face_vertices=face_vertices, face_lines=(f_lines + 1).astype(np.int64), vertex_weights=weights,
                    vertex_normals=normals, vertex_uvs=uvs, vertex_attributes=vertex_attributes,
                    face_groups=face_groups, group_names=group_names, collapsed_corners=collapsed, tags=tags,
                    reader_notes=notes)


def _tag_lines(text: ObjText):
    """(1-based line, bytes) of every ``t`` record, keyword included, comments blanked."""
    kw = text.kw_pos
    candidates = np.flatnonzero((kw >= 0) & (text.kind == OTHER))
    if candidates.size == 0:
        return []
    after = np.minimum(kw[candidates] + 1, text.buf.size - 1)
    is_t = (text.buf[kw[candidates]] == ord("t")) & ((kw[candidates] + 1 == text.ends[candidates])
                                                      | WHITESPACE[text.buf[after]])
    return [(int(li) + 1, text.buf[text.starts[li]:text.ends[li]].tobytes()) for li in candidates[is_t]]


# ----------------------------------------------------------------------
# records


def _record_lines(text: ObjText, path: str):
    """(v lines, f lines): 0-based line numbers of the vertex and face records; refuses a file without either."""
    v_lines = np.flatnonzero(text.kind == V)
    f_lines = np.flatnonzero(text.kind == F)
    if v_lines.size == 0 and f_lines.size == 0:
        raise MeshInputError(
            path, "no `v` vertex or `f` face lines found: this is not an "
            "OBJ polygon mesh (export the mesh as OBJ with faces)")
    if v_lines.size == 0:
        raise MeshInputError(
            path, "has faces but no vertices: add the `v x y z` lines the "
            "faces refer to")
    if f_lines.size == 0:
        raise MeshInputError(
            path, "has vertices but no faces: c1surf needs polygon faces "
            "(`f` lines), not a point cloud or curves")
    return v_lines, f_lines


def _vertices(text: ObjText, v_lines, path: str):
    """Positions (V, 3), weights (V,) or None (``v x y z w``) and colours (``v x y z r g b``) of the v records."""
    vals, counts = text.numbers(v_lines, min_count=3, need="a vertex needs x y z")
    n_vert = v_lines.size
    off = np.cumsum(counts) - counts
    uniform = bool((counts == counts[0]).all())
    if uniform:
        table = vals.reshape(n_vert, counts[0])
        points = np.ascontiguousarray(table[:, :3])
    else:
        points = vals[off[:, None] + np.arange(3)]
    _check_finite(points, v_lines, path, "vertex has a NaN or infinite "
                  "coordinate: fix or remove this `v` line")
    weights = None
    has_w = counts == 4  # x y z w; six numbers mean x y z r g b instead
    if has_w.any():
        weights = np.ones(n_vert)
        weights[has_w] = vals[off[has_w] + 3]
        _check_finite(weights[:, None], v_lines, path, "vertex weight is "
                      "NaN or infinite: fix the fourth number of this `v` "
                      "line")
    vertex_attributes = {}
    if uniform and counts[0] == 6:
        for col, name in zip((3, 4, 5), ("red", "green", "blue")):
            vertex_attributes[name] = table[:, col].copy()
    return points, weights, vertex_attributes


def _face_sizes(text: ObjText, f_lines, path: str) -> np.ndarray:
    """Corners of each f record; refuses a face of fewer than 3."""
    sizes = text.ntok[f_lines] - 1
    small = np.flatnonzero(sizes < 3)
    if small.size:
        k = int(sizes[small[0]])
        raise MeshInputError(
            path, f"face has {k} {'vertex' if k == 1 else 'vertices'}: a polygon "
            "needs at least 3 (remove this line, or use `l` for a line)",
            int(f_lines[small[0]]) + 1)
    return sizes


def _uv_table(text: ObjText) -> np.ndarray:
    """(n_vt, 2) texture coordinates of the vt records (v = 0 where only u is given)."""
    vt_lines = np.flatnonzero(text.kind == VT)
    tvals, tcounts = text.numbers(vt_lines, min_count=1, need="a texture coordinate needs u [v]")
    toff = np.cumsum(tcounts) - tcounts
    uv = np.zeros((vt_lines.size, 2))
    uv[:, 0] = tvals[toff]
    has_v = tcounts >= 2
    uv[has_v, 1] = tvals[toff[has_v] + 1]
    return uv


def _normal_table(text: ObjText) -> np.ndarray:
    """(n_vn, 3) normals of the vn records."""
    vn_lines = np.flatnonzero(text.kind == VN)
    nvals, ncounts = text.numbers(vn_lines, min_count=3, need="a normal needs x y z")
    noff = np.cumsum(ncounts) - ncounts
    return nvals[noff[:, None] + np.arange(3)]


# ignored records that carry geometry: each is named in a note, never dropped silently
_IGNORED_GEOMETRY = ((b"l", "line (`l`)"), (b"p", "point (`p`)"), (b"curv", "free-form curve (`curv`)"),
                     (b"curv2", "curve on a surface (`curv2`)"), (b"surf", "free-form surface (`surf`)"))


def _corner_attribute(text: ObjText, raw, corners, face_vertices, n_vert: int, kind_code: int, path: str):
    """Per-vertex texture coordinates (V, 2) or normals (V, 3) from the face corners, or None.

    Corners that name a ``vt``/``vn`` record the file does not have are
    ignored (the reader notes them); index 0 is still refused.

    Returns
    -------
    values : ndarray, shape (V, 2) or (V, 3), float64, or None
    dangling : int, corners whose index names no record
    """
    if raw is None:
        return None, 0
    total = int(np.count_nonzero(text.kind == kind_code))
    what = "texture coordinate" if kind_code == VT else "normal"
    idx = _resolve(raw, total, corners, kind_code, what, path, dangling_ok=True)
    dangling = int(np.count_nonzero((raw != ABSENT) & (idx < 0)))
    if dangling == raw.size:
        return None, dangling
    table = _uv_table(text) if kind_code == VT else _normal_table(text)
    return _per_vertex(face_vertices, idx, table, n_vert), dangling


def _dangling_note(text: ObjText, dangling_vt: int, dangling_vn: int, path: str) -> str | None:
    """One note on the face corners whose ``vt``/``vn`` index names no record, or None."""
    parts = []
    for count, kind_code, what in ((dangling_vt, VT, "texture coordinate"), (dangling_vn, VN, "normal")):
        if count:
            kw, total = _KEYWORD[kind_code], int(np.count_nonzero(text.kind == kind_code))
            parts.append(f"{count} {what} {'index that names' if count == 1 else 'indices that name'} no `{kw}` line "
                         f"(the file has {total or 'none'})")
    if not parts:
        return None
    return f"{path}: ignored {' and '.join(parts)}: the faces are read without them"


def _ignored_geometry_note(text: ObjText, path: str) -> str | None:
    """One note naming the geometry records c1surf ignores (``l``, ``p``, free-form), or None."""
    parts = []
    for keyword, what in _IGNORED_GEOMETRY:
        count = int(text.records(keyword).size)
        if count:
            parts.append(f"{count} {what} record{'s' if count != 1 else ''}")
    if not parts:
        return None
    return f"{path}: ignored {', '.join(parts)}: c1surf builds the surface from the `f` faces only"


class _FaceCorners:
    """Where each face corner stands in the file: its line, and the records of a kind above it.

    sizes : (F,) int, corners per face (of the corner arrays being resolved)
    """

    def __init__(self, text: ObjText, f_lines, sizes):
        self.kind, self.f_lines, self.sizes = text.kind, f_lines, sizes
        self.offsets = np.zeros(sizes.size + 1, dtype=np.int64)
        np.cumsum(sizes, out=self.offsets[1:])

    def line(self, corner: int) -> int:
        """1-based line of the face holding ``corner``."""
        face = int(np.searchsorted(self.offsets, corner, side="right")) - 1
        return int(self.f_lines[face]) + 1

    def records_above(self, kind_code: int) -> np.ndarray:
        """(C,) records of ``kind_code`` above each corner's line (negative indices count back from there)."""
        cum = np.cumsum(self.kind == kind_code)
        return np.repeat(cum[self.f_lines], self.sizes)


# ----------------------------------------------------------------------
# helpers


def _check_text(data: bytes, path: str) -> None:
    """Refuse empty, binary and non-text input with a one-line reason."""
    if not data or data.isspace():
        raise MeshInputError(
            path, "the file is empty: an OBJ mesh needs `v` vertex lines "
            "and `f` face lines")
    if data[:3] == b"ply" and data[3:4] in (b"\n", b"\r"):
        raise MeshInputError(
            path, "this is a PLY file, not OBJ: give it a .ply suffix")
    nul = data.find(b"\0")
    if nul >= 0:
        raise MeshInputError(
            path, "not an OBJ text file (a NUL byte: binary data): export "
            "the mesh as text OBJ or as PLY", data.count(b"\n", 0, nul) + 1)
    arr = np.frombuffer(data, dtype=np.uint8)
    if arr.max() < 128:
        return  # plain ASCII
    try:
        data.decode("utf-8")
        return
    except UnicodeDecodeError:
        pass
    # Not UTF-8: tolerate a few Latin-1 bytes (names, comments), refuse
    # anything that is mostly non-text.
    head = arr[:65536]
    odd = (head >= 128) | ((head < 32) & ~WHITESPACE[head])
    if odd.mean() > 0.1:
        raise MeshInputError(
            path, "not an OBJ text file (it is not readable as text): "
            "export the mesh as text OBJ or as PLY")



def _check_finite(values, lines, path, message):
    """Raise at the first row of ``values`` (N, k) with a NaN/inf."""
    ok = np.isfinite(values).all(axis=1)
    if not ok.all():
        raise MeshInputError(path, message, int(lines[np.argmin(ok)]) + 1)


def _resolve(raw, total, corners: _FaceCorners, kind_code: int, what: str, path, dangling_ok: bool = False):
    """Turn 1-based / negative OBJ indices into 0-based ones, checking range.

    Parameters
    ----------
    raw : ndarray, shape (C,), int64
        Indices as written; ``ABSENT`` where a corner has none.
    total : int
        Number of records of this kind in the file.
    corners : _FaceCorners
        Lines of the corners, and records of ``kind_code`` above them
        (only needed when the file uses negative indices).
    dangling_ok : bool
        Out-of-range indices become -1 instead of an error (index 0 is
        still refused).

    Returns
    -------
    ndarray, shape (C,), int64
        0-based indices, -1 where ``raw`` is ``ABSENT`` (or dangling).
    """
    present = raw != ABSENT
    res = np.where(raw > 0, raw - 1, -1)
    neg = (raw < 0) & present
    n_before = None
    keyword = _KEYWORD[kind_code]
    if neg.any():
        n_before = corners.records_above(kind_code)
        res[neg] = n_before[neg] + raw[neg]
    out = present & (raw != 0) & ((res < 0) | (res >= total))
    if dangling_ok and out.any():
        res[out] = -1
    bad = present & (raw == 0) if dangling_ok else present & ((raw == 0) | out)
    if not bad.any():
        return res
    c = int(np.argmax(bad))
    r = int(raw[c])
    line = corners.line(c)
    if r == 0:
        msg = (f"face uses {what} index 0: OBJ indices start at 1 "
               f"(negative ones count back from the last `{keyword}` line)")
    elif r > 0 and total == 0:
        msg = (f"face refers to {what} {r} but the file has no "
               f"`{keyword}` lines: add them or drop that part of the face")
    elif r > 0:
        msg = (f"face refers to {what} {r} but the file has only {total} "
               f"`{keyword}` line{'s' if total != 1 else ''}: fix the index "
               f"or add the missing `{keyword}` lines")
    else:
        nb = int(n_before[c])
        msg = (f"face refers to {what} {r} (counting back) but only {nb} "
               f"`{keyword}` line{'s are' if nb != 1 else ' is'} above this "
               "face: fix the relative index")
    raise MeshInputError(path, msg, line)


def _per_vertex(face_vertices, attr_idx, attr_values, n_vert):
    """Attach per-corner attributes to vertices; the first corner wins.

    Returns
    -------
    ndarray, shape (n_vert, k), float64, or None
        NaN rows for vertices never referenced with the attribute.
    """
    present = attr_idx >= 0
    if not present.any():
        return None
    verts = face_vertices[present]
    uniq, first = np.unique(verts, return_index=True)
    out = np.full((n_vert, attr_values.shape[1]), np.nan)
    out[uniq] = attr_values[attr_idx[present][first]]
    return out
