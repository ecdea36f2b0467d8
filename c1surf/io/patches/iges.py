"""Patch files in IGES 5.3 (``.igs`` / ``.iges``): write a PatchSet as a B-rep, read Bezier patches and merged surfaces back.

Writing goes through ``iges_writer.write_iges``: one rational B-spline surface
entity (type 128, form 0) per CAD face, merged pieces first (the default for
IGES: they replace the patches they stand for), then the remaining patches,
biquadratic before bicubic, clamped knots on [0, 1], the patch weights (PROP3
= 1 where they are all equal: polynomial), control points with the first (u)
index fastest. By default those surfaces are the faces of a B-rep built from
c1surf's own patch adjacency (``brep.iges_brep``): one manifold solid (186)
per closed component, an open shell (514 form 2) per open one, faces (510),
loops (508), shared edges (504) and vertices (502), so a CAD system reads one
valid solid without sewing. ``group=False`` (``convert --no-group``) writes
the surfaces alone, independent; ``brep=False`` collects them in one group
entity (402 form 7) instead (the layout before the B-rep).

Reading accepts everything that writer writes: entities 128 that are single
Bezier patches (polynomial or rational: unequal weights become
``PatchSet.weights``) and c1surf's merged B-spline surfaces (degree (2, 2),
knots 0 0 0 1 ... m m m: ``PatchSet.merged``, their patches cut out again
into the patch list), in Directory order; 402 groups and the B-rep around the
surfaces (its curves 126 are physically dependent) are passed over, its faces
being whole surfaces. Anything else (trimmed surfaces, other B-splines,
transformation matrices, free curves, other geometry) is refused with one
line saying so. The reader takes no adjacency from the B-rep:
``PatchSet.welding()`` finds it from the geometry.
"""
from __future__ import annotations

import os

import numpy as np

from ... import __version__
from ...evaluation.merge import MergedPiece, piece_dicts
from ...evaluation.patch_set import PatchSet, degree_runs
from ..errors import MeshInputError
from ..finite import refuse_non_finite_patch_set
from .brep.iges_brep import iges_brep
from .iges_writer import DEFAULT_UNITS, UNITS, bezier_patches_to_surfaces, write_iges
from .merged import cad_patch_set, is_piece_knots, piece_patches, uncovered_groups



def write_patch_set_iges(path, patch_set: PatchSet, *, units: str = DEFAULT_UNITS, group: bool = True,
                         file_name: str | None = None, brep: bool | None = None, strips: bool = True,
                         **_options) -> None:
    """Write ``patch_set`` as IGES 5.3: its merged pieces, then the patches they do not stand for, as a B-rep.

    Parameters
    ----------
    path : the file to write (may be a temporary name)
    patch_set : evaluation.patch_set.PatchSet (weights and merged pieces are written)
    units : a key of ``iges_writer.UNITS`` (coordinates are written unscaled; this labels them)
    group : make CAD show one object: by default through the B-rep (a solid, an open shell, or a
        402 group of several); ``group=False`` (``convert --no-group``) writes independent surfaces only
    file_name : the name recorded in the Global section (default: basename of ``path``)
    brep : the surfaces as the faces of a B-rep built from the patch adjacency
        (``brep.iges_brep``: 186 solids of the closed components, 514 shells, 510 faces, ...);
        None: when ``group``. ``brep=False, group=True``: the surfaces in one 402 group (no B-rep)
    strips : the merged pieces cut into strips one span wide (``merged.cad_patch_set``; False: ``--cad-pieces``)
    """
    refuse_non_finite_patch_set(patch_set, path)
    if strips:  # Open CASCADE's default mass properties exact (io.patches.merged.cad_patch_set)
        patch_set = cad_patch_set(patch_set)
    surfaces = piece_dicts(patch_set.merged)
    for points, weights in zip(*uncovered_groups(patch_set)):
        surfaces.extend(bezier_patches_to_surfaces(points, weights))
    layout = iges_brep(patch_set, len(surfaces), group) if (group if brep is None else brep) and surfaces else None
    write_iges(path, surfaces, units=units, group=group, file_name=file_name or os.path.basename(os.fspath(path)),
               description=_description(patch_set, layout), brep=layout)


