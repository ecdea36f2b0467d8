"""OpenSubdiv ``t`` tag lines of an OBJ file: ``t NAME nints/nfloats/nstrings ints floats strings``.

Vertex and face indices in tags count from 0 (as OpenSubdiv's shapes write
them).  Tag lines are few, so each is parsed on its own in Python.
"""

from __future__ import annotations

import re

import numpy as np

from ...errors import MeshInputError
from .record import SharpTags

__all__ = ["parse_tag_lines"]

_COUNTS = re.compile(r"(\d+)/(\d+)/(\d+)\Z")
_FORM = "write `t NAME nints/nfloats/nstrings` and then exactly that many integers, numbers and words"


class _Collected:
    """Tag values gathered line by line: lists of (values, line) for each known kind."""

    def __init__(self):
        self.crease_edges, self.crease_sharpness, self.crease_lines = [], [], []
        self.corner_vertices, self.corner_sharpness, self.corner_lines = [], [], []
        self.hole_faces, self.hole_lines = [], []
        self.interpolate_boundary = None
        self.other = []

    def record(self) -> SharpTags:
        """The collected tags as a SharpTags (index arrays int64, sharpness float64, lines 1-based)."""
        def ints(values, shape=(-1,)):
            return np.array(values, dtype=np.int64).reshape(shape)
        return SharpTags(
            crease_edges=ints(self.crease_edges, (-1, 2)), crease_sharpness=np.array(self.crease_sharpness, float),
            crease_lines=ints(self.crease_lines), corner_vertices=ints(self.corner_vertices),
            corner_sharpness=np.array(self.corner_sharpness, float), corner_lines=ints(self.corner_lines),
            hole_faces=ints(self.hole_faces), hole_lines=ints(self.hole_lines),
            interpolate_boundary=self.interpolate_boundary, other=self.other)


def parse_tag_lines(lines, path: str) -> SharpTags:
    """Parse OpenSubdiv tag lines into a SharpTags (not yet checked against the mesh: see ``check_tags``).

    Parameters
    ----------
    lines : iterable of (int, bytes)
        1-based line number and text of every ``t`` line, keyword included, comments removed.
    path : str
        The file, for error messages.

    Returns
    -------
    SharpTags

    Raises
    ------
    MeshInputError
        A malformed line: counts missing or not matching the values, a value not a number,
        a known tag with the wrong number of values.
    """
    got = _Collected()
    for line, text in lines:
        name, ints, floats = _split(text.decode("utf-8", "replace").split(), path, line)
        if name == "crease":
            _crease(got, ints, floats, path, line)
        elif name == "corner":
            _counted(path, line, "corner", len(ints) >= 1 and len(floats) in (1, len(ints)),
                     "k/1/0 (one sharpness for all k vertices) or k/k/0 (one sharpness each)")
            got.corner_vertices += ints
            got.corner_sharpness += floats * len(ints) if len(floats) == 1 else floats
            got.corner_lines += [line] * len(ints)
        elif name == "hole":
            _counted(path, line, "hole", len(floats) == 0, "k/0/0 followed by k face indices")
            got.hole_faces += ints
            got.hole_lines += [line] * len(ints)
        elif name == "interpolateboundary":
            _counted(path, line, "interpolateboundary", len(ints) == 1 and not floats and ints[0] in (0, 1, 2),
                     "1/0/0 followed by the mode 0 (none), 1 (edges and corners) or 2 (edges only)")
            got.interpolate_boundary = ints[0]
        else:
            got.other.append((name, line))
    return got.record()


def _split(tokens, path: str, line: int):
    """(name, ints, floats) of one tag line's tokens; refuses a malformed line."""
    if len(tokens) < 3 or not _COUNTS.match(tokens[2]):
        raise MeshInputError(path, f"malformed tag line: {_FORM}, e.g. `t crease 2/1/0 0 1 10.0`", line)
    n_int, n_float, n_string = (int(c) for c in _COUNTS.match(tokens[2]).groups())
    values = tokens[3:]
    if len(values) != n_int + n_float + n_string:
        raise MeshInputError(path, f"tag `{tokens[1]}` declares {n_int}/{n_float}/{n_string} values but the line "
                             f"has {len(values)}: {_FORM}", line)
    try:
        ints = [int(v) for v in values[:n_int]]
    except ValueError:
        bad = next(v for v in values[:n_int] if not re.fullmatch(r"[+-]?\d+", v))
        raise MeshInputError(path, f"tag `{tokens[1]}`: cannot read {bad!r} as an integer (the first {n_int} "
                             "values are integers): fix the value or the counts", line) from None
    huge = next((v for v in ints if abs(v) >= _LARGEST_INDEX), None)
    if huge is not None:
        raise MeshInputError(path, f"tag `{tokens[1]}`: the integer {huge} is beyond any vertex or face index: fix the "
                             "value", line)
    try:
        floats = [float(v) for v in values[n_int:n_int + n_float]]
    except ValueError:
        bad = next(v for v in values[n_int:n_int + n_float] if not _is_float(v))
        raise MeshInputError(path, f"tag `{tokens[1]}`: cannot read {bad!r} as a number: fix the value or the "
                             "counts", line) from None
    return tokens[1], ints, floats


_LARGEST_INDEX = 2**62  # an index at or beyond it fits no mesh (and no int64 after arithmetic)


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _crease(got: _Collected, ints, floats, path: str, line: int) -> None:
    """A crease chain v0 .. v(k-1): k - 1 edges, one sharpness for all or one per edge."""
    _counted(path, line, "crease", len(ints) >= 2 and len(floats) in (1, len(ints) - 1),
             "2/1/0 a b s, or a chain k/1/0 v0 .. v(k-1) s (or k/(k-1)/0 with one sharpness per edge)")
    got.crease_edges += [pair for pair in zip(ints[:-1], ints[1:])]
    got.crease_sharpness += floats * (len(ints) - 1) if len(floats) == 1 else floats
    got.crease_lines += [line] * (len(ints) - 1)


def _counted(path: str, line: int, name: str, ok: bool, form: str) -> None:
    """Refuse a known tag whose value counts do not fit its form."""
    if not ok:
        raise MeshInputError(path, f"malformed `{name}` tag: write it as `t {name} {form}`", line)
