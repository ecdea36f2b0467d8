"""IGES numbers as text, vectorised: reals that read back to the same double, integers, fixed columns.

Every real is written with the fewest digits (16 or 17 significant digits,
trailing zeros dropped) that read back to the *same* IEEE double, without an
exponent whenever ``1e-4 <= |x| < 1e16`` (the range in which Python's
``repr`` is positional); other values fall back to ``repr`` with the exponent
written as ``D`` (IGES double precision).

A formatted array is ``(chars, off, lens)``: row ``i`` of the ``(n, WIDTH + 1)``
uint8 array ``chars`` holds the text of number ``i`` in columns
``off[i] .. off[i] + lens[i] - 1`` (other columns are undefined; column
``off + lens`` is always free for a delimiter).
"""
from __future__ import annotations

import numpy as np

__all__ = ["format_reals", "format_ints", "real_text", "put_int", "WIDTH", "SLOT", "SPACE", "ZERO"]

WIDTH = 24  # widest formatted number (without delimiter)
SLOT = WIDTH + 1  # ... with its delimiter
SPACE, _DOT, _MINUS, ZERO = 32, 46, 45, 48

_POW10 = 10.0 ** np.arange(0, 23)  # 10**0 .. 10**22 are exact doubles
_I10 = 10 ** np.arange(0, 19, dtype=np.int64)
#: "0000" .. "9999" as ASCII rows
_DIGITS4 = (np.stack([(np.arange(10000) // 10**p) % 10 for p in (3, 2, 1, 0)], axis=1) + ZERO).astype(np.uint8)


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


def _digits17(a: np.ndarray):
    """Decimal exponent k and 17 significant digits d (an int64) of each positive ``a``: a ~ d 10**(k - 16).

    Returns (k, d, ok); ``ok`` is False where the digits could not be made
    exactly (practically never: those values go to ``repr``).
    """
    k = np.floor(np.log10(a)).astype(np.int64)
    np.clip(k, -6, 16, out=k)
    d = _round_scaled(a, 16 - k)
    # log10 may be off by one near powers of ten; fix up (twice at most)
    for _ in range(2):
        bad = (d >= _I10[17]) | (d < _I10[16])
        if not bad.any():
            break
        k[bad] += (d[bad] >= _I10[17]).astype(np.int64) - (d[bad] < _I10[16])
        np.clip(k, -6, 16, out=k)
        d[bad] = _round_scaled(a[bad], 16 - k[bad])
    ok = (k >= -4) & (k <= 15) & (d >= _I10[16]) & (d < _I10[17])
    return k, d, ok


def _prefer_16(a: np.ndarray, k: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``d`` with its 17th digit zero wherever 16 significant digits read back exactly to ``a``.

    The check is exact when the 16 digits are an exact double and the power of
    ten is <= 1e22 (one correctly rounded division == correctly rounded strtod).
    """
    d16 = _round_scaled(a, 15 - k)
    d16f = d16.astype(np.float64)
    use16 = (d16 >= _I10[15]) & (d16 < _I10[16]) & (d16f.astype(np.int64) == d16)
    use16 &= d16f / _POW10[15 - k] == a
    return np.where(use16, d16 * 10, d)


def _positional_text(d: np.ndarray, k: np.ndarray, chars: np.ndarray | None = None):
    """Positional text of d 10**(k - 16) (17 digits d, -4 <= k <= 15): (chars (m, SLOT), length (m,)).

    Column 0 holds a minus sign (used for negative numbers, skipped by ``off``
    otherwise); the number follows from column 1 with trailing zeros dropped.
    """
    m = d.size
    # 17 ASCII digits (4-digit lookup table), preceded by 4 zeros and
    # followed by padding: shifting by s = 0..4 is then a column slice
    z = np.full((m, 4 + SLOT - 1), ZERO, dtype=np.uint8)
    z[:, 4] = (d // _I10[16]).astype(np.uint8) + ZERO
    r = d % _I10[16]
    z[:, 5:9] = _DIGITS4[r // _I10[12]]
    z[:, 9:13] = _DIGITS4[(r // _I10[8]) % 10000]
    z[:, 13:17] = _DIGITS4[(r // _I10[4]) % 10000]
    z[:, 17:21] = _DIGITS4[r % 10000]
    nd = 17 - np.argmax(z[:, 20:3:-1] != ZERO, axis=1)  # significant digits
    s = np.maximum(-k, 0)  # zeros after "0." plus one (0..4)
    kk = np.maximum(k, 0)  # column of the last integer digit
    length = kk + 2 + np.maximum(nd + s - kk - 1, 1)
    # ext[:, j] = j-th char of the digits preceded by s zeros (rows of each s copied as slices)
    ext = z[:, 4 : 4 + SLOT - 1].copy()
    for sv in np.unique(s[s > 0]).tolist():
        rows = np.flatnonzero(s == sv)
        ext[rows] = z[rows, 4 - sv : 4 - sv + SLOT - 1]
    # body char j (stored in column j+1): ext[j] for j <= kk, '.' for j == kk+1, ext[j-1] after it
    chars = np.empty((m, SLOT), dtype=np.uint8) if chars is None else chars
    chars[:, 0] = _MINUS
    for kv in np.unique(kk).tolist():  # rows of one decimal point column at a time
        rows = slice(None) if kv == kk[0] and np.all(kk == kv) else np.flatnonzero(kk == kv)
        chars[rows, 1 : kv + 2] = ext[rows, : kv + 1]
        chars[rows, kv + 2] = _DOT
        chars[rows, kv + 3 :] = ext[rows, kv + 1 : SLOT - 2]
    return chars, length


def format_reals(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Format finite doubles as IGES reals: ``(chars, off, lens)`` (module docstring).

    Every string reads back (correctly rounded decimal -> double) to exactly the input value.
    """
    x = np.ascontiguousarray(x, dtype=np.float64).ravel()
    n = x.size
    out = np.empty((n, SLOT), dtype=np.uint8)
    off = np.zeros(n, dtype=np.int64)
    lens = np.zeros(n, dtype=np.int64)
    a = np.abs(x)
    fast = np.flatnonzero((a >= 1e-4) & (a < 1e16))  # where repr is positional
    if fast.size:
        k, d, ok = _digits17(a[fast])
        fast, k, d = fast[ok], k[ok], d[ok]
        d = _prefer_16(a[fast], k, d)
        everything = fast.size == n  # then write straight into ``out``
        chars, length = _positional_text(d, k, out if everything else None)
        if not everything:
            out[fast] = chars
        negative = (x[fast] < 0).astype(np.int64)
        off[fast] = 1 - negative
        lens[fast] = length + negative
    done = np.zeros(n, dtype=bool)
    done[fast] = True
    for i in np.flatnonzero(~done).tolist():
        b = b"0.0" if x[i] == 0.0 else _repr_iges(x[i]).encode("ascii")
        out[i, : len(b)] = np.frombuffer(b, dtype=np.uint8)
        lens[i] = len(b)
    return out, off, lens


def format_ints(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Format integers; same ``(chars, off, lens)`` convention as `format_reals` (the text ``str(v)``).

    The distinct values are formatted once, all at a time: their decimal
    digits from a 4-digit table, then copied left past the leading zeros,
    one slice per digit count (a B-rep's pointers are mostly distinct:
    hundreds of thousands of them).
    """
    v = np.asarray(v, dtype=np.int64).ravel()
    u, inv = np.unique(v, return_inverse=True)
    table = np.full((u.size, SLOT), SPACE, dtype=np.uint8)
    lens = np.zeros(u.size, dtype=np.int64)
    a = np.abs(u)
    ok = a >= 0  # False for -2**63, whose absolute value overflows
    digits = np.maximum(np.searchsorted(_I10, a, side="right"), 1)  # |v| < 10**19
    groups = (int(digits[ok].max()) + 3) // 4 if ok.any() else 0
    right = np.concatenate([_DIGITS4[(a // _I10[4 * k]) % 10000] for k in range(groups - 1, -1, -1)] or
                           [np.zeros((u.size, 0), np.uint8)], axis=1)  # (u, 4 groups), leading zeros
    sign = (u < 0).astype(np.int64)
    for count in np.unique(digits[ok]).tolist():
        for s in (0, 1):
            rows = np.flatnonzero(ok & (digits == count) & (sign == s))
            table[rows, s : s + count] = right[rows, 4 * groups - count :]
            lens[rows] = count + s
    table[sign.astype(bool) & ok, 0] = _MINUS
    for r in np.flatnonzero(~ok).tolist():
        b = str(int(u[r])).encode("ascii")
        table[r, : len(b)] = np.frombuffer(b, dtype=np.uint8)
        lens[r] = len(b)
    inv = inv.ravel()
    return table[inv], np.zeros(v.size, dtype=np.int64), lens[inv]


def real_text(v: float) -> str:
    """One real as `format_reals` writes it."""
    c, o, n = format_reals(np.array([float(v)]))
    return c[0, o[0] : o[0] + n[0]].tobytes().decode("ascii")


def put_int(rows: np.ndarray, start: int, width: int, values: np.ndarray, zero_pad: bool) -> None:
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
        ch[np.arange(width)[None, :] < (width - ndig)[:, None]] = SPACE
    rows[:, start : start + width] = ch