def _description(patch_set: PatchSet, layout=None) -> str:
    """The Start section's text: what was converted, the patch counts, the B-rep and the construction options."""
    input_path = (patch_set.header.get("input") or {}).get("path")
    source = os.path.basename(str(input_path)) if input_path else "a mesh"
    counts = {n: sum(len(g) for g in patch_set.groups if g.shape[1:3] == (n, n)) for n in (3, 4)}
    text = (f"c1surf {__version__}: G1 surface of {source}, {counts[3]} biquadratic and {counts[4]} bicubic Bezier "
            "patches as rational B-spline surfaces (type 128 form 0, "
            f"{'rational' if patch_set.weights is not None else 'polynomial'}), biquadratic first")
    if layout is not None:
        shells = layout.closed.size - layout.n_solids
        text += (f"; the faces of {layout.n_solids} solid{'s' * (layout.n_solids != 1)} (type 186)"
                 + (f" and {shells} open shell{'s' * (shells != 1)} (type 514)" if shells else "")
                 + " sharing their edges and vertices")
    o = patch_set.header.get("options")
    if not o:
        return text + "."
    return text + f"; options blend={o['blend']!r} alpha={o['alpha']!r} beta={o['beta']!r} tangent_rule={o['tangent_rule']}."


# ----------------------------------------------------------------------------
# reading


class _Lines:
    """The records of one section: ``numbers`` (k,) int, their line numbers in the file; ``text`` (k, 80) uint8."""

    def __init__(self, numbers, text):
        self.numbers = np.asarray(numbers, dtype=np.int64)
        self.text = text.reshape(-1, 80)

    def __len__(self) -> int:
        return int(self.numbers.size)

    def joined(self, start: int, stop: int, columns: int) -> str:
        """Columns 1 .. ``columns`` of records ``start`` .. ``stop`` - 1, as one string."""
        return self.text[start:stop, :columns].tobytes().decode("ascii")


def _records(path) -> dict:
    """{section letter: _Lines} of an IGES file (Start, Global, Directory, Parameter, Terminate).

    Files of 80-column records with LF line ends (c1surf's, and most) are cut
    as one byte matrix; any other layout (CR LF, short or blank lines) goes
    line by line, with the same result.
    """
    try:
        with open(path, "rb") as f:
            data = f.read()
    except FileNotFoundError:
        raise MeshInputError(str(path), "no such file") from None
    except IsADirectoryError:
        raise MeshInputError(str(path), "is a directory, not a patch file") from None
    raw = np.frombuffer(data, dtype=np.uint8)
    if raw.size and raw.max() >= 128:
        raise MeshInputError(str(path), "not an IGES file (not ASCII; compressed or binary IGES is not supported)")
    rows = raw.reshape(-1, 81) if raw.size and raw.size % 81 == 0 else None
    if rows is None or data.count(b"\n") != rows.shape[0] or np.any(rows[:, 80] != 10) \
            or any(c in data for c in _LINE_BREAKS) or not np.all(_SECTION_LETTER[rows[:, 72]]):
        return _records_by_line(path, data.decode("ascii"))  # the errors, blank lines and odd layouts too
    letters = rows[:, 72]
    sections = {c: _Lines(np.flatnonzero(letters == ord(c)) + 1, np.ascontiguousarray(rows[letters == ord(c), :80]))
                for c in "SGDPT"}
    if not len(sections["G"]) or not len(sections["T"]):
        raise MeshInputError(str(path), "not an IGES file (no Global or Terminate section)")
    return sections


