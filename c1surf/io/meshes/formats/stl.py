"""STL reader (ASCII and binary, through trimesh): one triangle per facet, three vertices of its own.

STL has no shared vertices: every facet lists its three corners. The reader
keeps them as they are (trimesh's STL loader, not ``trimesh.load``, which would
merge them); c1surf's welding (``prepare.mesh_edits.weld_mesh_file``) joins the
triangles into a surface, and ``--no-weld`` leaves them apart.
"""
from __future__ import annotations

import contextlib
import io
import logging
import os
import re
import warnings

import numpy as np

from ...errors import MeshInputError
from ..mesh_file import MeshFile

__all__ = ["read_stl"]

_FACET = re.compile(rb"^[ \t]*facet\b", re.IGNORECASE | re.MULTILINE)


def read_stl(path, *, keep_degenerate: bool = False) -> MeshFile:
    """Read an ASCII or binary STL file as separate triangles.

    Parameters
    ----------
    path : str or os.PathLike
    keep_degenerate : accepted for the readers' common signature: every facet has its own three corners, so
        no face repeats a vertex before welding (``prepare``)

    Returns
    -------
    MeshFile
        ``points`` (3T, 3) float64 (the facets' corners in file order),
        ``face_sizes`` (T,) all 3, ``face_vertices`` (3T,) = 0, 1, 2, ...;
        ``face_lines`` (T,) the ``facet`` lines of an ASCII file, else None.

    Raises
    ------
    MeshInputError
        Unreadable file, or no triangles in it (not an STL file, or a binary STL
        whose length does not match its triangle count).
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise MeshInputError(path, f"cannot read the file ({exc.strerror or exc}): check the path and its permissions") from None
    triangles = _triangles(data, path)
    if not np.all(np.isfinite(triangles)):
        t = int(np.argmax(~np.all(np.isfinite(triangles), axis=(1, 2))))
        raise MeshInputError(path, f"triangle {t} has a NaN or infinite coordinate: fix or remove it")
    n = triangles.shape[0]
    return MeshFile(path=path, points=triangles.reshape(-1, 3), face_sizes=np.full(n, 3, dtype=np.int64),
                    face_vertices=np.arange(3 * n, dtype=np.int64), face_lines=_facet_lines(data, n))


def _triangles(data: bytes, path: str) -> np.ndarray:
    """(T, 3, 3) float64 corners of every facet, in file order (all solids of an ASCII file)."""
    from trimesh.exchange.stl import load_stl  # a format library: imported on first use

    data = _as_utf8(data, path)
    try:
        with warnings.catch_warnings(), _quiet_logger("trimesh"):
            warnings.simplefilter("ignore")  # numpy's fromstring on text that is not numbers
            loaded = load_stl(io.BytesIO(data))  # logs a traceback when the facet normals are no numbers: c1surf
            # computes its own normals, so nothing is lost
    except Exception as exc:  # trimesh raises ValueError, HeaderError, ... on malformed files (numpy's words)
        line, what = _ascii_fault(data)
        if line is None and not data.lstrip()[:5].lower().startswith(b"solid"):
            what = (f"a binary STL whose {len(data)} bytes are not the 84 + 50 x "
                    f"{int.from_bytes(data[80:84], 'little') if len(data) >= 84 else 0} its header counts")
        raise MeshInputError(path, f"not a valid STL file: {what or type(exc).__name__}: re-export it", line) from None
    solids = list(loaded["geometry"].values()) if "geometry" in loaded else [loaded]
    with np.errstate(invalid="ignore"):  # a flipped bit makes a NaN: refused with its triangle by the caller
        corners = [np.asarray(s["vertices"], dtype=np.float64)[np.asarray(s["faces"])] for s in solids]
    if not corners or sum(len(c) for c in corners) == 0:
        raise MeshInputError(path, "no triangles found: not an STL file, or a binary STL whose length does not match "
                             "the triangle count in its header")
    return np.concatenate(corners)


@contextlib.contextmanager
def _quiet_logger(name: str):
    """Nothing ``name``'s logger (and its children) logs reaches stderr for the block."""
    logger = logging.getLogger(name)
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        logger.setLevel(level)


_VERTEX = re.compile(rb"^[ \t]*vertex\b(.*)$", re.IGNORECASE | re.MULTILINE)


def _ascii_fault(data: bytes):
    """(1-based line or None, what is wrong) of an ASCII STL trimesh could not read: the first ``vertex`` line
    without three numbers, or the first facet without three vertices; (None, None) when neither is found."""
    vertex_lines = []
    for match in _VERTEX.finditer(data):
        line = data.count(b"\n", 0, match.start()) + 1
        fields = match.group(1).split()
        try:
            ok = len(fields) == 3 and [float(f) for f in fields] is not None
        except ValueError:
            ok = False
        if not ok:
            return line, "a `vertex` line needs three numbers x y z"
        vertex_lines.append(line)
    facets = np.array([data.count(b"\n", 0, m.start()) + 1 for m in _FACET.finditer(data)], dtype=np.int64)
    inside = np.diff(np.searchsorted(np.array(vertex_lines, dtype=np.int64), np.r_[facets, np.iinfo(np.int64).max]))
    wrong = np.flatnonzero(inside != 3)
    if wrong.size:
        return int(facets[wrong[0]]), f"this facet has {int(inside[wrong[0]])} `vertex` lines, a triangle needs 3"
    return None, None


def _as_utf8(data: bytes, path: str) -> bytes:
    """``data`` as trimesh's STL loader takes it without guessing an encoding (``charset_normalizer``, not a
    dependency): a binary STL (84 header bytes and 50 per triangle its header counts) or UTF-8 text as it is,
    other text (a solid named in Latin-1) re-encoded as UTF-8; anything else refused in one line."""
    if len(data) >= 84 and 84 + 50 * int.from_bytes(data[80:84], "little") == len(data):
        return data
    try:
        data.decode("utf-8")
        return data
    except UnicodeDecodeError:
        pass
    if b"\0" in data or not data.lstrip()[:5].lower().startswith(b"solid"):
        raise MeshInputError(path, f"not an STL file: not ASCII STL text (no `solid` line), and not a binary STL "
                                   f"(its {len(data)} bytes are not the 84 + 50 x {int.from_bytes(data[80:84], 'little') if len(data) >= 84 else 0} "
                                   "of its header's triangle count): re-export it")
    return data.decode("latin-1").encode("utf-8")


def _facet_lines(data: bytes, n_triangles: int) -> np.ndarray | None:
    """(T,) 1-based line of each ``facet`` of an ASCII STL, or None (binary, or the count differs)."""
    if not data[:512].lstrip().lower().startswith(b"solid"):
        return None
    starts = np.array([m.start() for m in _FACET.finditer(data)], dtype=np.int64)
    if starts.size != n_triangles:
        return None
    newlines = np.flatnonzero(np.frombuffer(data, dtype=np.uint8) == ord("\n"))
    return np.searchsorted(newlines, starts) + 1
