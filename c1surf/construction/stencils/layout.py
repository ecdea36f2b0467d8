"""Patch coefficients as gathers of refined points and one small dense product per group (A2, A3).

Every patch of a group reads m refined points (its *slots*) and has r
coefficients, each a fixed combination of those points: the group is one
(r, m) weight matrix and an (m, k) table of point indices. Applying it gathers
the points block by block and multiplies (``gathered_products``); the same map
as a sparse matrix (``gathered_matrix``) is built only when asked for.
"""
from __future__ import annotations

import numpy as np

from ...parallel import for_each_range, ranges_of


def gathered_products(points: np.ndarray, slots: np.ndarray, weights: np.ndarray, out: np.ndarray,
                      offset: np.ndarray | None = None) -> np.ndarray:
    """out[p] = weights @ points[slots[:, p]] for every patch p: a small stencil applied to gathered rows.

    Blocks of patches that stay in cache, on the thread pool: gather slot by slot
    (each into a contiguous row of the block), one (r x m) @ (m x block d) product,
    one gather by a fixed permutation into the output (``product_block``). mode="clip":
    no bounds check, no buffering (the indices are valid by construction). The blocks
    are ``product_blocks``: a block computed alone (``product_block``) gives the same bits.

    Parameters
    ----------
    points : (V, d) float
    slots : (m, k) int, slots[j, p] is the row of points that is input j of patch p
    weights : (r, m) float
    out : (k, r, d) float, filled and returned
    offset : (d,) float or None, added to every output row after its sum (points relative to an
        origin: rows of ``weights`` summing to 1, this puts the origin back), as the last term of
        the product or in a pass before the copy out (``block_product``); added as the first term
        instead, it would round the small terms at the offset's scale: 1.1e-10 rad on OpenSubdiv's
        bishop against 4.9e-11
    """
    points = np.ascontiguousarray(points)
    m, k = slots.shape
    step = _step(m)

    def fill(first: int, last: int) -> None:
        work = _ProductWork(m, weights.shape[0], min(step, last - first), points.shape[1])
        for start in range(first, last, step):
            stop = min(last, start + step)
            product_block(points, slots, weights, start, stop, out[start:stop], offset, work)

    for_each_range(k, fill, minimum=_minimum(m), uses_blas=True)
    return out


_BLOCK_POINTS = 1 << 17  # gathered points per product block (work arrays of ~3 MB: in L2; smaller blocks made the
# streamed corner table GIL-bound, no faster on two threads than on one: 0.75 s against ~0.45 s on the 180k torus)
_THREAD_POINTS = 1 << 19  # fewer gathered points than this per thread are not worth a thread


