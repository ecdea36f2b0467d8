"""Array helpers where numpy's own call is slow, for every layer (imports nothing of c1surf).

numpy >= 2.3 finds the values of a plain ``np.unique(a)`` (no index, inverse or
counts asked for) with a hash table, which on this project's arrays is far
slower than sorting: measured 0.55 s for 720,000 int64 edge keys against 4 ms
for ``np.sort``, and 73 ms for the face sizes of 2,880,000 faces against 8 ms
for a ``np.bincount``. ``unique_integers`` gives the same array by counting or
sorting.
"""
from __future__ import annotations

import numpy as np

__all__ = ["column_bounds", "unique_integers"]


def unique_integers(values) -> np.ndarray:
    """``np.unique(values)`` for an integer array: its distinct values, sorted, flattened, same dtype.

    Counts when the values are non-negative and their range is at most a few
    times their number (face sizes, vertex ids), else sorts.

    Parameters
    ----------
    values : (...) int array

    Returns
    -------
    (k,) array of the dtype of ``values``
    """
    values = np.asarray(values).ravel()
    if values.dtype.kind not in "iu":
        raise TypeError(f"unique_integers takes integers, not {values.dtype}")
    if values.size == 0:
        return values.copy()
    low, high = int(values.min()), int(values.max())
    if low >= 0 and high < 4 * values.size + 1024 and values.dtype != np.uint64:  # bincount takes what casts to intp
        return np.flatnonzero(np.bincount(values, minlength=high + 1)).astype(values.dtype, copy=False)
    ordered = np.sort(values)
    keep = np.empty(ordered.size, dtype=bool)
    keep[0] = True
    np.not_equal(ordered[1:], ordered[:-1], out=keep[1:])
    return ordered[keep]


def column_bounds(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(low (c,), high (c,)): ``values.min(axis=0)`` and ``values.max(axis=0)`` of a non-empty (n, c) array.

    Column by column: numpy reduces axis 0 of a C-contiguous (n, 3) array with inner loops of 3 (9 ms for
    180,000 points against 1 ms this way). The same values (NaN propagates as there).
    """
    low = np.array([values[:, k].min() for k in range(values.shape[1])], dtype=values.dtype)
    high = np.array([values[:, k].max() for k in range(values.shape[1])], dtype=values.dtype)
    return low, high
