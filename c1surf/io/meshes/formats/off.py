"""OFF reader (Object File Format, Geomview): polygons of any size, kept as they are.

The file is a few blocks of lines::

    OFF                      # or COFF, NOFF, CNOFF: per-vertex colours / normals follow x y z
    8 6 12                   # vertices, faces, edges (the edge count is not used)
    0 0 0                    # one vertex per line: x y z [extra values of COFF/NOFF, ignored]
    ...
    4 0 1 3 2 [r g b [a]]    # one face per line: n, then n vertex indices from 0, then an optional colour

``#`` starts a comment; blank lines are skipped; the counts may also follow the
keyword on the header line. Every malformed line is refused with its number.
"""
from __future__ import annotations

import os
import re

import numpy as np

from ...errors import MeshInputError
from ..mesh_file import MeshFile, collapse_repeated_corners_or_refuse, refuse_repeated_vertex

__all__ = ["read_off", "parse_off"]

HEADERS = frozenset({b"OFF", b"COFF", b"NOFF", b"CNOFF", b"NCOFF"})  # the extra values of C and N are ignored


def read_off(path, *, keep_degenerate: bool = False) -> MeshFile:
    """Read an OFF polygon mesh without triangulating it.

    Parameters
    ----------
    path : str or os.PathLike
    keep_degenerate : keep faces that repeat a vertex as written (no collapse, no refusal;
        ``c1surf inspect`` reports them)

    Returns
    -------
    MeshFile
        ``points`` (V, 3), ``face_sizes`` (F,), ``face_vertices`` (sum(face_sizes),), ``face_lines`` (F,)

    Raises
    ------
    MeshInputError
        Unreadable file, or not a valid OFF polygon mesh (``FILE:LINE: ...``).
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise MeshInputError(path, f"cannot read the file ({exc.strerror or exc}): check the path and its permissions") from None
    return parse_off(data, path, keep_degenerate=keep_degenerate)


def parse_off(data: bytes, path="<memory>", *, keep_degenerate: bool = False) -> MeshFile:
    """Parse OFF text given as bytes; see :func:`read_off`.

    Parameters
    ----------
    data : bytes, the whole file
    path : str, the name used in messages and stored in the result
    keep_degenerate : as in :func:`read_off`
    """
    path = os.fspath(path)
    lines, tokens = _content_lines(data)
    if not lines:
        raise MeshInputError(path, "the file is empty: an OFF file starts with the line `OFF`")
    plain, counts, first = _header(lines, tokens, path)
    n_vertices, n_faces = counts
    if len(lines) < first + n_vertices + n_faces:
        have = len(lines) - first
        raise MeshInputError(path, f"the header announces {n_vertices} vertices and {n_faces} faces but only {have} "
                             "vertex and face lines follow: the file is truncated or the counts are wrong", lines[-1])
    points = _vertices(lines[first:first + n_vertices], tokens[first:first + n_vertices], plain, path)
    face_lines = np.asarray(lines[first + n_vertices:first + n_vertices + n_faces], dtype=np.int64)
    sizes, face_vertices = _faces(face_lines, tokens[first + n_vertices:first + n_vertices + n_faces], n_vertices, path)
    line_of = lambda f: int(face_lines[f])  # noqa: E731
    collapsed = 0
    if not keep_degenerate:
        sizes, face_vertices, _, collapsed = collapse_repeated_corners_or_refuse(sizes, face_vertices, path, line_of)
        refuse_repeated_vertex(sizes, face_vertices, path, line_of, lambda f: "face")
    return MeshFile(path=path, points=points, face_sizes=sizes, face_vertices=face_vertices, face_lines=face_lines,
                    collapsed_corners=collapsed)


def _content_lines(data: bytes):
    """(1-based numbers, tokens) of the lines that hold something once comments are removed (a UTF-8 byte
    order mark read as spaces, as in OBJ)."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = b"   " + data[3:]
    numbered = [(k + 1, line.split(b"#", 1)[0].split()) for k, line in enumerate(data.split(b"\n"))]
    kept = [(k, t) for k, t in numbered if t]
    return [k for k, _ in kept], [t for _, t in kept]


