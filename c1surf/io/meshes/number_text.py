"""Numbers as text for whole arrays at once: the character matrices the OBJ writer joins into lines.

A *field* is a pair ``(chars, keep)`` of (m, k, width) arrays: the characters
of k numbers on each of m lines, and which of them to keep (numbers shorter
than ``width`` are padded with characters that ``keep`` drops). Lines are
assembled from fields as one byte matrix per block and the padding is dropped
with the mask, so no Python object is made per number.

Two number styles:

- fixed point (:func:`format_fixed`): the decimals that resolve ``10**-15``
  (float64) or ``10**-8`` (float32) of the largest magnitude of the array,
  trailing zeros dropped; float64 (or float32) precision relative to the size
  of the model, for any model size. Digit arithmetic over whole columns.
- printf (:func:`printf_field`): any ``%`` conversion, e.g. ``%r`` (Python's
  repr: the shortest text that reads back to the same double). One ``%``
  operation formats the whole array in C; slower than fixed point (repr's
  shortest-digit search), used where files must keep that spelling.
"""
from __future__ import annotations

import numpy as np

__all__ = ["decimals_for", "format_fixed", "printf_field", "constant_field", "join_columns", "text_lines",
           "FLOAT64_DIGITS", "FLOAT32_DIGITS"]

FLOAT64_DIGITS, FLOAT32_DIGITS = 15, 8  # relative digits of fixed-point text
_MINUS, _DOT, _NEWLINE = ord("-"), ord("."), ord("\n")
_TABLE = np.array([list(f"{i:04d}".encode()) for i in range(10000)], dtype=np.uint8)  # "0000" .. "9999"
_TABLE32 = _TABLE.view(np.uint32).ravel()  # the same, one 4-byte entry per number


def decimals_for(values: np.ndarray, relative_digits: int) -> int:
    """Decimals that resolve 10**-relative_digits of the largest finite magnitude of ``values``."""
    finite = np.abs(values[np.isfinite(values)])
    largest = float(finite.max()) if finite.size else 0.0
    if largest <= 0.0:
        return 1
    return int(max(0, relative_digits - np.ceil(np.log10(largest))))


def _packed_digits(scaled: np.ndarray, decimals: int):
    """All digits of ``scaled`` (m, k) int64, four per table entry: (m, k, 4 * groups) uint8 and groups."""
    largest = int(scaled.max()) if scaled.size else 0
    groups = max(1, -(-max(len(str(largest)), decimals + 1) // 4))
    packed = np.empty(scaled.shape + (groups,), dtype=np.uint32)  # most significant group first
    rest = scaled
    for g in range(groups):
        rest, chunk = np.divmod(rest, 10000)
        packed[..., groups - 1 - g] = _TABLE32[chunk]
    return packed.view(np.uint8), groups


def format_fixed(values: np.ndarray, decimals: int):
    """Characters of ``values`` (m, k) in fixed point: a (m, k, width) uint8 array and its keep mask.

    Four digits at a time from a table; leading zeros of the integer part and
    trailing zeros of the fraction are masked out (the units digit stays).
    Non-finite values are written as 0, and so is negative zero.
    """
    values = np.where(np.isfinite(values), values, 0.0)
    scaled = np.rint(np.abs(values) * 10.0 ** decimals)
    if scaled.size and scaled.max() >= 9e18:
        raise OverflowError("values too large for fixed-point text; use a binary format")
    scaled = scaled.astype(np.int64)
    digits, groups = _packed_digits(scaled, decimals)
    integer = 4 * groups - decimals  # integer digit columns (with leading zeros)
    width = 1 + integer + (1 + decimals if decimals else 0)
    chars = np.empty(values.shape + (width,), dtype=np.uint8)
    keep = np.empty(values.shape + (width,), dtype=bool)
    chars[..., 0] = _MINUS
    keep[..., 0] = (values < 0) & (scaled > 0)
    chars[..., 1 : 1 + integer] = digits[..., :integer]
    # digits of the integer part: 1 + number of powers of ten it reaches
    powers = 10 ** np.arange(1, integer, dtype=np.int64)
    whole = scaled // 10**decimals if decimals < 19 else np.zeros_like(scaled)  # scaled < 9e18 < 10**decimals
    count = 1 + np.searchsorted(powers, whole, side="right")
    keep[..., 1 : 1 + integer] = np.arange(integer) >= (integer - count)[..., None]
    if decimals:
        fraction = digits[..., integer:]
        chars[..., 1 + integer] = _DOT
        chars[..., 2 + integer :] = fraction
        # a fraction digit stays when it or a digit right of it is not zero
        significant = np.logical_or.accumulate(fraction[..., ::-1] != ord("0"), axis=-1)[..., ::-1]
        keep[..., 2 + integer :] = significant
        keep[..., 1 + integer] = significant[..., 0]
    return chars, keep


def printf_field(values: np.ndarray, conversion: str):
    """Field of ``values`` (m, k) each written with the ``%`` ``conversion`` ("%r", "%.6g", "%d").

    Python floats (``tolist``) keep ``%r`` the plain repr (numpy scalars would add their type name).
    """
    values = np.asarray(values)
    m, k = values.shape
    if m * k == 0:
        return np.zeros((m, k, 1), dtype=np.uint8), np.zeros((m, k, 1), dtype=bool)
    text = ((conversion + " ") * (m * k)) % tuple(values.ravel().tolist())
    chars = np.array(text.encode("ascii").split(), dtype=np.bytes_).reshape(m, k)
    chars = chars.view(np.uint8).reshape(m, k, -1)
    return chars, chars != 0


def constant_field(text: bytes, m: int, k: int):
    """Field of the same short text in every slot (e.g. the "//" of ``f a//a``)."""
    chars = np.broadcast_to(np.frombuffer(text, dtype=np.uint8), (m, k, len(text)))
    return chars, np.ones((m, k, len(text)), dtype=bool)


def join_columns(*fields):
    """One field of the columns of several (same m): (m, k1 + k2 + ..., max width), short ones padded."""
    if len(fields) == 1:
        return fields[0]
    width = max(chars.shape[2] for chars, _ in fields)
    padded = [(np.pad(c, ((0, 0), (0, 0), (0, width - c.shape[2]))), np.pad(k, ((0, 0), (0, 0), (0, width - k.shape[2]))))
              for c, k in fields]
    return np.concatenate([c for c, _ in padded], axis=1), np.concatenate([k for _, k in padded], axis=1)


def text_lines(prefix: bytes, fields, separator: bytes = b" ") -> bytes:
    """Lines ``prefix f_1 sep f_2 ... f_k\\n`` from fields of equal (m, k), as bytes.

    ``fields`` are written one after the other (without separator) in each of
    the k slots, e.g. ``a``, ``//``, ``a`` for the corners of ``f a//a b//b c//c``.
    """
    m, k = fields[0][0].shape[:2]
    widths = [c.shape[2] for c, _ in fields]
    slot = sum(widths) + len(separator)
    line = len(prefix) + k * slot - len(separator) + 1
    chars = np.empty((m, line), dtype=np.uint8)
    keep = np.ones((m, line), dtype=bool)
    chars[:, : len(prefix)] = np.frombuffer(prefix, dtype=np.uint8)
    for j in range(k):
        at = len(prefix) + j * slot
        for (c, kp), w in zip(fields, widths):
            chars[:, at : at + w] = c[:, j]
            keep[:, at : at + w] = kp[:, j]
            at += w
        if j < k - 1:
            chars[:, at : at + len(separator)] = np.frombuffer(separator, dtype=np.uint8)
    chars[:, -1] = _NEWLINE
    return chars[keep].tobytes()
