"""IGES 5.3 writer for Bezier / B-spline surface patches.

Each surface becomes one *Rational B-spline surface entity* (type 128, form 0);
optionally all of them are collected by one *Unordered group without back
pointers* (type 402, form 7; or form 15, ordered) so that a CAD system shows a
single object, or they are the faces of a B-rep whose entities a caller
builds (``brep``: ``io.patches.brep.iges_brep``) and this writer writes after
them.  Open CASCADE reads the files without a single load-check message; note
that it converts file units to millimetres on import.

The file has the five fixed-format sections of IGES 5.3 (Start, Global,
Directory Entry, Parameter Data, Terminate), 80-column records, LF line ends
(``iges_records``); every number reads back to the same double
(``iges_numbers``).  Entities of one layout (degrees, net size) are
formatted together, a chunk of tokens at a time.

Output is deterministic: the date fields come from the ``timestamp``
argument, else the ``SOURCE_DATE_EPOCH`` environment variable, else the fixed
epoch 0 (``19700101.000000``); nothing depends on the clock or on randomness.

Public API
----------
``write_iges(path, surfaces, *, units="mm", group=True, author="c1surf",
description=None, organization="", file_name=None, product_id=None,
timestamp=None, resolution=None, brep=None)``

``bezier_patches_to_surfaces(points_array, weights=None)``
"""

from __future__ import annotations

import datetime as _dt
import os
import textwrap
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from .iges_numbers import SLOT, SPACE, format_ints, format_reals, real_text
from .iges_records import (RECORD, SG_COLS, ParameterWriter, ascii_text, de_records, hollerith, pack_text_params,
                           text_records)

__all__ = ["write_iges", "bezier_patches_to_surfaces", "UNITS", "DEFAULT_UNITS"]

#: accepted ``units`` names -> (IGES units flag, IGES units name)
UNITS: dict[str, tuple[int, str]] = {
    "in": (1, "INCH"), "inch": (1, "INCH"), "mm": (2, "MM"), "ft": (4, "FT"), "mi": (5, "MI"), "m": (6, "M"),
    "km": (7, "KM"), "mil": (8, "MIL"), "um": (9, "UM"), "micron": (9, "UM"), "cm": (10, "CM"), "uin": (11, "UIN"),
}
DEFAULT_UNITS = "mm"

_BIG_ENTITY = 1024  # entities with more tokens are packed on their own
_CHUNK_TOKENS = 1 << 15  # tokens formatted per chunk (memory bound)

_STATUS_INDEPENDENT = b"00000000"
_STATUS_GROUP_MEMBER = b"00020000"  # logically dependent (member of a 402)
_STATUS_DEPENDENT = b"00010000"  # physically dependent (the surface of a B-rep face)


# ----------------------------------------------------------------------------
# input normalisation


class _Kind:
    """All surfaces with one layout (degrees, control net size, knot counts)."""

    __slots__ = ("du", "dv", "nu", "nv", "rows", "pts", "wts", "ku", "kv", "ntok")

    def __init__(self, du: int, dv: int, nu: int, nv: int):
        self.du, self.dv, self.nu, self.nv = du, dv, nu, nv
        self.rows: list[int] = []  # entity indices (input order)
        self.pts: Any = []
        self.wts: Any = []
        self.ku: Any = []
        self.kv: Any = []
        nf = (nu + du + 1) + (nv + dv + 1) + 4 * nu * nv + 4
        self.ntok = 10 + nf


def _bezier_knots(d: int) -> np.ndarray:
    return np.concatenate([np.zeros(d + 1), np.ones(d + 1)])


