"""IGES 5.3 writer for Bezier / B-spline surface patches.

Each surface becomes one *Rational B-spline surface entity* (type 128, form 0);
optionally all of them are collected by one *Unordered group without back
pointers* (type 402, form 7; or form 15, ordered) so that a CAD system shows a
single object.  Open CASCADE reads the files without a single load-check
message; note that it converts file units to millimetres on import.

The file has the five fixed-format sections of IGES 5.3 (Start, Global,
Directory Entry, Parameter Data, Terminate), 80-column records, LF line ends.

Number formatting is vectorised with numpy: every coordinate is written with
the fewest digits (16 or 17 significant digits, trailing zeros dropped) that
read back to the *same* IEEE double, without an exponent whenever
``1e-4 <= |x| < 1e16`` (the range in which Python's ``repr`` is positional);
other values fall back to ``repr`` with the exponent written as ``D``
(IGES double precision).  Parameter records wrap only at delimiters, so no
number is ever split across lines.

Output is deterministic: the date fields come from the ``timestamp``
argument, else the ``SOURCE_DATE_EPOCH`` environment variable, else the fixed
epoch 0 (``19700101.000000``); nothing depends on the clock or on randomness.

Public API
----------
``write_iges(path, surfaces, *, units="mm", group=True, author="c1surf",
description=None, organization="", file_name=None, product_id=None,
timestamp=None, resolution=None)``

``bezier_patches_to_surfaces(points_array, weights=None)``
"""

from __future__ import annotations

import datetime as _dt
import os
import textwrap
import unicodedata
from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ["write_iges", "bezier_patches_to_surfaces", "UNITS"]

# ----------------------------------------------------------------------------
# constants

#: accepted ``units`` names -> (IGES units flag, IGES units name)
UNITS: dict[str, tuple[int, str]] = {
    "in": (1, "INCH"),
    "inch": (1, "INCH"),
    "mm": (2, "MM"),
    "ft": (4, "FT"),
    "mi": (5, "MI"),
    "m": (6, "M"),
    "km": (7, "KM"),
    "mil": (8, "MIL"),
    "um": (9, "UM"),
    "micron": (9, "UM"),
    "cm": (10, "CM"),
    "uin": (11, "UIN"),
}

_REC = 81  # 80 columns + "\n"
_PD_COLS = 64  # parameter data lives in columns 1-64
_SG_COLS = 72  # start / global data live in columns 1-72
_W = 24  # widest formatted number (without delimiter)
_W1 = _W + 1  # ... with its delimiter
_BIG_ENTITY = 1024  # entities with more tokens are packed on their own
_CHUNK_TOKENS = 1 << 15  # tokens formatted per chunk (memory bound)

_STATUS_INDEPENDENT = b"00000000"
_STATUS_GROUP_MEMBER = b"00020000"  # logically dependent (member of a 402)

_SP, _COMMA, _SEMI, _DOT, _MINUS, _ZERO = 32, 44, 59, 46, 45, 48

