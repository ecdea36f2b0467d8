"""Patch files in IGES 5.3 (``.igs`` / ``.iges``): write a surface, read Bezier patches back.

Writing goes through ``io.iges.write_iges``: one rational B-spline surface
entity (type 128, form 0) per patch, biquadratic first, then bicubic, clamped
knots on [0, 1], unit weights (PROP3 = 1, polynomial), control points with the
first (u) index fastest; by default one group entity (type 402 form 7)
collects them so CAD systems show one object.

Reading accepts exactly what ``c1surf tessellate`` can use: entities 128 that
are single Bezier patches (no interior knots, equal weights), optionally
collected by 402 groups. Anything else (trimmed surfaces, rational patches,
transformation matrices, other geometry) is refused with one line saying so.
IGES carries no adjacency: ``PatchSet.welding()`` finds it from the geometry.
"""
from __future__ import annotations

import os

import numpy as np

from ... import __version__
from ..errors import MeshInputError
from .iges_writer import UNITS, bezier_patches_to_surfaces, write_iges
from ...evaluation.patch_set import PatchSet, degree_runs

DEFAULT_UNITS = "mm"


def write_patches_iges(path, surface, input_path: str | None = None, *, units: str = DEFAULT_UNITS, group: bool = True,
                       file_name: str | None = None, merged=None, **_options) -> None:
    """Write ``surface``'s patches as IGES 5.3.

    Parameters
    ----------
    path : the file to write (may be a temporary name)
    surface : core.surface.Surface
    input_path : str or None, recorded in the Start section
    units : a key of ``io.iges.UNITS`` (coordinates are written unscaled; this labels them)
    group : collect the surfaces in one group entity (402 form 7)
    file_name : the name recorded in the Global section (default: basename of ``path``)
    merged : ``core.merge.MergedPiece`` list (``convert --merge``): those B-spline surfaces
        first, then the patches they do not cover
    """
    surfaces = []
    weights = getattr(surface, "patch_weights", None) or [None, None]  # rational surfaces (A2a): IGES weights
    keep = np.ones(len(surface.biquadratic), dtype=bool)
    if merged:
        from ...evaluation.merge import piece_dicts

        surfaces.extend(piece_dicts(merged))
        for piece in merged:
            keep[piece.patches.ravel()] = False
    for g, w, mask in zip((surface.biquadratic, surface.bicubic), weights, (keep, None)):
        if mask is not None:
            g, w = g[mask], (None if w is None else w[mask])
        if len(g):
            surfaces.extend(bezier_patches_to_surfaces(np.ascontiguousarray(g[..., :3]), w))
    o = surface.options
    source = os.path.basename(str(input_path)) if input_path else "a mesh"
    description = (
        f"c1surf {__version__}: G1 surface of {source}, {len(surface.biquadratic)} biquadratic and "
        f"{len(surface.bicubic)} bicubic Bezier patches as rational B-spline surfaces (type 128 form 0, "
        f"{'rational' if getattr(surface, 'patch_weights', None) is not None else 'polynomial'}), biquadratic first; options blend={o.blend!r} alpha={o.alpha!r} beta={o.beta!r} "
        f"tangent_rule={o.tangent_rule}."
    )
    write_iges(path, surfaces, units=units, group=group, file_name=file_name or os.path.basename(os.fspath(path)),
               description=description)


# ----------------------------------------------------------------------------
# reading


def _records(path) -> dict:
    try:
        with open(path, "rb") as f:
            data = f.read()
    except FileNotFoundError:
        raise MeshInputError(str(path), "no such file") from None
    except IsADirectoryError:
        raise MeshInputError(str(path), "is a directory, not a patch file") from None
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        raise MeshInputError(str(path), "not an IGES file (not ASCII; compressed or binary IGES is not supported)") from None
    sections: dict = {c: [] for c in "SGDPT"}
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        if len(line) < 73 or line[72] not in sections:
            raise MeshInputError(str(path), "not an IGES file (fixed-format records need a section letter S, G, D, P or T in column 73)", number)
        sections[line[72]].append((number, line[:80].ljust(80)))
    if not sections["G"] or not sections["T"]:
        raise MeshInputError(str(path), "not an IGES file (no Global or Terminate section)")
    return sections