def _step(m: int) -> int:
    """Items per product block when each reads m points."""
    return max(1, _BLOCK_POINTS // m)


def _minimum(m: int) -> int:
    """Fewest items per thread (``parallel.for_each_range``)."""
    return max(1, _THREAD_POINTS // m)


def product_blocks(k: int, m: int) -> tuple[np.ndarray, bool]:
    """The blocks of ``gathered_products`` on k items of m points: (starts (b + 1,) int64, BLAS held).

    Block i covers items starts[i]:starts[i + 1]: every thread's range of
    ``parallel.for_each_range`` cut into ``_step(m)`` items from its start.
    BLAS held: the products run with BLAS on one thread (``parallel.run_tasks``
    on more than one thread), as ``product_block`` must then run too to give the
    same bits (a BLAS on several threads cuts the product differently).
    """
    threads = ranges_of(k, _minimum(m))
    step = _step(m)
    starts = [np.arange(threads[i], threads[i + 1], step) for i in range(len(threads) - 1)]
    return np.concatenate(starts + [np.array([k])]).astype(np.int64), len(threads) > 2


def product_block(points: np.ndarray, slots: np.ndarray, weights: np.ndarray, start: int, stop: int, out: np.ndarray,
                  offset: np.ndarray | None = None, work: "_ProductWork | None" = None) -> np.ndarray:
    """``out`` (stop - start, r, d) = the products of items start:stop, one block of ``gathered_products``.

    points : (V, d) float, C-contiguous; slots : (m, k) int, or a table made by blocks (``block(start, stop)``:
    ``biquadratic.GridSlots``); weights : (r, m) float; work : the block's work arrays (made here if None)
    """
    d, r = points.shape[1], weights.shape[0]
    inside = offset is not None and getattr(slots, "offset_in_product", False)
    product = block_product(points, slots, weights, start, stop, work, offset if inside else None)  # (r, items d)
    if offset is not None and not inside:  # one pass over rows items d long: the bits of adding it after the transpose
        product += _tiled(offset, stop - start)
    if out.flags.c_contiguous:
        # (r, items, d) -> (items, r, d) as one gather of single values by a fixed permutation (kept per
        # block size): 2.2x faster than the copy by coordinates below, whose writes are d apart
        np.take(product.reshape(-1), _transpose_order(r, stop - start, d), out=out.reshape(-1), mode="clip")
        return out
    block = product.reshape(r, -1, d)
    for c in range(d):  # (r, items, d) -> (items, r, d) one coordinate at a time
        out[:, :, c] = block[:, :, c].T
    return out


_ORDERS: dict = {}


def _transpose_order(r: int, items: int, d: int) -> np.ndarray:
    """(items r d,) intp: the flat index in an (r, items, d) array of every entry of the (items, r, d) one."""
    key = (r, items, d)
    order = _ORDERS.get(key)
    if order is None:
        if len(_ORDERS) > 64:
            _ORDERS.clear()
        p, i, c = np.ogrid[:items, :r, :d]
        order = _ORDERS[key] = (i * (items * d) + p * d + c).reshape(-1).astype(np.intp)
    return order


def _tiled(offset: np.ndarray, items: int) -> np.ndarray:
    """(items d,) float: ``offset`` (d,) repeated once per item (kept per offset and block size)."""
    key = ("offset", items, offset.tobytes())
    tiled = _ORDERS.get(key)
    if tiled is None:
        if len(_ORDERS) > 64:
            _ORDERS.clear()
        tiled = _ORDERS[key] = np.tile(offset, items)
    return tiled


_WITH_ONES: dict = {}


def _with_ones(weights: np.ndarray) -> np.ndarray:
    """(r, m + 1) float: ``weights`` and a column of ones (the offset's row of ``block_product``), kept per array."""
    held = _WITH_ONES.get(id(weights))
    if held is None or held[0] is not weights:
        held = _WITH_ONES[id(weights)] = (weights, np.concatenate([weights, np.ones((weights.shape[0], 1))], axis=1))
    return held[1]


def block_product(points: np.ndarray, slots: np.ndarray, weights: np.ndarray, start: int, stop: int,
                  work: "_ProductWork | None" = None, offset: np.ndarray | None = None) -> np.ndarray:
    """(r, (stop - start) d) float: the product of ``product_block`` before it is copied out, coefficient-major
    (row i, columns (item, coordinate)); in ``work.product`` (made here if None).

    offset : (d,) float or None, added to every entry as the product's last term: one more gathered row
    holding it (written once per work array) with weight 1. Only for slots whose product sums its terms in
    order (their ``offset_in_product``: the biquadratic grid's 9, checked bit for bit): then this gives the
    bits of adding it after the sum (as ``product_block`` does for the others and
    ``patch_blocks.PatchSource.rows_of`` for all), without a pass. (The bicubic holes' products of 4n + 1
    terms do not: BLAS splits their sums.)
    """
    m, d, n = slots.shape[0], points.shape[1], stop - start
    work = work or _ProductWork(m, weights.shape[0], n, d)
    g = work.gathered[:, :n]
    index = slots[:, start:stop] if isinstance(slots, np.ndarray) else slots.block(start, stop, work.index(m, slots.dtype))
    if index.dtype != np.intp:  # converted once into the block's work array: np.take converts on every call
        np.copyto(work.index(m, np.intp)[:, :n], index)
        index = work.index(m, np.intp)[:, :n]
    np.take(points, index, axis=0, out=g[:m], mode="clip")  # one call for all slots (a whole block: contiguous)
    if not isinstance(weights, np.ndarray):  # a rule applied without its matrix (``hole_rules.HoleOperator``)
        product = weights.product(g[:m].reshape(m, -1), out=work.product[:, : n * d])
        return product if offset is None else np.add(product, _tiled(offset, n), out=product)
    if offset is None:
        return np.matmul(weights, g[:m].reshape(m, -1), out=work.product[:, : n * d])
    work.offset_row(offset)
    return np.matmul(_with_ones(weights), g.reshape(m + 1, -1), out=work.product[:, : n * d])


class _ProductWork:
    """Work arrays of product blocks of up to ``items`` items: gathered (m + 1, items, d), product (r, items d),
    and the block's slots when they are made by blocks (``index``)."""

    def __init__(self, m: int, r: int, items: int, d: int):
        self.gathered = np.empty((m + 1, items, d))  # the last row: the offset's (``offset_row``)
        self.product = np.empty((r, items * d))
        self._index = {}
        self._offset = None

    def offset_row(self, offset: np.ndarray) -> None:
        """Fill the last gathered row with ``offset`` (d,) for every item (unless it holds it already)."""
        if self._offset is None or not np.array_equal(self._offset, offset):
            self.gathered[-1] = offset
            self._offset = np.array(offset, dtype=np.float64)

    def index(self, m: int, dtype) -> np.ndarray:
        """(m, items) int of ``dtype``: room for the slots of a block made by blocks, or converted (made on first use)."""
        key = np.dtype(dtype)
        if key not in self._index:
            self._index[key] = np.empty((m, self.gathered.shape[1]), dtype=dtype)
        return self._index[key]


def gathered_matrix(slots: np.ndarray, weights: np.ndarray, n_points: int):
    """The map of ``gathered_products`` as a (k r, n_points) csr_matrix: row ``r p + i`` is coefficient i of patch p.

    Written straight into CSR arrays (every patch has the same pattern of non-zero weights).

    Parameters
    ----------
    slots : (m, k) int
    weights : (r, m) float
    n_points : int
    """
    from scipy.sparse import csr_matrix  # scipy.sparse is imported where a matrix is made: the usual conversion needs none (0.2 s)

    slots = np.asarray(slots)  # a table made by blocks, whole
    weights = np.asarray(weights)  # a rule applied without its matrix: its dense block (``hole_rules.HoleOperator``)
    k = slots.shape[1]
    i, j = np.nonzero(weights)  # row by row, so each patch's entries are in row order
    index = np.int32 if max(n_points, k * i.size) < 2**31 else np.int64
    per_row = np.bincount(i, minlength=weights.shape[0])
    indptr = np.zeros(k * weights.shape[0] + 1, dtype=index)
    np.cumsum(np.tile(per_row, k), out=indptr[1:])
    columns = np.ascontiguousarray(slots[j].T, dtype=index).ravel()  # (k, nnz): patch by patch
    return csr_matrix((np.tile(weights[i, j], k), columns, indptr), shape=(k * weights.shape[0], n_points))


class PatchLayout:
    """Patch coefficient rows from refined points, by groups that share a weight matrix (a ``Stage``).

    Parameters
    ----------
    name : str
    groups : sequence of (slots, weights): slots (m, k) int, the refined points each
        of the group's k items reads (a patch for A2, a hole of n patches for A3);
        weights (r, m) float, the item's r coefficient rows on those points
    n_points : int, refined points
    coefficients : int, rows per patch (9 for A2, 16 for A3)
    keep : (P,) bool or None, the patches kept, P = all patches of all groups
        (open meshes: those at real corners); None keeps all
    """

    mixes_coordinates = False

    def __init__(self, name: str, groups, n_points: int, coefficients: int, keep=None):
        self.name = name
        self.groups = tuple(groups)
        self.n_points = int(n_points)
        self.coefficients = coefficients
        self.keep = None if keep is None or np.all(keep) else np.asarray(keep, dtype=bool)
        self.n_rows = sum(slots.shape[1] * weights.shape[0] for slots, weights in self.groups)  # before ``keep``
        kept = self.n_rows if self.keep is None else int(self.keep.sum()) * coefficients
        self.shape = (kept, self.n_points)
        self._matrix = None
        self._kept = None

    def apply(self, points: np.ndarray, out: np.ndarray | None = None, offset: np.ndarray | None = None) -> np.ndarray:
        """(rows, d) coefficients from refined ``points`` (n_points, d), written into ``out`` if given;
        ``offset`` (d,) is added to every row (``gathered_products``)."""
        d = points.shape[1]
        if out is None:
            out = np.empty((self.shape[0], d))
        every = out if self.keep is None else np.empty((self.n_rows, d))
        start = 0
        for slots, weights in self.groups:  # m points in, r coefficients out per item
            rows = slots.shape[1] * weights.shape[0]
            gathered_products(points, slots, weights, every[start : start + rows].reshape(-1, weights.shape[0], d), offset)
            start += rows
        if self.keep is not None:
            out[:] = every.reshape(self.keep.size, -1)[self.keep].reshape(out.shape)
        return out

    def reuse(self) -> None:
        """Applied again (``Surface.update_points``): slots made by blocks are made whole once and kept."""
        for slots, _ in self.groups:
            if not isinstance(slots, np.ndarray):
                slots.hold()

    @property
    def n_patches(self) -> int:
        """Patches kept (rows / coefficients)."""
        return self.shape[0] // self.coefficients

    def kept_rows(self) -> np.ndarray:
        """(kept,) int64: the index among all patches of every kept patch (``keep`` not None; made once)."""
        if self._kept is None:
            self._kept = np.flatnonzero(self.keep)
        return self._kept

    def matrix(self):
        """(rows, n_points) csr_matrix, built on the first call and kept."""
        if self._matrix is None:
            from scipy.sparse import csr_matrix, vstack

            parts = [gathered_matrix(slots, weights, self.n_points) for slots, weights in self.groups]
            matrix = vstack(parts, format="csr") if parts else csr_matrix((0, self.n_points))
            if self.keep is not None:
                rows = np.flatnonzero(self.keep)[:, None] * self.coefficients + np.arange(self.coefficients)
                matrix = matrix[rows.ravel()]
            self._matrix = matrix
        return self._matrix