def _header(lines, tokens, path: str):
    """(plain OFF?, (V, F), index of the first vertex line): the keyword and the counts."""
    keyword = tokens[0][0]
    if keyword.upper() not in HEADERS:
        shown = keyword[:20].decode("latin-1")
        raise MeshInputError(path, f"expected the header `OFF` (or COFF, NOFF), found {shown!r}: this is not an OFF "
                             "file", lines[0])
    if len(tokens[0]) > 1:  # OFF V F E on one line
        count_tokens, count_line, first = tokens[0][1:], lines[0], 1
    elif len(lines) > 1:
        count_tokens, count_line, first = tokens[1], lines[1], 2
    else:
        raise MeshInputError(path, "the header has no counts: the line after `OFF` gives vertices faces edges", lines[0])
    try:
        counts = [int(t) for t in count_tokens]
    except ValueError:
        counts = []
    if len(counts) not in (2, 3) or min(counts) < 0:
        raise MeshInputError(path, "expected the counts `vertices faces edges` (whole numbers >= 0)", count_line)
    if counts[1] == 0:
        raise MeshInputError(path, "has no faces (face count 0): c1surf needs polygon faces, not a point cloud", count_line)
    return keyword.upper() == b"OFF", (counts[0], counts[1]), first


def _vertices(lines, tokens, plain: bool, path: str) -> np.ndarray:
    """(V, 3) float64 positions of the vertex lines; COFF/NOFF values after x y z are ignored."""
    sizes = np.array([len(t) for t in tokens], dtype=np.int64)
    bad = np.flatnonzero((sizes != 3) if plain else (sizes < 3))
    if bad.size:
        k = int(sizes[bad[0]])
        raise MeshInputError(path, f"vertex has {k} numbers: an OFF vertex is `x y z` (a COFF or NOFF header allows "
                             "colours or normals after them)", lines[bad[0]])
    text = [t[:3] for t in tokens]
    try:
        points = np.array(text, dtype=np.bytes_).astype(np.float64).reshape(-1, 3)
    except ValueError:
        row = next(k for k, t in enumerate(text) if not _all_numbers(t))
        raise MeshInputError(path, "vertex coordinate is not a number: fix this line", lines[row]) from None
    finite = np.all(np.isfinite(points), axis=1)
    if not finite.all():
        raise MeshInputError(path, "vertex has a NaN or infinite coordinate: fix this line", lines[int(np.argmin(finite))])
    return points


def _faces(lines: np.ndarray, tokens, n_vertices: int, path: str):
    """(sizes (F,), vertices (sum(sizes),)) of the face lines ``n i1 .. in [colour]``; refuses the first bad line."""
    try:
        sizes = np.array([int(t[0]) for t in tokens], dtype=np.int64)
    except (ValueError, OverflowError):
        row = next(k for k, t in enumerate(tokens) if not _is_int(t[0]))
        raise MeshInputError(path, "a face line starts with its vertex count, a whole number", lines[row]) from None
    present = np.array([len(t) - 1 for t in tokens], dtype=np.int64)
    bad = np.flatnonzero((sizes < 3) | (present < sizes))
    if bad.size:
        f = int(bad[0])
        why = (f"a polygon needs at least 3 vertices, this face has {sizes[f]}" if sizes[f] < 3
               else f"the face announces {sizes[f]} vertices but lists {present[f]}")
        raise MeshInputError(path, f"{why}: fix or remove this face", lines[f])
    try:
        vertices = np.array([i for t, n in zip(tokens, sizes.tolist()) for i in t[1:n + 1]], dtype=np.bytes_)
        vertices = vertices.astype(np.int64)
    except (ValueError, OverflowError):
        row = next(k for k, (t, n) in enumerate(zip(tokens, sizes.tolist())) if not all(_is_int(i) for i in t[1:n + 1]))
        raise MeshInputError(path, "a vertex index is not a whole number below 10**18: fix this face", lines[row]) from None
    face = np.repeat(np.arange(sizes.size), sizes)
    outside = np.flatnonzero((vertices < 0) | (vertices >= n_vertices))
    if outside.size:
        c = outside[0]
        raise MeshInputError(path, f"face refers to vertex {vertices[c]}, but the file has {n_vertices} vertices "
                             f"(numbered from 0 to {n_vertices - 1})", lines[face[c]])
    return sizes, vertices


def _all_numbers(tokens) -> bool:
    try:
        [float(t) for t in tokens]
    except ValueError:
        return False
    return True


def _is_int(token: bytes) -> bool:
    """A whole number that fits an index (below 10**18 in magnitude: 18446744073709551617 is none; --1 neither)."""
    return _WHOLE.fullmatch(token) is not None


_WHOLE = re.compile(rb"[+-]?\d{1,18}")