def _delimiters(global_lines) -> tuple[str, str]:
    text = "".join(line[:72] for _, line in global_lines)
    param, record = ",", ";"
    if text.startswith("1H"):
        param = text[2]
        rest = text[4:]  # after "1H<p><p>"
        if rest.startswith("1H"):
            record = rest[2]
    return param, record


def _parameters(path, pd_lines, start: int, count: int, param: str, record: str):
    body = "".join(line[:64] for _, line in pd_lines[start - 1 : start - 1 + count])
    end = body.find(record)
    if end < 0:
        raise MeshInputError(str(path), "Parameter Data entry without a record delimiter", pd_lines[start - 1][0])
    return [t.strip() for t in body[:end].split(param)]


def _int(field: str) -> int:
    field = field.strip()
    return int(field) if field else 0


def _real(token: str) -> float:
    return float(token.replace("D", "E").replace("d", "e")) if token else 0.0


def read_patch_set_iges(path) -> PatchSet:
    """Read the Bezier patches (entities 128) of an IGES file, in Directory order.

    Returns
    -------
    PatchSet without adjacency or sources (IGES has neither)
    """
    sections = _records(path)
    param, record = _delimiters(sections["G"])
    de, pd = sections["D"], sections["P"]
    if len(de) % 2:
        raise MeshInputError(str(path), "the Directory Entry section has an odd number of records", de[-1][0] if de else None)
    patches = []
    for k in range(0, len(de), 2):
        line_number, d1 = de[k]
        d2 = de[k + 1][1]
        try:
            etype, pointer, matrix, count, form = (_int(x) for x in (d1[0:8], d1[8:16], d1[48:56], d2[24:32], d2[32:40]))
        except ValueError:
            raise MeshInputError(str(path), "malformed Directory Entry", line_number) from None
        if etype in (402, 0, 406):  # groups, null entities and properties: nothing to draw
            continue
        if etype != 128:
            raise MeshInputError(str(path), f"entity type {etype} is not supported: c1surf tessellate reads only "
                                 "untrimmed Bezier patches (type 128)", line_number)
        if matrix != 0:
            raise MeshInputError(str(path), "entity 128 with a transformation matrix is not supported", line_number)
        tokens = _parameters(path, pd, pointer, count, param, record)
        try:
            k1, k2, m1, m2 = (int(t) for t in tokens[1:5])
            n1, n2, nc = k1 + m1 + 2, k2 + m2 + 2, (k1 + 1) * (k2 + 1)
            values = np.array([_real(t) for t in tokens[10 : 10 + n1 + n2 + 4 * nc]])
        except (ValueError, IndexError):
            raise MeshInputError(str(path), "malformed rational B-spline surface (type 128)", line_number) from None
        if values.size != n1 + n2 + 4 * nc or not np.all(np.isfinite(values)):
            raise MeshInputError(str(path), "truncated rational B-spline surface (type 128)", line_number)
        ku, kv = values[:n1], values[n1 : n1 + n2]
        weights = values[n1 + n2 : n1 + n2 + nc]
        if k1 != m1 or k2 != m2 or np.any(ku[: m1 + 1] != ku[0]) or np.any(ku[m1 + 1 :] != ku[-1]) \
                or np.any(kv[: m2 + 1] != kv[0]) or np.any(kv[m2 + 1 :] != kv[-1]):
            raise MeshInputError(str(path), f"the B-spline surface (type 128, form {form}) has interior knots: "
                                 "c1surf tessellate reads only single Bezier patches", line_number)
        if np.any(weights != weights[0]):
            raise MeshInputError(str(path), "rational patch (unequal weights): c1surf tessellate reads only polynomial patches", line_number)
        points = values[n1 + n2 + nc :].reshape(k2 + 1, k1 + 1, 3).transpose(1, 0, 2)  # u index fastest in the file
        patches.append(np.ascontiguousarray(points))
    header = {"format": "iges", "input": {"path": str(path)}, "counts": {"patches": len(patches)}}
    return PatchSet(degree_runs(patches), None, None, None, header)


__all__ = ["write_patches_iges", "read_patch_set_iges", "UNITS", "DEFAULT_UNITS"]