def _surface_net(idx: int, s: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray | None]:
    """Control points (nu, nv, 3) float64 and weights (nu, nv) float64 or None of surface ``idx``, checked."""
    pts = s["points"]
    if not (isinstance(pts, np.ndarray) and pts.dtype == np.float64):
        pts = np.asarray(pts, dtype=np.float64)
    if pts.ndim != 3 or pts.shape[2] != 3:
        raise ValueError(f"surface {idx}: points must have shape (nu, nv, 3), got {pts.shape}")
    w = s.get("weights")
    if w is not None:
        w = np.asarray(w, dtype=np.float64)
        if w.shape != pts.shape[:2]:
            raise ValueError(f"surface {idx}: weights must have shape {pts.shape[:2]}, got {w.shape}")
    return pts, w


def _surface_knots(idx: int, s: Mapping[str, Any], nu: int, nv: int, bez_knots: dict) -> tuple:
    """(du, dv, knots_u, knots_v) of surface ``idx``: clamped [0, 1] knots of a Bezier patch (shared
    through ``bez_knots``, degree -> knots), or the B-spline's own, checked."""
    if s.get("knots_u") is None and s.get("knots_v") is None:
        du, dv = nu - 1, nv - 1
        if "degree" in s and s["degree"] is not None and tuple(s["degree"]) != (du, dv):
            raise ValueError(f"surface {idx}: degree {tuple(s['degree'])} does not match a Bezier net {(nu, nv)}")
        if du < 1 or dv < 1:
            raise ValueError(f"surface {idx}: a Bezier patch needs at least 2x2 control points")
        for d in (du, dv):
            if d not in bez_knots:
                bez_knots[d] = _bezier_knots(d)
        return du, dv, bez_knots[du], bez_knots[dv]
    if s.get("degree") is None or s.get("knots_u") is None or s.get("knots_v") is None:
        raise ValueError(f"surface {idx}: a B-spline surface needs knots_u, knots_v and degree")
    du, dv = (int(d) for d in s["degree"])
    ku = np.asarray(s["knots_u"], dtype=np.float64).ravel()
    kv = np.asarray(s["knots_v"], dtype=np.float64).ravel()
    if du < 1 or dv < 1 or nu < du + 1 or nv < dv + 1:
        raise ValueError(f"surface {idx}: degrees {(du, dv)} need at least {(du + 1, dv + 1)} control points")
    if ku.size != nu + du + 1 or kv.size != nv + dv + 1:
        raise ValueError(
            f"surface {idx}: need {nu + du + 1} u-knots and {nv + dv + 1} v-knots, got {ku.size} and {kv.size}"
        )
    for name, kn, d, n in (("u", ku, du, nu), ("v", kv, dv, nv)):
        if not np.all(np.isfinite(kn)) or np.any(np.diff(kn) < 0):
            raise ValueError(f"surface {idx}: knots_{name} must be finite and non-decreasing")
        if not kn[d] < kn[n]:
            raise ValueError(f"surface {idx}: empty parameter range in {name}")
    return du, dv, ku, kv


def _stack(kind: _Kind) -> None:
    """Turn the kind's lists of nets, weights and knots into stacked arrays, checked."""
    kind.pts = np.stack(kind.pts) if kind.rows else np.zeros((0, kind.nu, kind.nv, 3))
    if all(w is None for w in kind.wts):
        kind.wts = None
    else:
        kind.wts = np.stack([np.ones((kind.nu, kind.nv)) if w is None else w for w in kind.wts])
    kind.ku = np.stack(kind.ku)
    kind.kv = np.stack(kind.kv)
    if not np.all(np.isfinite(kind.pts)):
        raise ValueError("control points must be finite")
    if kind.wts is not None and not (np.all(np.isfinite(kind.wts)) and np.all(kind.wts > 0)):
        raise ValueError("weights must be finite and positive")
    kind.rows = np.asarray(kind.rows, dtype=np.int64)