_LINE_BREAKS = (b"\r", b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e")  # where str.splitlines cuts, besides LF
_SECTION_LETTER = np.zeros(256, dtype=bool)
_SECTION_LETTER[np.frombuffer(b"SGDPT", dtype=np.uint8)] = True


def _records_by_line(path, text: str) -> dict:
    """``_records`` of a file in any other line layout, line by line (blank lines skipped, short ones padded)."""
    sections: dict = {c: [] for c in "SGDPT"}
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        if len(line) < 73 or line[72] not in sections:
            raise MeshInputError(str(path), "not an IGES file (fixed-format records need a section letter S, G, D, P or T in column 73)", number)
        sections[line[72]].append((number, line[:80].ljust(80)))
    if not sections["G"] or not sections["T"]:
        raise MeshInputError(str(path), "not an IGES file (no Global or Terminate section)")
    return {c: _Lines([n for n, _ in v], np.frombuffer("".join(t for _, t in v).encode("ascii"), dtype=np.uint8))
            for c, v in sections.items()}


def _delimiters(global_lines: _Lines) -> tuple[str, str]:
    text = global_lines.joined(0, len(global_lines), 72)
    param, record = ",", ";"
    if text.startswith("1H"):
        param = text[2]
        rest = text[4:]  # after "1H<p><p>"
        if rest.startswith("1H"):
            record = rest[2]
    return param, record


def _parameters(path, pd_lines: _Lines, start: int, count: int, param: str, record: str):
    body = pd_lines.joined(start - 1, start - 1 + count, 64)
    end = body.find(record)
    if end < 0:
        raise MeshInputError(str(path), "Parameter Data entry without a record delimiter",
                             int(pd_lines.numbers[start - 1]) if 0 < start <= len(pd_lines) else None)
    return [t.strip() for t in body[:end].split(param)]


def _int(field: str) -> int:
    field = field.strip()
    return int(field) if field else 0


def _int_fields(fields: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Right-justified integer fields (k, w) uint8 of the Directory: (values (k,) int64, ok (k,) bool).

    ``ok`` is False where a field is not blanks followed by digits (signs, inner
    or trailing blanks); those are read one by one (``_int``).
    """
    digit = (fields >= 48) & (fields <= 57)
    blank = fields == 32
    leading = np.cumsum(digit, axis=1) == 0  # before the first digit
    ok = np.all(digit | (blank & leading), axis=1)
    values = (np.where(digit, fields - 48, 0).astype(np.int64) * 10 ** np.arange(fields.shape[1] - 1, -1, -1)).sum(axis=1)
    return values, ok


def _real(token: str) -> float:
    return float(token.replace("D", "E").replace("d", "e")) if token else 0.0


def read_patch_set_iges(path) -> PatchSet:
    """Read the Bezier patches and merged surfaces (entities 128) of an IGES file, in Directory order.

    Returns
    -------
    PatchSet without adjacency or sources (IGES has neither); weights when
    some patch or piece is rational; the patches of each merged piece follow
    one another in the patch list, row by row, as ``merged.piece_patches`` cuts them
    """
    sections = _records(path)
    patches, weights, pieces = [], [], []
    n_biquadratic = 0  # biquadratic patches so far: a piece's patches are numbered among them
    for line, (knots_u, knots_v, w, points) in _surfaces(path, sections):
        if _single_span(knots_u, points.shape[0] - 1) and _single_span(knots_v, points.shape[1] - 1):
            patches.append(points)
            weights.append(w)
            n_biquadratic += points.shape[:2] == (3, 3)
            continue
        if not (points.shape[0] >= 3 and is_piece_knots(knots_u) and is_piece_knots(knots_v)
                and knots_u.size == points.shape[0] + 3 and knots_v.size == points.shape[1] + 3):
            raise MeshInputError(str(path), "the B-spline surface (type 128) has interior knots and is not a merged "
                                 "c1surf surface (degree (2, 2), knots 0 0 0 1 ... m m m): c1surf reads only such "
                                 "surfaces and single Bezier patches", line)
        m, n = points.shape[0] - 2, points.shape[1] - 2
        piece = MergedPiece(points, w, knots_u, knots_v, n_biquadratic + np.arange(m * n).reshape(m, n),
                            np.zeros((m, n), dtype=np.int64))
        n_biquadratic += m * n
        cut, cut_weights = piece_patches(piece)
        pieces.append(piece)
        patches.extend(cut)
        weights.extend(cut_weights)
    rational = any(not np.all(w == w.flat[0]) for w in weights)
    if not rational:
        pieces = [MergedPiece(p.points, None, p.knots_u, p.knots_v, p.patches, p.rotation) for p in pieces]
    header = {"format": "iges", "input": {"path": str(path)}, "counts": {"patches": len(patches)}}
    return PatchSet(degree_runs(patches), None, None, None, header, degree_runs(weights) if rational else None, pieces)


def _single_span(knots: np.ndarray, degree: int) -> bool:
    """Clamped knots of one Bezier span: degree + 1 equal values, then degree + 1 equal values."""
    return knots.size == 2 * degree + 2 and np.all(knots[: degree + 1] == knots[0]) and np.all(knots[degree + 1 :] == knots[-1])


_BREP = (186, 514, 510, 508, 504, 502)  # solid, shell, face, loop, edge and vertex lists


def _surfaces(path, sections):
    """(line, (knots_u, knots_v, weights (nu, nv), points (nu, nv, 3))) of each entity 128, in Directory order.

    Groups (402), null entities and properties are passed over, and so is the
    B-rep c1surf writes around its surfaces (186, 514, 510, 508, 504, 502 and
    the curves 126 they own, physically dependent): its faces are whole
    surfaces. Any other entity (a free curve too), and a surface with a
    transformation matrix, is refused.
    """
    param, record = _delimiters(sections["G"])
    de, pd = sections["D"], sections["P"]
    if len(de) % 2:
        raise MeshInputError(str(path), "the Directory Entry section has an odd number of records",
                             int(de.numbers[-1]) if len(de) else None)
    first, second = de.text[0::2], de.text[1::2]
    fields = [first[:, 0:8], first[:, 8:16], first[:, 48:56], second[:, 24:32]]
    parsed = [_int_fields(f) for f in fields]
    well_formed = np.all([ok for _, ok in parsed], axis=0)
    etype = parsed[0][0]
    dependent_curve = (etype == 126) & np.all(first[:, 66:68] == np.frombuffer(b"01", dtype=np.uint8), axis=1)
    passed_over = np.isin(etype, (402, 0, 406) + _BREP) | dependent_curve
    # groups, null entities, properties, the B-rep of the surfaces and its curves: not even looked at
    for k in np.flatnonzero(~(passed_over & well_formed)).tolist():
        line_number = int(de.numbers[2 * k])
        try:
            etype, pointer, matrix, count = (int(v[k]) if ok[k] else _int(f[k].tobytes().decode("ascii"))
                                             for (v, ok), f in zip(parsed, fields))
        except ValueError:
            raise MeshInputError(str(path), "malformed Directory Entry", line_number) from None
        if etype in (402, 0, 406) or etype in _BREP or (etype == 126 and dependent_curve[k]):
            continue
        if etype != 128:
            raise MeshInputError(str(path), f"entity type {etype} is not supported: c1surf tessellate reads only "
                                 "untrimmed Bezier patches and B-spline surfaces (type 128)", line_number)
        if matrix != 0:
            raise MeshInputError(str(path), "entity 128 with a transformation matrix is not supported", line_number)
        yield line_number, _surface_128(path, _parameters(path, pd, pointer, count, param, record), line_number)


def _surface_128(path, tokens: list, line: int):
    """Knots, weights and control points of a rational B-spline surface entity from its parameters."""
    try:
        k1, k2, m1, m2 = (int(t) for t in tokens[1:5])
        if min(m1, m2) < 1 or k1 < m1 or k2 < m2:
            raise MeshInputError(str(path), f"rational B-spline surface (type 128) with degrees {m1}, {m2} and upper "
                                 f"indices {k1}, {k2}: each degree must be at least 1 and at most its index", line)
        n1, n2, nc = k1 + m1 + 2, k2 + m2 + 2, (k1 + 1) * (k2 + 1)
        reals = tokens[10 : 10 + n1 + n2 + 4 * nc]
        try:
            values = np.array(reals, dtype=np.float64)  # plain decimal numbers, converted at C speed
        except ValueError:  # D exponents, defaulted (empty) parameters
            values = np.array([_real(t) for t in reals])
    except (ValueError, IndexError):
        raise MeshInputError(str(path), "malformed rational B-spline surface (type 128)", line) from None
    if values.size != n1 + n2 + 4 * nc or not np.all(np.isfinite(values)):
        raise MeshInputError(str(path), "truncated rational B-spline surface (type 128)", line)
    weights = values[n1 + n2 : n1 + n2 + nc].reshape(k2 + 1, k1 + 1).T  # u index fastest in the file
    if not np.all(weights > 0):
        raise MeshInputError(str(path), "rational B-spline surface (type 128) with a weight <= 0", line)
    points = values[n1 + n2 + nc :].reshape(k2 + 1, k1 + 1, 3).transpose(1, 0, 2)
    return values[:n1], values[n1 : n1 + n2], np.ascontiguousarray(weights), np.ascontiguousarray(points)


__all__ = ["write_patch_set_iges", "read_patch_set_iges", "UNITS", "DEFAULT_UNITS"]