_POW10 = 10.0 ** np.arange(0, 23)  # 10**0 .. 10**22 are exact doubles
_I10 = 10 ** np.arange(0, 19, dtype=np.int64)
#: "0000" .. "9999" as ASCII rows
_DIGITS4 = (np.stack([(np.arange(10000) // 10**p) % 10 for p in (3, 2, 1, 0)], axis=1) + _ZERO).astype(np.uint8)


# ----------------------------------------------------------------------------
# vectorised number formatting


def _two_prod(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Error-free product (Dekker/Veltkamp): a*b == p + e exactly."""
    p = a * b
    c = 134217729.0 * a  # 2**27 + 1
    ah = c - (c - a)
    al = a - ah
    c = 134217729.0 * b
    bh = c - (c - b)
    bl = b - bh
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    return p, e


def _round_scaled(a: np.ndarray, p: np.ndarray) -> np.ndarray:
    """round(a * 10**p) as int64 for a > 0, 0 <= p <= 22, a*10**p < 2**62."""
    prod, err = _two_prod(a, _POW10[p])
    fl = np.floor(prod)
    frac = (prod - fl) + err  # |frac| < 10, rounding error irrelevant here
    return fl.astype(np.int64) + np.floor(frac + 0.5).astype(np.int64)


def _repr_iges(v: float) -> str:
    s = repr(float(v))
    if "e" in s:
        mant, exp = s.split("e")
        if "." not in mant:
            mant += "."
        s = mant + "D" + exp
    return s


def _format_reals(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Format finite doubles as IGES reals.

    Returns ``(chars, off, lens)``: row ``i`` of the ``(n, _W1)`` uint8 array
    ``chars`` holds the ASCII text of ``x[i]`` in columns
    ``off[i] .. off[i]+lens[i]-1`` (other columns are undefined; column
    ``off+lens`` is always free for a delimiter).  Every string reads back
    (correctly rounded decimal -> double) to exactly the input value.
    """
    x = np.ascontiguousarray(x, dtype=np.float64).ravel()
    n = x.size
    out = np.empty((n, _W1), dtype=np.uint8)
    off = np.zeros(n, dtype=np.int64)
    lens = np.zeros(n, dtype=np.int64)
    if n == 0:
        return out, off, lens
    a = np.abs(x)
    fastmask = (a >= 1e-4) & (a < 1e16)
    allfast = bool(fastmask.all())
    fast = slice(None) if allfast else np.nonzero(fastmask)[0]
    slow = np.zeros(0, dtype=np.intp) if allfast else np.nonzero(~fastmask)[0]
    af = a if allfast else a[fast]
    if af.size:
        k = np.floor(np.log10(af)).astype(np.int64)
        np.clip(k, -6, 16, out=k)
        d = _round_scaled(af, 16 - k)
        # log10 may be off by one near powers of ten; fix up (twice at most)
        for _ in range(2):
            bad = (d >= _I10[17]) | (d < _I10[16])
            if not bad.any():
                break
            k[bad] += (d[bad] >= _I10[17]).astype(np.int64) - (d[bad] < _I10[16])
            np.clip(k, -6, 16, out=k)
            d[bad] = _round_scaled(af[bad], 16 - k[bad])
        ok = (k >= -4) & (k <= 15) & (d >= _I10[16]) & (d < _I10[17])
        if not ok.all():  # (practically never) leave these to repr
            idx = np.arange(n)[fast]
            slow = np.union1d(slow, idx[~ok])
            fast, af, k, d = idx[ok], af[ok], k[ok], d[ok]

        # try 16 significant digits: accept when it reads back exactly.  The
        # check is exact when D16 is an exact double and the power of ten is
        # <= 1e22 (one correctly rounded division == correctly rounded strtod)
        d16 = _round_scaled(af, 15 - k)
        d16f = d16.astype(np.float64)
        use16 = (d16 >= _I10[15]) & (d16 < _I10[16]) & (d16f.astype(np.int64) == d16)
        use16 &= d16f / _POW10[15 - k] == af
        d = np.where(use16, d16 * 10, d)

        m = d.size
        # 17 ASCII digits (4-digit lookup table), preceded by 4 zeros and
        # followed by padding: shifting by s = 0..4 is then a column slice
        z = np.full((m, 4 + _W1 - 1), _ZERO, dtype=np.uint8)
        z[:, 4] = (d // _I10[16]).astype(np.uint8) + _ZERO
        r = d % _I10[16]
        z[:, 5:9] = _DIGITS4[r // _I10[12]]
        z[:, 9:13] = _DIGITS4[(r // _I10[8]) % 10000]
        z[:, 13:17] = _DIGITS4[(r // _I10[4]) % 10000]
        z[:, 17:21] = _DIGITS4[r % 10000]
        nd = 17 - np.argmax(z[:, 20:3:-1] != _ZERO, axis=1)  # significant digits

        s = np.maximum(-k, 0)  # zeros after "0." plus one (0..4)
        kk = np.maximum(k, 0)  # column of the last integer digit
        length = kk + 2 + np.maximum(nd + s - kk - 1, 1)
        neg = (x[fast] < 0).astype(np.int64)

        # ext[:, j] = j-th char of the digits preceded by s zeros, stored
        # from column 1 on (column 0 is kept for the sign)
        ext = z[:, 4 : 4 + _W1 - 1]
        for sv in range(1, 5):
            sel = s == sv
            if sel.any():
                ext = np.where(sel[:, None], z[:, 4 - sv : 4 - sv + _W1 - 1], ext)
        # body char j (stored in column j+1): ext[j] for j <= kk, '.' for
        # j == kk+1, ext[j-1] after it
        j = np.arange(_W1 - 1, dtype=np.int8)[None, :]
        kk8 = kk.astype(np.int8)[:, None]
        ch = out if allfast else np.empty((m, _W1), dtype=np.uint8)
        ch[:, 0] = _MINUS
        ch[:, 1] = ext[:, 0]
        ch[:, 2:] = np.where(j[:, 1:] <= kk8, ext[:, 1:], ext[:, :-1])
        ch[:, 1:] = np.where(j == kk8 + 1, np.uint8(_DOT), ch[:, 1:])
        if not allfast:
            out[fast] = ch
        off[fast] = 1 - neg
        lens[fast] = length + neg

    for i in slow.tolist():
        if x[i] == 0.0:
            b = b"0.0"
        else:
            b = _repr_iges(x[i]).encode("ascii")
        out[i, : len(b)] = np.frombuffer(b, dtype=np.uint8)
        lens[i] = len(b)
    return out, off, lens


def _format_ints(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Format integers; same ``(chars, off, lens)`` convention as `_format_reals`."""
    v = np.asarray(v, dtype=np.int64).ravel()
    u, inv = np.unique(v, return_inverse=True)
    table = np.full((u.size, _W1), _SP, dtype=np.uint8)
    tlen = np.zeros(u.size, dtype=np.int64)
    for r, val in enumerate(u.tolist()):
        b = str(val).encode("ascii")
        table[r, : len(b)] = np.frombuffer(b, dtype=np.uint8)
        tlen[r] = len(b)
    inv = inv.ravel()
    return table[inv], np.zeros(v.size, dtype=np.int64), tlen[inv]


# ----------------------------------------------------------------------------
# line packing


def _pack_lockstep(lens: np.ndarray, width: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Greedy packing of many token rows at once.

    ``lens`` is ``(G, T)`` (token lengths incl. delimiter, 0 = padding).
    Returns ``(line, col, nlines)``: line index and start column of each token
    within its entity, and the number of lines of each entity.
    """
    g, t = lens.shape
    line = np.zeros((g, t), dtype=np.int64)
    col = np.zeros((g, t), dtype=np.int64)
    cur = np.zeros(g, dtype=np.int64)
    ln = np.zeros(g, dtype=np.int64)
    for c in range(t):
        lc = lens[:, c]
        brk = cur + lc > width
        ln += brk
        start = np.where(brk, 0, cur)
        col[:, c] = start
        line[:, c] = ln
        cur = start + lc
    return line, col, ln + 1


def _pack_sequential(lens: np.ndarray, width: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Greedy packing of one long token row (``lens`` is ``(T,)``)."""
    t = lens.size
    cs = np.concatenate([[0], np.cumsum(lens)])
    line = np.zeros(t, dtype=np.int64)
    col = np.zeros(t, dtype=np.int64)
    start, ln = 0, 0
    while start < t:
        end = int(np.searchsorted(cs, cs[start] + width, side="right")) - 1
        end = max(end, start + 1)  # a token never exceeds the width
        line[start:end] = ln
        col[start:end] = cs[start:end] - cs[start]
        start, ln = end, ln + 1
    return line, col, max(ln, 1)


# ----------------------------------------------------------------------------
# fixed-column helpers


def _put_int(rows: np.ndarray, start: int, width: int, values: np.ndarray, zero_pad: bool) -> None:
    """Write integers (0 <= v < 10**width, width <= 8) right-justified into
    columns [start, start+width) of ``rows``."""
    v = np.asarray(values, dtype=np.int64).ravel()
    if width > 8:
        raise ValueError("width > 8")
    if v.size and (v.min() < 0 or v.max() >= _I10[width]):
        raise ValueError(f"integer does not fit into {width} columns")
    ch = np.concatenate([_DIGITS4[v // 10000], _DIGITS4[v % 10000]], axis=1)[:, 8 - width :]
    if not zero_pad:
        ndig = np.maximum(np.searchsorted(_I10, v, side="right"), 1)
        ch[np.arange(width)[None, :] < (width - ndig)[:, None]] = _SP
    rows[:, start : start + width] = ch


def _finish_records(rows: np.ndarray, letter: str) -> None:
    rows[:, 72] = ord(letter)
    _put_int(rows, 73, 7, np.arange(1, rows.shape[0] + 1), zero_pad=True)
    rows[:, 80] = 10


def _text_records(lines: Sequence[str], letter: str) -> bytes:
    rows = np.full((len(lines), _REC), _SP, dtype=np.uint8)
    for r, s in enumerate(lines):
        b = s.encode("ascii")
        if len(b) > _SG_COLS:
            raise AssertionError("record too long")
        rows[r, : len(b)] = np.frombuffer(b, dtype=np.uint8)
    _finish_records(rows, letter)
    return rows.tobytes()


def _ascii(s: str) -> str:
    """Printable ASCII only (IGES character set)."""
    s = unicodedata.normalize("NFKD", str(s)).encode("ascii", "ignore").decode("ascii")
    return "".join(ch if 32 <= ord(ch) < 127 else " " for ch in s)


def _hollerith(s: str | None) -> str:
    if s is None or s == "":
        return ""  # defaulted parameter
    s = _ascii(s)
    return f"{len(s)}H{s}"


def _pack_text_params(tokens: Sequence[str], width: int) -> list[str]:
    """Join parameters with ',' (last gets ';'), wrapping only at delimiters.

    A single token longer than a record (a long Hollerith string) is the only
    thing continued onto the next record."""
    out: list[str] = []
    cur = ""
    n = len(tokens)
    for i, tok in enumerate(tokens):
        piece = tok + (";" if i == n - 1 else ",")
        if len(cur) + len(piece) <= width:
            cur += piece
            continue
        if cur:
            out.append(cur)
            cur = ""
        while len(piece) > width:
            out.append(piece[:width])
            piece = piece[width:]
        cur = piece
    if cur:
        out.append(cur)
    return out


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


def _normalise(surfaces: Sequence[Mapping[str, Any]]) -> tuple[list[_Kind], np.ndarray, np.ndarray]:
    kinds: dict[tuple, int] = {}
    kind_of = np.empty(len(surfaces), dtype=np.int64)
    row_of = np.empty(len(surfaces), dtype=np.int64)
    order: list[_Kind] = []
    bez_knots: dict[int, np.ndarray] = {}
    for idx, s in enumerate(surfaces):
        pts = s["points"]
        if not (isinstance(pts, np.ndarray) and pts.dtype == np.float64):
            pts = np.asarray(pts, dtype=np.float64)
        if pts.ndim != 3 or pts.shape[2] != 3:
            raise ValueError(f"surface {idx}: points must have shape (nu, nv, 3), got {pts.shape}")
        nu, nv = pts.shape[0], pts.shape[1]
        w = s.get("weights")
        if w is not None:
            w = np.asarray(w, dtype=np.float64)
            if w.shape != (nu, nv):
                raise ValueError(f"surface {idx}: weights must have shape {(nu, nv)}, got {w.shape}")
        if s.get("knots_u") is None and s.get("knots_v") is None:
            du, dv = nu - 1, nv - 1
            if "degree" in s and s["degree"] is not None and tuple(s["degree"]) != (du, dv):
                raise ValueError(f"surface {idx}: degree {tuple(s['degree'])} does not match a Bezier net {pts.shape[:2]}")
            if du < 1 or dv < 1:
                raise ValueError(f"surface {idx}: a Bezier patch needs at least 2x2 control points")
            ku = bez_knots.get(du)
            if ku is None:
                ku = bez_knots[du] = _bezier_knots(du)
            kv = bez_knots.get(dv)
            if kv is None:
                kv = bez_knots[dv] = _bezier_knots(dv)
        else:
            if s.get("degree") is None or s.get("knots_u") is None or s.get("knots_v") is None:
                raise ValueError(f"surface {idx}: a B-spline surface needs knots_u, knots_v and degree")
            du, dv = (int(d) for d in s["degree"])
            ku = np.asarray(s["knots_u"], dtype=np.float64).ravel()
            kv = np.asarray(s["knots_v"], dtype=np.float64).ravel()
            if du < 1 or dv < 1 or nu < du + 1 or nv < dv + 1:
                raise ValueError(f"surface {idx}: degrees {(du, dv)} need at least {(du + 1, dv + 1)} control points")
            if ku.size != nu + du + 1 or kv.size != nv + dv + 1:
                raise ValueError(
                    f"surface {idx}: need {nu + du + 1} u-knots and {nv + dv + 1} v-knots, "
                    f"got {ku.size} and {kv.size}"
                )
            for name, kn, d, n in (("u", ku, du, nu), ("v", kv, dv, nv)):
                if not np.all(np.isfinite(kn)) or np.any(np.diff(kn) < 0):
                    raise ValueError(f"surface {idx}: knots_{name} must be finite and non-decreasing")
                if not kn[d] < kn[n]:
                    raise ValueError(f"surface {idx}: empty parameter range in {name}")
        key = (du, dv, nu, nv)
        ki = kinds.get(key)
        if ki is None:
            ki = kinds[key] = len(order)
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
        n = len(kind.rows)
        kind.pts = np.stack(kind.pts) if n else np.zeros((0, kind.nu, kind.nv, 3))
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


class _PDWriter:
    """Writes P records sequentially, remembering pointer and line count of
    every entity."""

    def __init__(self, fh, n_entities: int):
        self.fh = fh
        self.next_line = 1  # 1-based P sequence number of the next record
        self.pd_ptr = np.zeros(n_entities, dtype=np.int64)
        self.pd_cnt = np.zeros(n_entities, dtype=np.int64)

    def emit(self, ents: np.ndarray, chars: np.ndarray, off: np.ndarray, lens: np.ndarray, big: bool) -> None:
        """``ents`` (G,) entity indices (0-based, DE order, consecutive);
        token ``(e, t)`` is ``chars[e, t, off[e, t] : off[e, t] + lens[e, t]]``
        (``lens`` 0 = padding after the last token).  Delimiters are added
        here: ',' after each token, ';' after the last one of an entity."""
        g, t = lens.shape
        real = lens > 0
        ntok = real.sum(axis=1)
        flat = chars.reshape(g * t, _W1)
        offf = off.reshape(-1)
        lflat = lens.reshape(-1)
        flat[np.arange(g * t), offf + lflat] = _COMMA
        last = np.arange(g) * t + ntok - 1  # flat index of each entity's last token
        flat[last, offf[last] + lflat[last]] = _SEMI
        tl = np.where(real, lens + 1, 0)
        if big:
            assert g == 1
            _, col1, nl = _pack_sequential(tl[0], _PD_COLS)
            col, nlines = col1[None, :], np.array([nl])
        else:
            _, col, nlines = _pack_lockstep(tl, _PD_COLS)
        # the PD text as one stream, then cut into records where a token
        # starts a new line (column 0)
        tlf = tl.reshape(-1)
        c = np.arange(_W1, dtype=np.int64)[None, :]
        srcmask = (c >= offf[:, None]) & (c < (offf + tlf)[:, None])
        blob = np.concatenate([flat[srcmask], np.full(_PD_COLS, _SP, dtype=np.uint8)])
        tstart = np.cumsum(tlf) - tlf
        lstart = tstart[(col.reshape(-1) == 0) & (tlf > 0)]
        total = lstart.size
        assert total == int(nlines.sum())
        llen = np.diff(np.append(lstart, blob.size - _PD_COLS))
        ar = np.arange(_PD_COLS, dtype=np.int64)[None, :]
        rows = np.empty((total, _REC), dtype=np.uint8)
        rows[:, :_PD_COLS] = np.where(ar < llen[:, None], blob[lstart[:, None] + ar], np.uint8(_SP))
        rows[:, _PD_COLS] = _SP
        first = np.cumsum(nlines) - nlines  # chunk-relative first record
        _put_int(rows, 65, 7, np.repeat(2 * ents + 1, nlines), zero_pad=False)
        rows[:, 72] = ord("P")
        _put_int(rows, 73, 7, np.arange(self.next_line, self.next_line + total), zero_pad=True)
        rows[:, 80] = 10
        self.pd_ptr[ents] = self.next_line + first
        self.pd_cnt[ents] = nlines
        self.next_line += total
        if self.next_line - 1 > 9_999_999:
            raise ValueError("IGES parameter section exceeds 9,999,999 records")
        self.fh.write(rows.tobytes())


def _entity_tokens(kind: _Kind, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tokens ``(g, T, _W1)``, offsets and lengths of the entity-128 parameter
    lists of ``rows`` of one kind.  Columns equal in all rows (knots,
    parameter range, unit weights, ...) are formatted once."""
    ints, floats = _kind_tables(kind, rows)
    g = rows.size
    ni, nf = ints.shape[1], floats.shape[1]
    nt = ni + nf
    chars = np.empty((g, nt, _W1), dtype=np.uint8)
    off = np.empty((g, nt), dtype=np.int64)
    lens = np.empty((g, nt), dtype=np.int64)
    ic, io, il = _format_ints(ints)
    chars[:, :ni] = ic.reshape(g, ni, _W1)
    off[:, :ni] = io.reshape(g, ni)
    lens[:, :ni] = il.reshape(g, ni)
    const = np.all(floats == floats[:1], axis=0)
    cidx = np.nonzero(const)[0]
    vidx = np.nonzero(~const)[0]
    if cidx.size:
        c, o, ln = _format_reals(floats[0, cidx])
        chars[:, ni + cidx] = c[None]
        off[:, ni + cidx] = o[None]
        lens[:, ni + cidx] = ln[None]
    if vidx.size:
        c, o, ln = _format_reals(floats[:, vidx])
        chars[:, ni + vidx] = c.reshape(g, vidx.size, _W1)
        off[:, ni + vidx] = o.reshape(g, vidx.size)
        lens[:, ni + vidx] = ln.reshape(g, vidx.size)
    return chars, off, lens


def _emit_surfaces(pdw: _PDWriter, kinds: list[_Kind], kind_of: np.ndarray, row_of: np.ndarray) -> None:
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
            chars = np.full((g, tmax, _W1), _SP, dtype=np.uint8)
            off = np.zeros((g, tmax), dtype=np.int64)
            lens = np.zeros((g, tmax), dtype=np.int64)
            for ki in kinds_here:
                sel = np.nonzero(kof == ki)[0]
                c, o, ln = _entity_tokens(kinds[ki], row_of[start:end][sel])
                nt = c.shape[1]
                chars[sel, :nt] = c
                off[sel, :nt] = o
                lens[sel, :nt] = ln
        pdw.emit(ents, chars, off, lens, big=(g == 1 and tmax > _BIG_ENTITY))
        start = end


# ----------------------------------------------------------------------------
# Directory Entry section


def _de_records(
    etype: np.ndarray,
    pd_ptr: np.ndarray,
    pd_cnt: np.ndarray,
    form: np.ndarray,
    status: Sequence[bytes],
    status_idx: np.ndarray,
    labels: Sequence[bytes],
    label_idx: np.ndarray,
    subscript: np.ndarray,
) -> bytes:
    e = etype.size
    rows = np.full((2 * e, _REC), _SP, dtype=np.uint8)
    l1 = rows[0::2]
    l2 = rows[1::2]
    zeros = np.zeros(e, dtype=np.int64)
    _put_int(l1, 0, 8, etype, False)  # 1 entity type
    _put_int(l1, 8, 8, pd_ptr, False)  # 2 parameter data pointer
    for f in range(2, 8):  # 3 structure .. 8 label display: 0
        _put_int(l1, 8 * f, 8, zeros, False)
    stab = np.array([np.frombuffer(s, dtype=np.uint8) for s in status])
    l1[:, 64:72] = stab[status_idx]  # 9 status number
    _put_int(l2, 0, 8, etype, False)  # 11 entity type
    _put_int(l2, 8, 8, zeros, False)  # 12 line weight
    _put_int(l2, 16, 8, zeros, False)  # 13 color
    _put_int(l2, 24, 8, pd_cnt, False)  # 14 parameter line count
    _put_int(l2, 32, 8, form, False)  # 15 form number
    # 16, 17 reserved: blank
    ltab = np.array([np.frombuffer(s.rjust(8), dtype=np.uint8) for s in labels])
    l2[:, 56:64] = ltab[label_idx]  # 18 entity label
    _put_int(l2, 64, 8, subscript, False)  # 19 entity subscript
    rows[:, 72] = ord("D")
    _put_int(rows, 73, 7, np.arange(1, 2 * e + 1), zero_pad=True)
    rows[:, 80] = 10
    return rows.tobytes()


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


def _real_text(v: float) -> str:
    c, o, l = _format_reals(np.array([float(v)]))
    return c[0, o[0] : o[0] + l[0]].tobytes().decode("ascii")


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
        _hollerith(product_id),  # 3 product id (sending system)
        _hollerith(file_name),  # 4 file name
        _hollerith("c1surf"),  # 5 native system id
        _hollerith(f"c1surf {__version__}"),  # 6 preprocessor version
        "32",  # 7 bits of an integer
        "38",  # 8 single precision: max power of ten
        "6",  # 9 single precision: significant digits
        "308",  # 10 double precision: max power of ten
        "15",  # 11 double precision: significant digits
        _hollerith(product_id),  # 12 product id (receiving system)
        "1.0",  # 13 model space scale
        str(flag),  # 14 units flag
        _hollerith(uname),  # 15 units name
        "1",  # 16 max number of line weight gradations
        "1.0",  # 17 width of max line weight (model units)
        _hollerith(stamp),  # 18 date/time of file generation
        _real_text(resolution),  # 19 minimum user-intended resolution
        _real_text(max_coord),  # 20 approximate maximum coordinate value
        _hollerith(author),  # 21 author
        _hollerith(organization),  # 22 organization
        "11",  # 23 version flag: 11 = IGES 5.3
        "0",  # 24 drafting standard: none
        _hollerith(stamp),  # 25 date/time model created/modified
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


def write_iges(
    path: str | os.PathLike,
    surfaces: Sequence[Mapping[str, Any]],
    *,
    units: str = "mm",
    group: bool | str = True,
    author: str = "c1surf",
    description: str | None = None,
    organization: str = "",
    file_name: str | None = None,
    product_id: str | None = None,
    timestamp: Any = None,
    resolution: float | None = None,
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

    ``units``: key of `UNITS` (``mm``, ``m``, ``cm``, ``in``, ...).
    ``file_name``: name recorded in the Global section (default: basename of
    ``path``; pass the final name when writing to a temporary file).
    ``product_id``: default = ``file_name`` without extension.
    ``timestamp``: datetime (UTC) or seconds since the epoch; default
    ``$SOURCE_DATE_EPOCH`` or 0.  ``resolution``: default 1e-9 * bounding box
    diagonal (1e-9 if that is 0).

    ``path`` must be a seekable regular file (the Parameter section is written
    before the Directory section it is indexed from).
    """
    ukey = str(units).lower()
    if ukey not in UNITS:
        raise ValueError(f"unknown units {units!r}; use one of {sorted(UNITS)}")
    surfaces = list(surfaces)
    kinds, kind_of, row_of = _normalise(surfaces)
    n_surf = len(surfaces)
    if isinstance(group, str):
        if group not in ("unordered", "ordered"):
            raise ValueError(f"group must be a bool, 'unordered' or 'ordered', not {group!r}")
        group_form = 7 if group == "unordered" else 15
    else:
        group_form = 7 if group else 0
    has_group = group_form != 0 and n_surf > 0
    n_ent = n_surf + (1 if has_group else 0)
    if 2 * n_ent > 9_999_999:
        raise ValueError("too many entities for one IGES file")

    # extent of the model (control points bound the surfaces)
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for kind in kinds:
        if kind.pts.size:
            lo = np.minimum(lo, kind.pts.reshape(-1, 3).min(axis=0))
            hi = np.maximum(hi, kind.pts.reshape(-1, 3).max(axis=0))
    if n_surf:
        max_coord = float(np.max(np.maximum(np.abs(lo), np.abs(hi))))
        diag = float(np.linalg.norm(hi - lo))
    else:
        max_coord, diag = 0.0, 0.0
    if resolution is None:
        resolution = 1e-9 * diag if diag > 0 else 1e-9
    resolution = float(resolution)
    if not (np.isfinite(resolution) and resolution > 0):
        raise ValueError("resolution must be positive")

    fname = os.path.basename(os.fspath(path)) if file_name is None else str(file_name)
    pid = os.path.splitext(fname)[0] if product_id is None else str(product_id)
    stamp = _timestamp_string(timestamp)

    if description is None:
        nb = sum(1 for s in surfaces if s.get("knots_u") is None)
        description = (
            f"c1surf surface: {n_surf} rational B-spline surface entities (type 128), "
            f"{nb} of them Bezier patches"
            + (f", collected in one group (type 402 form {group_form})." if has_group else ".")
        )
    start_lines: list[str] = []
    for para in _ascii(description).splitlines() or [""]:
        start_lines.extend(textwrap.wrap(para, _SG_COLS) or [""])
    gparams = _global_params(
        file_name=fname,
        product_id=pid,
        units=ukey,
        author=author,
        organization=organization,
        stamp=stamp,
        resolution=resolution,
        max_coord=max_coord,
    )
    global_lines = _pack_text_params(gparams, _SG_COLS)
    s_bytes = _text_records(start_lines, "S")
    g_bytes = _text_records(global_lines, "G")
    d_offset = len(s_bytes) + len(g_bytes)
    p_offset = d_offset + 2 * n_ent * _REC

    with open(path, "wb") as fh:
        fh.write(s_bytes)
        fh.write(g_bytes)
        fh.seek(p_offset)
        pdw = _PDWriter(fh, n_ent)
        _emit_surfaces(pdw, kinds, kind_of, row_of)
        if has_group:
            members = 2 * np.arange(n_surf, dtype=np.int64) + 1
            ints = np.concatenate([[402, n_surf], members])
            ic, io, il = _format_ints(ints)
            pdw.emit(
                np.array([n_surf]),
                ic[None, :, :],
                io[None, :],
                il[None, :],
                big=ints.size > _BIG_ENTITY,
            )
        n_p = pdw.next_line - 1

        etype = np.full(n_ent, 128, dtype=np.int64)
        form = np.zeros(n_ent, dtype=np.int64)
        status_idx = np.full(n_ent, 1 if has_group else 0, dtype=np.int64)
        label_idx = np.zeros(n_ent, dtype=np.int64)
        bspl = np.array([s.get("knots_u") is not None for s in surfaces], dtype=bool)
        label_idx[:n_surf][bspl] = 1
        subscript = np.arange(1, n_ent + 1, dtype=np.int64)
        if has_group:
            etype[-1] = 402
            form[-1] = group_form
            status_idx[-1] = 0
            label_idx[-1] = 2
            subscript[-1] = 0
        d_bytes = _de_records(
            etype,
            pdw.pd_ptr,
            pdw.pd_cnt,
            form,
            [_STATUS_INDEPENDENT, _STATUS_GROUP_MEMBER],
            status_idx,
            [b"BEZIER", b"BSPLINE", b"C1SURF"],
            label_idx,
            subscript,
        )
        fh.seek(d_offset)
        fh.write(d_bytes)

        n_s, n_g, n_d = len(start_lines), len(global_lines), 2 * n_ent
        term = f"S{n_s:07d}G{n_g:07d}D{n_d:07d}P{n_p:07d}"
        t_bytes = _text_records([term], "T")
        fh.seek(p_offset + n_p * _REC)
        fh.write(t_bytes)
        fh.truncate()
