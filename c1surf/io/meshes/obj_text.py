"""The line and token structure of an OBJ file, found with array operations (``obj.parse_obj`` reads it).

The whole file is handled as one ``uint8`` array: line and token
boundaries, record keywords and token counts come from array operations,
and all numbers of one record kind are parsed in a single
``np.fromstring`` call.  A Python loop over lines runs only when that bulk
parse fails, to find the offending line for the error message (or to
accept rare-but-legal spellings such as ``f 1/ 2/ 3/``).
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from ..errors import MeshInputError

__all__ = ["ObjText", "ABSENT", "WHITESPACE", "V", "VT", "VN", "F", "GROUP"]

# ASCII whitespace as bytes.split() and np.fromstring understand it.
WHITESPACE = np.zeros(256, dtype=bool)
WHITESPACE[[9, 10, 11, 12, 13, 32]] = True

# Marks a missing /vt or /vn part of a face corner (0 is a real, if
# invalid, OBJ index, so it cannot be used).
ABSENT = np.iinfo(np.int64).min

OTHER, V, VT, VN, F, GROUP = range(6)
_KEYWORD = {V: "v", VT: "vt", VN: "vn", F: "f"}

_INT_RE = re.compile(rb"[+-]?[0-9]+\Z")

_FORMS = "write v, v/vt, v//vn or v/vt/vn with whole numbers"


def _numbers(text: bytes, dtype, expected: int):
    """Parse whitespace-separated numbers; None unless exactly `expected`.

    Returns
    -------
    ndarray, shape (expected,), or None
    """
    if expected == 0:
        # np.fromstring returns a bogus value for blank input.
        return np.empty(0, dtype=dtype)
    with warnings.catch_warnings():
        # Trailing garbage is a DeprecationWarning (future ValueError).
        warnings.simplefilter("error", DeprecationWarning)
        try:
            vals = np.fromstring(text, dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    return vals if vals.size == expected else None



class ObjText:
    """Line/token structure of an OBJ file held as a ``uint8`` array.

    Attributes
    ----------
    buf : ndarray, shape (N,), uint8
        File bytes with comments and record keywords blanked to spaces.
    starts, ends : ndarray, shape (L,), int64
        Byte range of each line (``ends`` excludes the newline).
    ntok : ndarray, shape (L,), int64
        Tokens per line, keyword included.
    kind : ndarray, shape (L,), int8
        Record kind of each line (``V``, ``F``, ...).
    kw_pos : ndarray, shape (L,), int64
        Byte offset of each line's keyword (-1 for blank lines).
    kw_len : ndarray, shape (L,), int64
        Length of each line's keyword (0 for blank lines).

    A line ending in a backslash is joined with the next: the record
    belongs to its first line, and the lines it continues into are empty.
    """

    def __init__(self, data: bytes, path: str):
        self.path = path
        buf = np.frombuffer(data, dtype=np.uint8).copy()
        if data.startswith(b"\xef\xbb\xbf"):  # UTF-8 byte order mark
            buf[:3] = 32
        if b"\n" not in data and b"\r" in data:  # classic Mac line ends
            buf[buf == 13] = 10
        n = buf.size
        nl = np.flatnonzero(buf == 10)
        self.starts = np.concatenate(([0], nl + 1))
        self.ends = np.concatenate((nl, [n]))
        self.buf = buf

        self._blank_comments(nl)
        self._join_continuations(nl)

        # Control bytes count as blanks here (a 256-entry table lookup
        # costs 10x more); one inside a number still fails the parse.
        nonws = buf > 32
        first = nonws.copy()
        first[1:] &= ~nonws[:-1]
        ts = np.flatnonzero(first)
        last = nonws
        last[:-1] &= ~nonws[1:]  # reuses nonws: not needed any more
        te = np.flatnonzero(last) + 1
        del first, last, nonws

        tok0 = np.searchsorted(ts, self.starts)
        self.ntok = np.diff(np.append(tok0, ts.size))
        lines = np.flatnonzero(self.ntok > 0)
        k0 = ts[tok0[lines]]
        klen = te[tok0[lines]] - k0
        c0 = buf[k0]
        c1 = buf[np.minimum(k0 + 1, n - 1)]
        one, two = klen == 1, klen == 2
        is_v = c0 == ord("v")
        kind = np.zeros(self.starts.size, dtype=np.int8)
        kind[lines[one & is_v]] = V
        kind[lines[one & (c0 == ord("f"))]] = F
        kind[lines[two & is_v & (c1 == ord("t"))]] = VT
        kind[lines[two & is_v & (c1 == ord("n"))]] = VN
        kind[lines[one & ((c0 == ord("g")) | (c0 == ord("o")))]] = GROUP
        self.kind = kind
        self.kw_pos = np.full(self.starts.size, -1, dtype=np.int64)
        self.kw_pos[lines] = k0
        self.kw_len = np.zeros(self.starts.size, dtype=np.int64)
        self.kw_len[lines] = klen

        # Blank the keywords so a record's bytes are just its numbers.
        kw1 = self.kw_pos[(kind == V) | (kind == F)]
        kw2 = self.kw_pos[(kind == VT) | (kind == VN)]
        buf[kw1] = 32
        buf[kw2] = 32
        buf[kw2 + 1] = 32

    def _blank_comments(self, nl):
        """Blank everything from the first '#' of a line to its end."""
        buf = self.buf
        hashes = np.flatnonzero(buf == 35)
        if hashes.size == 0:
            return
        hline = np.searchsorted(nl, hashes)  # line of each '#'
        first = np.flatnonzero(np.diff(hline, prepend=-1))
        begin = hashes[first]
        length = self.ends[hline[first]] - begin
        # Byte offsets of all comment text, in O(comment bytes) rather
        # than O(file bytes).
        skip = np.cumsum(length) - length
        idx = np.arange(int(length.sum())) + np.repeat(begin - skip, length)
        buf[idx] = 32

    def _join_continuations(self, nl):
        """Join each line ending in a backslash with the next one (OBJ line continuation).

        The joined record belongs to its first physical line: that line's
        byte range grows to the end of the last line it continues into, and
        the continued lines become empty, so line numbers stay physical.
        The backslashes and the newlines they escape are blanked.
        """
        cont = self._continued(nl)
        if cont is None:
            return
        cont[-1] = False  # a backslash on the last line continues into nothing
        self.buf[self.ends[cont]] = 32  # the escaped newlines
        idx = np.arange(cont.size)
        joined = np.concatenate(([False], cont[:-1]))
        if not joined.any():
            return
        open_end = np.flatnonzero(~cont)  # each run of joined lines ends at one of these
        run_end = self.ends[open_end[np.searchsorted(open_end, idx)]]
        heads = cont & ~joined
        self.ends[heads] = run_end[heads]
        self.starts[joined] = np.minimum(run_end[joined] + 1, self.buf.size)
        self.ends[joined] = self.starts[joined]

    def _continued(self, nl):
        """(L,) bool, lines whose last non-blank byte is a backslash (now blanked), or None if there are none."""
        buf = self.buf
        slashes = np.flatnonzero(buf == 92)
        if slashes.size == 0:
            return None
        line = np.searchsorted(nl, slashes)
        tail = self.ends[line] - slashes - 1  # bytes after each backslash on its line
        blank_after = np.ones(slashes.size, dtype=bool)
        if tail.sum():
            # Offsets of all tail bytes, in O(tail bytes), as in _blank_comments.
            skip = np.cumsum(tail) - tail
            idx = np.arange(int(tail.sum())) + np.repeat(slashes + 1 - skip, tail)
            owner = np.repeat(np.arange(slashes.size), tail)
            blank_after = np.bincount(owner, weights=~WHITESPACE[buf[idx]], minlength=slashes.size) == 0
        if not blank_after.any():
            return None
        buf[slashes[blank_after]] = 32
        cont = np.zeros(self.starts.size, dtype=bool)
        cont[line[blank_after]] = True
        return cont

    def records(self, keyword: bytes) -> np.ndarray:
        """0-based lines of the records with ``keyword`` among those not parsed (kind ``OTHER``).

        Returns
        -------
        ndarray, shape (K,), int64
        """
        lines = np.flatnonzero((self.kind == OTHER) & (self.kw_len == len(keyword)))
        for i, byte in enumerate(keyword):
            lines = lines[self.buf[self.kw_pos[lines] + i] == byte]
        return lines

    def gather(self, lines):
        """Bytes of the given lines (with newlines), in file order.

        Returns
        -------
        data : ndarray, shape (M,), uint8
        offsets : ndarray, shape (len(lines) + 1,), int64
            Where each line starts in ``data``.
        """
        lengths = np.diff(np.append(self.starts, self.buf.size))
        mask = np.zeros(self.starts.size, dtype=bool)
        mask[lines] = True
        offsets = np.zeros(lines.size + 1, dtype=np.int64)
        np.cumsum(lengths[lines], out=offsets[1:])
        return self.buf[np.repeat(mask, lengths)], offsets

    def numbers(self, lines, min_count, need):
        """Parse the numbers of records on ``lines`` (all of one kind).

        Returns
        -------
        vals : ndarray, shape (sum(counts),), float64
        counts : ndarray, shape (len(lines),), int64
            Numbers per record.
        """
        counts = self.ntok[lines] - 1
        short = np.flatnonzero(counts < min_count)
        if short.size:
            li = int(lines[short[0]])
            k = int(counts[short[0]])
            kw = _KEYWORD[int(self.kind[li])]
            raise MeshInputError(
                self.path, f"`{kw}` line has {k} number{'s' if k != 1 else ''}"
                f": {need}", li + 1)
        data, offsets = self.gather(lines)
        vals = _numbers(data.tobytes(), np.float64, int(counts.sum()))
        if vals is None:
            # Re-parse in chunks so only one chunk goes line by line.
            parts = []
            for a, b in _chunks(lines.size):
                piece = data[offsets[a]:offsets[b]].tobytes()
                got = _numbers(piece, np.float64, int(counts[a:b].sum()))
                parts.append(got if got is not None
                             else self._slow_numbers(lines[a:b]))
            vals = np.concatenate(parts)
        return vals, counts

    def _slow_numbers(self, lines):
        """Line-by-line parse, only to name the line with a bad number."""
        out = []
        for li in lines.tolist():
            text = self.buf[self.starts[li]:self.ends[li]].tobytes()
            toks = text.split()
            vals = _numbers(text, np.float64, len(toks))
            if vals is None:
                kw = _KEYWORD[int(self.kind[li])]
                bad = next((t for t in toks
                            if _numbers(t, np.float64, 1) is None), text)
                raise MeshInputError(
                    self.path, f"cannot read {_show(bad)} as a number in a "
                    f"`{kw}` line: write plain decimal numbers such as 1.5 "
                    "or -2e-3", li + 1)
            out.append(vals)
        return np.concatenate(out)

    def face_corners(self, f_lines, sizes):
        """Raw vertex / texture / normal indices of every face corner.

        Returns
        -------
        v : ndarray, shape (C,), int64
        vt, vn : ndarray, shape (C,), int64, or None
            ``ABSENT`` where a corner has no such index; None if no
            corner has one.
        """
        data, offsets = self.gather(f_lines)
        got = _fast_corners(data, int(sizes.sum()))
        if got is None:
            # Chunks that fail the bulk parse go corner by corner: that
            # names a bad token, or accepts legal oddities such as "1/".
            parts = []
            for a, b in _chunks(f_lines.size):
                piece = _fast_corners(data[offsets[a]:offsets[b]],
                                      int(sizes[a:b].sum()))
                if piece is None:
                    piece = self._slow_corners(f_lines[a:b])
                parts.append(piece)
            got = tuple(
                np.concatenate([
                    np.full(p[0].size, ABSENT, dtype=np.int64)
                    if p[i] is None else p[i] for p in parts])
                for i in range(3))
        v, vt, vn = got
        if vt is not None and (vt == ABSENT).all():
            vt = None
        if vn is not None and (vn == ABSENT).all():
            vn = None
        return v, vt, vn

    def _slow_corners(self, f_lines):
        """Corner-by-corner parse: names the bad token, accepts ``1/``."""
        out = []
        for li in f_lines.tolist():
            text = self.buf[self.starts[li]:self.ends[li]].tobytes()
            for tok in text.split():
                parts = tok.split(b"/")
                if len(parts) > 3:
                    raise MeshInputError(
                        self.path, f"face corner {_show(tok)} has too many "
                        f"'/' parts: {_FORMS}", li + 1)
                if not parts[0]:
                    raise MeshInputError(
                        self.path, f"face corner {_show(tok)} has no vertex "
                        f"index: {_FORMS}", li + 1)
                row = [ABSENT, ABSENT, ABSENT]
                for i, part in enumerate(parts):
                    if not part:
                        continue
                    if not _INT_RE.match(part):
                        raise MeshInputError(
                            self.path, f"face corner {_show(tok)}: "
                            f"{_show(part)} is not a whole number: {_FORMS}",
                            li + 1)
                    # Clamp absurd values; the range check reports them.
                    row[i] = max(-2**62, min(2**62, int(part)))
                out.append(row)
        arr = np.array(out, dtype=np.int64).reshape(-1, 3)
        return arr[:, 0].copy(), arr[:, 1].copy(), arr[:, 2].copy()

    def groups(self, f_lines):
        """Group of each face from the nearest ``g``/``o`` line above it.

        Returns
        -------
        face_groups : ndarray, shape (F,), int64, or None
        group_names : list of str
            In order of first use; faces above any group are "default".
        """
        g_lines = np.flatnonzero(self.kind == GROUP)
        if g_lines.size == 0:
            return None, []
        table: dict[str, int] = {}
        ids = []
        for li in g_lines.tolist():  # group lines are few
            raw = self.buf[self.kw_pos[li] + 1:self.ends[li]].tobytes()
            name = b" ".join(raw.split()).decode("utf-8", "replace")
            ids.append(table.setdefault(name or "default", len(table)))
        default = table.setdefault("default", len(table))
        ids = np.array(ids + [default], dtype=np.int64)
        which = np.searchsorted(g_lines, f_lines) - 1  # -1: above all groups
        per_face = ids[which]  # which == -1 picks the appended default
        uniq, first, inverse = np.unique(per_face, return_index=True,
                                         return_inverse=True)
        order = np.argsort(first)
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        names = {i: nm for nm, i in table.items()}
        group_names = [names[int(uniq[o])] for o in order]
        return rank[inverse].astype(np.int64), group_names


def _fast_corners(fbytes, total):
    """Bulk parse of all face corners; None if anything is unusual.

    Parameters
    ----------
    fbytes : ndarray, shape (M,), uint8
        The bytes of all ``f`` lines, keywords blanked.
    total : int
        Number of corners (tokens) expected.
    """
    slashes = np.flatnonzero(fbytes == 47)
    if slashes.size == 0:  # plain vertex indices
        v = _numbers(fbytes.tobytes(), np.int64, total)
        return None if v is None else (v, None, None)
    nonws = fbytes > 32
    first = nonws.copy()
    first[1:] &= ~nonws[:-1]
    ts = np.flatnonzero(first)
    last = nonws
    last[:-1] &= ~nonws[1:]
    te = np.flatnonzero(last) + 1
    if ts.size != total:
        return None
    # Fields per corner = 1 + slashes inside the token.  Usual files use
    # one form throughout: check that cheaply before counting per token.
    k, rem = divmod(slashes.size, total)
    rows = slashes.reshape(total, k) if rem == 0 and k in (1, 2) else None
    if rows is not None and ((rows[:, 0] > ts) & (rows[:, -1] < te)).all():
        nf = np.full(total, k + 1, dtype=np.int64)
    else:
        owner = np.searchsorted(ts, slashes, side="right") - 1
        nf = np.bincount(owner, minlength=total) + 1
    if nf.max() > 3:
        return None
    raw = fbytes.tobytes()
    n_dd = raw.count(b"//")
    # "v//vn" -> "v 0 vn" keeps three fields; a literal 0 is caught below.
    vals = _numbers(raw.replace(b"//", b"/0/").replace(b"/", b" "),
                    np.int64, int(nf.sum()))
    if vals is None:  # e.g. an empty field such as "1/"
        return None
    off = np.cumsum(nf) - nf
    v = vals[off]
    vt = np.full(total, ABSENT, dtype=np.int64)
    vn = np.full(total, ABSENT, dtype=np.int64)
    m2, m3 = nf >= 2, nf == 3
    vt[m2] = vals[off[m2] + 1]
    vn[m3] = vals[off[m3] + 2]
    dd = m3 & (vt == 0)
    if int(dd.sum()) != n_dd:  # some 0 was written, not inserted by us
        return None
    vt[dd] = ABSENT
    return v, vt, vn


def _chunks(n: int, size: int = 4096):
    """(start, stop) pairs covering range(n) in blocks of ``size``."""
    return [(a, min(a + size, n)) for a in range(0, n, size)]


def _show(tok: bytes) -> str:
    """A token for an error message, quoted and shortened."""
    s = tok.decode("utf-8", "replace")
    return repr(s if len(s) <= 40 else s[:37] + "...")