def _normalise(surfaces: Sequence[Mapping[str, Any]]) -> tuple[list[_Kind], np.ndarray, np.ndarray]:
    """Sort the surfaces into kinds (one layout each): (kinds, kind of each surface, its row in the kind)."""
    kinds: dict[tuple, int] = {}
    kind_of = np.empty(len(surfaces), dtype=np.int64)
    row_of = np.empty(len(surfaces), dtype=np.int64)
    order: list[_Kind] = []
    bez_knots: dict[int, np.ndarray] = {}
    for idx, s in enumerate(surfaces):
        pts, w = _surface_net(idx, s)
        nu, nv = pts.shape[:2]
        du, dv, ku, kv = _surface_knots(idx, s, nu, nv, bez_knots)
        ki = kinds.setdefault((du, dv, nu, nv), len(order))
        if ki == len(order):
            order.append(_Kind(du, dv, nu, nv))
        kind = order[ki]
        kind_of[idx] = ki
        row_of[idx] = len(kind.rows)
        kind.rows.append(idx)
        kind.pts.append(pts)
        kind.wts.append(w)
        kind.ku.append(ku)
        kind.kv.append(kv)
    for kind in order:
        _stack(kind)
    return order, kind_of, row_of


def _kind_tables(kind: _Kind, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Integer header ``(g, 10)`` and real parameters ``(g, nf)`` of entity 128
    for the given rows (indices into the kind's stacked arrays)."""
    du, dv, nu, nv = kind.du, kind.dv, kind.nu, kind.nv
    g = rows.size
    P = kind.pts[rows]  # (g, nu, nv, 3)
    ku = kind.ku[rows]
    kv = kind.kv[rows]
    if kind.wts is None:
        W = np.ones((g, nu, nv))
        poly = np.ones(g, dtype=np.int64)
    else:
        W = kind.wts[rows]
        flat = W.reshape(g, -1)
        poly = np.all(flat == flat[:, :1], axis=1).astype(np.int64)
    # closed flags: exact equality of the boundary rows with clamped knots
    clamped_u = np.all(ku[:, : du + 1] == ku[:, :1], axis=1) & np.all(ku[:, -du - 1 :] == ku[:, -1:], axis=1)
    clamped_v = np.all(kv[:, : dv + 1] == kv[:, :1], axis=1) & np.all(kv[:, -dv - 1 :] == kv[:, -1:], axis=1)
    closed_u = (
        clamped_u
        & np.all((P[:, 0] == P[:, -1]).reshape(g, -1), axis=1)
        & np.all(W[:, 0] == W[:, -1], axis=1)
    )
    closed_v = (
        clamped_v
        & np.all((P[:, :, 0] == P[:, :, -1]).reshape(g, -1), axis=1)
        & np.all(W[:, :, 0] == W[:, :, -1], axis=1)
    )
    ints = np.zeros((g, 10), dtype=np.int64)
    ints[:, 0] = 128
    ints[:, 1] = nu - 1  # K1
    ints[:, 2] = nv - 1  # K2
    ints[:, 3] = du  # M1
    ints[:, 4] = dv  # M2
    ints[:, 5] = closed_u
    ints[:, 6] = closed_v
    ints[:, 7] = poly
    # PROP4, PROP5 (periodic) = 0
    rng = np.stack([ku[:, du], ku[:, nu], kv[:, dv], kv[:, nv]], axis=1)
    # IGES order: first (u) index varies fastest
    wt = W.transpose(0, 2, 1).reshape(g, -1)
    pt = P.transpose(0, 2, 1, 3).reshape(g, -1)
    floats = np.concatenate([ku, kv, wt, pt, rng], axis=1)
    return ints, floats




# ----------------------------------------------------------------------------
# Parameter Data section


def _entity_tokens(kind: _Kind, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tokens ``(g, T, SLOT)``, offsets and lengths of the entity-128 parameter
    lists of ``rows`` of one kind.  Columns equal in all rows (knots,
    parameter range, unit weights, ...) are formatted once."""
    ints, floats = _kind_tables(kind, rows)
    g = rows.size
    ni, nf = ints.shape[1], floats.shape[1]
    nt = ni + nf
    chars = np.empty((g, nt, SLOT), dtype=np.uint8)
    off = np.empty((g, nt), dtype=np.int64)
    lens = np.empty((g, nt), dtype=np.int64)
    ic, io, il = format_ints(ints)
    chars[:, :ni] = ic.reshape(g, ni, SLOT)
    off[:, :ni] = io.reshape(g, ni)
    lens[:, :ni] = il.reshape(g, ni)
    const = np.all(floats == floats[:1], axis=0)
    cidx = np.nonzero(const)[0]
    vidx = np.nonzero(~const)[0]
    if cidx.size:
        c, o, ln = format_reals(floats[0, cidx])
        chars[:, ni + cidx] = c[None]
        off[:, ni + cidx] = o[None]
        lens[:, ni + cidx] = ln[None]
    if vidx.size:
        c, o, ln = format_reals(floats[:, vidx])
        chars[:, ni + vidx] = c.reshape(g, vidx.size, SLOT)
        off[:, ni + vidx] = o.reshape(g, vidx.size)
        lens[:, ni + vidx] = ln.reshape(g, vidx.size)
    return chars, off, lens


def _emit_surfaces(pdw: ParameterWriter, kinds: list[_Kind], kind_of: np.ndarray, row_of: np.ndarray) -> None:
    n = kind_of.size
    ntok_of = np.array([k.ntok for k in kinds], dtype=np.int64)[kind_of] if n else np.zeros(0, np.int64)
    start = 0
    while start < n:
        if ntok_of[start] > _BIG_ENTITY:
            end = start + 1
        else:
            # consecutive small entities up to the token budget
            cs = np.cumsum(ntok_of[start : start + _CHUNK_TOKENS // 16])
            big = np.nonzero(ntok_of[start : start + cs.size] > _BIG_ENTITY)[0]
            lim = cs.size if big.size == 0 else int(big[0])
            end = start + max(1, min(lim, int(np.searchsorted(cs, _CHUNK_TOKENS, side="right"))))
        ents = np.arange(start, end)
        g = end - start
        tmax = int(ntok_of[start:end].max())
        kof = kind_of[start:end]
        kinds_here = np.unique(kof).tolist()
        if len(kinds_here) == 1 and kinds[kinds_here[0]].ntok == tmax:
            chars, off, lens = _entity_tokens(kinds[kinds_here[0]], row_of[start:end])
        else:
            chars = np.full((g, tmax, SLOT), SPACE, dtype=np.uint8)
            off = np.zeros((g, tmax), dtype=np.int64)
            lens = np.zeros((g, tmax), dtype=np.int64)
            for ki in kinds_here:
                sel = np.nonzero(kof == ki)[0]
                c, o, ln = _entity_tokens(kinds[ki], row_of[start:end][sel])
                nt = c.shape[1]
                chars[sel, :nt] = c
                off[sel, :nt] = o
                lens[sel, :nt] = ln
        pdw.emit(ents, chars, off, lens)
        start = end


# ----------------------------------------------------------------------------
# Start / Global sections


def _timestamp_string(timestamp: Any) -> str:
    if timestamp is None:
        env = os.environ.get("SOURCE_DATE_EPOCH")
        timestamp = int(env) if env not in (None, "") else 0
    if isinstance(timestamp, _dt.datetime):
        t = timestamp
        if t.tzinfo is not None:
            t = t.astimezone(_dt.timezone.utc).replace(tzinfo=None)
    else:
        t = _dt.datetime(1970, 1, 1) + _dt.timedelta(seconds=int(timestamp))
    return t.strftime("%Y%m%d.%H%M%S")




def _global_params(
    *,
    file_name: str,
    product_id: str,
    units: str,
    author: str,
    organization: str,
    stamp: str,
    resolution: float,
    max_coord: float,
) -> list[str]:
    from c1surf import __version__

    flag, uname = UNITS[units]
    return [
        "1H,",  # 1 parameter delimiter
        "1H;",  # 2 record delimiter
        hollerith(product_id),  # 3 product id (sending system)
        hollerith(file_name),  # 4 file name
        hollerith("c1surf"),  # 5 native system id
        hollerith(f"c1surf {__version__}"),  # 6 preprocessor version
        "32",  # 7 bits of an integer
        "38",  # 8 single precision: max power of ten
        "6",  # 9 single precision: significant digits
        "308",  # 10 double precision: max power of ten
        "15",  # 11 double precision: significant digits
        hollerith(product_id),  # 12 product id (receiving system)
        "1.0",  # 13 model space scale
        str(flag),  # 14 units flag
        hollerith(uname),  # 15 units name
        "1",  # 16 max number of line weight gradations
        "1.0",  # 17 width of max line weight (model units)
        hollerith(stamp),  # 18 date/time of file generation
        real_text(resolution),  # 19 minimum user-intended resolution
        real_text(max_coord),  # 20 approximate maximum coordinate value
        hollerith(author),  # 21 author
        hollerith(organization),  # 22 organization
        "11",  # 23 version flag: 11 = IGES 5.3
        "0",  # 24 drafting standard: none
        hollerith(stamp),  # 25 date/time model created/modified
        "",  # 26 application protocol / subset id: none
    ]


# ----------------------------------------------------------------------------
# public API

def bezier_patches_to_surfaces(points_array: Any, weights: Any = None) -> list[dict[str, Any]]:
    """Split a homogeneous patch array ``(N, du+1, dv+1, 3)`` (and optional
    weights ``(N, du+1, dv+1)``) into the list of surface dicts that
    `write_iges` takes.  The dicts hold views, nothing is copied."""
    P = np.asarray(points_array, dtype=np.float64)
    if P.ndim != 4 or P.shape[3] != 3:
        raise ValueError(f"points_array must have shape (N, du+1, dv+1, 3), got {P.shape}")
    if weights is None:
        return [{"points": P[i], "weights": None} for i in range(P.shape[0])]
    W = np.asarray(weights, dtype=np.float64)
    if W.shape != P.shape[:3]:
        raise ValueError(f"weights must have shape {P.shape[:3]}, got {W.shape}")
    return [{"points": P[i], "weights": W[i]} for i in range(P.shape[0])]



def _group_form(group: bool | str, n_surfaces: int) -> int:
    """Form of the group entity 402: 7 (unordered), 15 (ordered) or 0 (no group, also of no surfaces)."""
    if isinstance(group, str):
        if group not in ("unordered", "ordered"):
            raise ValueError(f"group must be a bool, 'unordered' or 'ordered', not {group!r}")
        form = 7 if group == "unordered" else 15
    else:
        form = 7 if group else 0
    return form if n_surfaces else 0


def _extent(kinds: list[_Kind]) -> tuple[float, float]:
    """(largest |coordinate|, bounding-box diagonal) of all control points (they bound the surfaces); 0, 0 if none."""
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for kind in kinds:
        if kind.pts.size:
            lo = np.minimum(lo, kind.pts.reshape(-1, 3).min(axis=0))
            hi = np.maximum(hi, kind.pts.reshape(-1, 3).max(axis=0))
    if not np.all(np.isfinite(lo)):
        return 0.0, 0.0
    return float(np.max(np.maximum(np.abs(lo), np.abs(hi)))), float(np.linalg.norm(hi - lo))


def _extent_and_resolution(kinds: list[_Kind], resolution: float | None) -> tuple[float, float]:
    """(largest |coordinate|, the Global section's resolution: given, else 1e-9 of the bounding-box diagonal)."""
    max_coord, diag = _extent(kinds)
    resolution = float((1e-9 * diag if diag > 0 else 1e-9) if resolution is None else resolution)
    if not (np.isfinite(resolution) and resolution > 0):
        raise ValueError("resolution must be positive")
    return max_coord, resolution


def _start_lines(description: str) -> list[str]:
    """The Start section's text, wrapped to 72 columns (paragraphs kept)."""
    lines: list[str] = []
    for para in ascii_text(description).splitlines() or [""]:
        lines.extend(textwrap.wrap(para, SG_COLS) or [""])
    return lines


def _default_description(bspline: np.ndarray, group_form: int) -> str:
    """Start section text when the caller gives none: the entity counts."""
    return (f"c1surf surface: {bspline.size} rational B-spline surface entities (type 128), "
            f"{int((~bspline).sum())} of them Bezier patches"
            + (f", collected in one group (type 402 form {group_form})." if group_form else "."))


def _directory(pdw: ParameterWriter, bspline: np.ndarray, group_form: int, brep=None) -> bytes:
    """Directory Entry records of the surfaces (``bspline`` (n,) bool: label BSPLINE, else BEZIER), the group
    and the B-rep entities (``brep``: ``io.patches.brep.iges_brep.IgesBRep`` or None; its faces' surfaces are
    physically dependent)."""
    n_surf = bspline.size
    n_ent = n_surf + (1 if group_form else 0)
    etype = np.full(n_ent, 128, dtype=np.int64)
    form = np.zeros(n_ent, dtype=np.int64)
    status_idx = np.full(n_ent, 2 if brep is not None else 1 if group_form else 0, dtype=np.int64)
    label_idx = np.zeros(n_ent, dtype=np.int64)
    label_idx[:n_surf][bspline] = 1
    subscript = np.arange(1, n_ent + 1, dtype=np.int64)
    if group_form:
        etype[-1], form[-1], status_idx[-1], label_idx[-1], subscript[-1] = 402, group_form, 0, 2, 0
    status, labels = [_STATUS_INDEPENDENT, _STATUS_GROUP_MEMBER, _STATUS_DEPENDENT], [b"BEZIER", b"BSPLINE", b"C1SURF"]
    if brep is not None:
        etype, form, subscript = np.r_[etype, brep.etype], np.r_[form, brep.form], np.r_[subscript, brep.subscript]
        status_idx, label_idx = np.r_[status_idx, len(status) + brep.status], np.r_[label_idx, len(labels) + brep.label]
        status, labels = status + list(brep.STATUS), labels + list(brep.LABELS)
    return de_records(etype, pdw.pd_ptr, pdw.pd_cnt, form, (status, status_idx), (labels, label_idx), subscript)


def _write_sections(fh, start_lines: list[str], global_lines: list[str], normalised: tuple, bspline: np.ndarray,
                    group_form: int, brep=None) -> None:
    """Write the five sections to the seekable file ``fh``: Parameter Data first, then the Directory indexing it."""
    kinds, kind_of, row_of = normalised
    n_surf = bspline.size
    n_ent = n_surf + (1 if group_form else 0) + (0 if brep is None else brep.n_entities)
    s_bytes = text_records(start_lines, "S")
    g_bytes = text_records(global_lines, "G")
    d_offset = len(s_bytes) + len(g_bytes)
    p_offset = d_offset + 2 * n_ent * RECORD
    fh.write(s_bytes)
    fh.write(g_bytes)
    fh.seek(p_offset)
    pdw = ParameterWriter(fh, n_ent)
    _emit_surfaces(pdw, kinds, kind_of, row_of)
    if group_form:
        ints = np.concatenate([[402, n_surf], 2 * np.arange(n_surf, dtype=np.int64) + 1])  # members' DE pointers
        ic, io, il = format_ints(ints)
        pdw.emit(np.array([n_surf]), ic[None, :, :], io[None, :], il[None, :])
    if brep is not None:
        brep.emit(pdw)
    n_p = pdw.next_line - 1
    fh.seek(d_offset)
    fh.write(_directory(pdw, bspline, group_form, brep))
    term = f"S{len(start_lines):07d}G{len(global_lines):07d}D{2 * n_ent:07d}P{n_p:07d}"
    fh.seek(p_offset + n_p * RECORD)
    fh.write(text_records([term], "T"))
    fh.truncate()


@dataclass(frozen=True)
class IgesHeader:
    """What the Start and Global sections of ``write_iges`` say (see its docstring for the defaults)."""

    author: str = "c1surf"
    description: str | None = None
    organization: str = ""
    file_name: str | None = None
    product_id: str | None = None
    timestamp: Any = None
    resolution: float | None = None


def write_iges(
    path: str | os.PathLike,
    surfaces: Sequence[Mapping[str, Any]],
    *,
    units: str = "mm",
    group: bool | str = True,
    brep: Any = None,
    **header,
) -> None:
    """Write ``surfaces`` to ``path`` as an IGES 5.3 file.

    Each surface is a dict, either a Bezier patch
    ``{"points": (du+1, dv+1, 3), "weights": (du+1, dv+1) or None}`` on
    [0,1]^2 (first index goes with u), or a B-spline surface
    ``{"points": (nu, nv, 3), "weights": ... or None, "knots_u": (nu+du+1,),
    "knots_v": (nv+dv+1,), "degree": (du, dv)}``.  Each becomes an entity 128
    (form 0) in input order, labelled ``BEZIER``/``BSPLINE`` with subscript =
    input index + 1.  With ``group=True`` (or ``"unordered"``) an entity 402
    form 7 (unordered group without back pointers, label ``C1SURF``) collects
    them; ``group="ordered"`` uses form 15 (ordered group without back
    pointers) instead.  Group members get status 00020000 (logically
    dependent).  ``group=False``: independent surfaces, status 00000000.
    ``brep``: the ``brep.iges_brep.IgesBRep`` whose faces these surfaces are,
    written after them (surfaces physically dependent, 00010000; no 402).

    ``units``: key of `UNITS` (``mm``, ``m``, ``cm``, ``in``, ...).  ``file_name``:
    name in the Global section (default: basename of ``path``; pass the final
    name when writing to a temporary file).  ``product_id``: default =
    ``file_name`` without extension.
    ``timestamp``: datetime (UTC) or seconds since the epoch; default
    ``$SOURCE_DATE_EPOCH`` or 0.  ``resolution``: default 1e-9 * bounding box
    diagonal (1e-9 if that is 0).

    ``path``: a seekable regular file (Parameter Data is written before the Directory).
    ``**header``: the fields of ``IgesHeader`` (author, description, organization, file_name, product_id,
    timestamp, resolution).
    """
    h = IgesHeader(**header)
    author, description, organization, file_name = h.author, h.description, h.organization, h.file_name
    product_id, timestamp, resolution = h.product_id, h.timestamp, h.resolution
    ukey = str(units).lower()
    if ukey not in UNITS:
        raise ValueError(f"unknown units {units!r}; use one of {sorted(UNITS)}")
    surfaces = list(surfaces)
    normalised = _normalise(surfaces)
    group_form = 0 if brep is not None else _group_form(group, len(surfaces))
    if 2 * (len(surfaces) + (1 if group_form else 0) + (0 if brep is None else brep.n_entities)) > 9_999_999:
        raise ValueError("too many entities for one IGES file")
    max_coord, resolution = _extent_and_resolution(normalised[0], resolution)
    fname = os.path.basename(os.fspath(path)) if file_name is None else str(file_name)
    bspline = np.array([s.get("knots_u") is not None for s in surfaces], dtype=bool)
    description = _default_description(bspline, group_form) if description is None else description
    gparams = _global_params(file_name=fname, product_id=os.path.splitext(fname)[0] if product_id is None else str(product_id),
                             units=ukey, author=author, organization=organization, stamp=_timestamp_string(timestamp), resolution=resolution,
                             max_coord=max_coord)
    with open(path, "wb") as fh:
        _write_sections(fh, _start_lines(description), pack_text_params(gparams, SG_COLS), normalised, bspline, group_form,
                        brep)
