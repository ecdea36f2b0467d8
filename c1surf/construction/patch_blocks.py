"""Patch coefficients by blocks, for callers that never hold all of them (the streamed conversion).

The patches stage computes its coefficients in blocks of items
(``stencils.layout.product_blocks``), and a block computed alone gives the
same bits as inside the whole stage. ``PatchSource`` serves the coefficients of
any patches, in any order, from those blocks: it computes a block when one of
its patches is asked for and keeps the most recent blocks up to a byte budget.
So ``Surface.patch_blocks`` and the streamed tessellation read exactly the
numbers of ``Surface.biquadratic`` / ``Surface.bicubic`` without making them.
"""
from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from ..parallel import blas_on_one_thread
from .stencils.layout import PatchLayout, _ProductWork, block_product, product_block, product_blocks

KINDS = ("biquadratic", "bicubic")
DEFAULT_CACHE_BYTES = 64 << 20


@dataclass(frozen=True)
class PatchBlock:
    """Coefficients of some patches of one kind.

    kind : 0 (biquadratic) or 1 (bicubic)
    ids : (c,) int64, global patch ids (biquadratic first, then bicubic: the order of ``Surface.frames``)
    coefficients : (c, k, k, d) float, k = 3 or 4, as in ``Surface.biquadratic`` / ``Surface.bicubic``
    weights : (c, k, k) float or None (polynomial surface)
    """

    kind: int
    ids: np.ndarray
    coefficients: np.ndarray
    weights: np.ndarray | None


class _Group:
    """One group of a layout: its items' slots and weights, where its patches start, its product blocks."""

    def __init__(self, slots, weights, first: int, coefficients: int):
        self.slots, self.weights, self.first = slots, weights, first
        self.per_item = weights.shape[0] // coefficients
        self.stop = first + slots.shape[1] * self.per_item
        self.starts, self.held = product_blocks(slots.shape[1], slots.shape[0])


class PatchSource:
    """The patch coefficients of a surface, computed by blocks on demand.

    Parameters
    ----------
    layouts : (biquadratic, bicubic) ``stencils.layout.PatchLayout``, the parts of the patches stage
    refined : (Vr, d) float, the refined points the stage reads (centred, homogeneous when rational)
    origin : (d,) float, the centre taken off the input points (put back on every coefficient)
    rational : bool, ``refined`` carries the homogeneous weight as its last column
    cache_bytes : int or None, the most bytes of coefficient blocks kept at once (None: ``DEFAULT_CACHE_BYTES``)
    """

    def __init__(self, layouts, refined: np.ndarray, origin: np.ndarray, rational: bool,
                 cache_bytes: int | None = None):
        self.layouts = tuple(layouts)
        self.refined = np.ascontiguousarray(refined)
        self.origin, self.rational = origin, rational
        self.cache_bytes = DEFAULT_CACHE_BYTES if cache_bytes is None else cache_bytes
        self._cache: OrderedDict = OrderedDict()
        self._cached = 0
        self._lock = threading.Lock()  # the cache, for blocks asked for by several threads (a streamed tessellation)
        self._making: dict = {}  # the blocks being made, each by one thread: (kind, g, b) -> Event set when done
        self._groups = []
        for layout in self.layouts:
            groups, first = [], 0
            for slots, weights in layout.groups:
                groups.append(_Group(slots, weights, first, layout.coefficients))
                first = groups[-1].stop
            self._groups.append(groups)

    @property
    def dim(self) -> int:
        """Columns of the coefficients (those of the input points)."""
        return self.refined.shape[1] - (1 if self.rational else 0)

    @property
    def counts(self) -> tuple:
        """(Nq, Nc): the patches of each kind."""
        return tuple(layout.n_patches for layout in self.layouts)

    def coefficients(self, kind: int, patches) -> tuple:
        """(coefficients (c, k, k, d), weights (c, k, k) or None) of patches ``patches`` (c,) int of one kind.

        ``patches`` are indices within the kind (0..Nq-1 or 0..Nc-1), any order, repeats allowed.
        """
        layout = self.layouts[kind]
        patches = np.asarray(patches, dtype=np.int64).reshape(-1)
        raw = patches if layout.keep is None else layout.kept_rows()[patches]
        rows = np.empty((raw.size, layout.coefficients, self.refined.shape[1]))
        for g, group in enumerate(self._groups[kind]):
            mine = np.flatnonzero((raw >= group.first) & (raw < group.stop))
            if mine.size == 0:
                continue
            item, corner = np.divmod(raw[mine] - group.first, group.per_item)
            block = np.searchsorted(group.starts, item, side="right") - 1
            for b in np.unique(block):
                chosen = np.flatnonzero(block == b)
                local = (item[chosen] - group.starts[b]) * group.per_item + corner[chosen]
                rows[mine[chosen]] = self._block(kind, g, int(b))[local]
        side = 3 if kind == 0 else 4
        rows = rows.reshape(raw.size, side, side, self.refined.shape[1])
        if not self.rational:
            return rows, None
        points = rows[..., :-1] / rows[..., -1:]  # as Surface._apply: divided, then the centre added back
        points += self.origin
        return points, rows[..., -1]

    def arrays(self) -> tuple:
        """(biquadratic (Nq, 3, 3, d), bicubic (Nc, 4, 4, d)) float, all patches at once: bit for bit
        ``Surface.biquadratic`` / ``bicubic``, by the same calls (``stages.StackedStage.apply``: every layout's
        ``apply`` into its rows, the centre added in the same pass). Polynomial surfaces only.

        For a caller that kept only this source and finds it needs the whole surface after all (the
        streamed conversion's fallback); ``Surface`` makes its own arrays.
        """
        if self.rational:
            raise ValueError("a rational surface's whole patches come from the Surface")
        d = self.refined.shape[1]
        out = np.empty((sum(layout.shape[0] for layout in self.layouts), d))
        start = 0
        for layout in self.layouts:
            layout.apply(self.refined, out=out[start : start + layout.shape[0]], offset=self.origin)
            start += layout.shape[0]
        n_quad = self.counts[0]
        return out[: 9 * n_quad].reshape(n_quad, 3, 3, d), out[9 * n_quad :].reshape(-1, 4, 4, d)

    def blocks(self, size: int):
        """Yield ``PatchBlock``s of up to ``size`` patches: every biquadratic patch in order, then every bicubic."""
        offset = 0
        for kind, count in enumerate(self.counts):
            for a in range(0, count, size):
                ids = np.arange(a, min(a + size, count))
                coefficients, weights = self.coefficients(kind, ids)
                yield PatchBlock(kind, ids + offset, coefficients, weights)
            offset += count

    def product_spans(self, kind: int) -> list:
        """[(g, b, p0, p1)]: every product block b of group g of kind ``kind``, in order, with the patches it makes:
        p0..p1-1 (indices within the kind, as ``coefficients`` takes them; a block of no kept patch is left out)."""
        layout, spans = self.layouts[kind], []
        for g, group in enumerate(self._groups[kind]):
            bounds = group.first + group.starts * group.per_item  # raw patches (all patches of all groups)
            if layout.keep is not None:
                bounds = np.searchsorted(layout.kept_rows(), bounds)
            spans += [(g, b, int(bounds[b]), int(bounds[b + 1])) for b in range(bounds.size - 1) if bounds[b + 1] > bounds[b]]
        return spans

    def span_rows(self, kind: int, g: int, b: int, rows: np.ndarray) -> np.ndarray:
        """(rows.shape + (d,)) float: coefficient rows of the patches of product block b of group g (``product_spans``),
        bit for bit those ``coefficients`` gives: ``rows`` int, patch * k * k + coefficient (i k + j), the patches
        numbered from the span's first (p0). Polynomial surfaces only.

        The block's product is made now (with BLAS as the block has it; not kept), in work arrays of the calling
        thread (blocks on a thread pool allocate little), and only the rows asked for are copied out of it, the
        centre added to them as ``product_block`` adds it to all.
        """
        if self.rational:
            raise ValueError("internal: the rows of a rational surface are homogeneous")
        layout, group = self.layouts[kind], self._groups[kind][g]
        start, stop = int(group.starts[b]), int(group.starts[b + 1])
        work = _thread_work(group.slots.shape[0], group.weights.shape[0], int(np.diff(group.starts).max()),
                            self.refined.shape[1])
        # the centre enters as ``product_block`` adds it: as the product's last term where the whole surface's
        # products take it so (``offset_in_product``), after the sum elsewhere, whichever way BLAS sums
        inside = bool(getattr(group.slots, "offset_in_product", False))
        with blas_on_one_thread(group.held):
            product = block_product(self.refined, group.slots, group.weights, start, stop, work,
                                    self.origin if inside else None)
        patch, coefficient = np.divmod(rows, layout.coefficients)
        if layout.keep is not None:  # kept patches -> all patches of the block (from its first)
            p0 = np.searchsorted(layout.kept_rows(), group.first + start * group.per_item)
            patch = np.take(layout.kept_rows(), patch + p0) - (group.first + start * group.per_item)
        # the product is (r, items, d): row (patch within its item) * k * k + coefficient, column item
        if group.per_item == 1:  # a patch per item (A2): no second division
            index = coefficient * (stop - start) + patch
        else:
            item, within = np.divmod(patch, group.per_item)
            index = (within * layout.coefficients + coefficient) * (stop - start) + item
        out = np.take(product.reshape(-1, self.refined.shape[1]), index, axis=0)
        if not inside:
            out += self.origin
        return out

    def keep_slot_arrays(self) -> None:
        """Let go of the topology the layouts' slots were made by blocks from, all but the arrays they read
        (``biquadratic.GridSlots.keep_slot_arrays``), for a caller that holds only this source."""
        for layout in self.layouts:
            for slots, _ in layout.groups:
                if hasattr(slots, "keep_slot_arrays"):
                    slots.keep_slot_arrays()

    def blas_held(self, kind: int) -> bool:
        """Whether every product block of ``kind`` runs with BLAS on one thread (``product_blocks``' held), so that
        blocks may be computed on the thread pool (``parallel.run_tasks``) and give the same bits."""
        return all(group.held for group in self._groups[kind])

    def _block(self, kind: int, g: int, b: int) -> np.ndarray:
        """(items * per item, coefficients, d) float: the rows of product block b of group g, computed or kept."""
        key = (kind, g, b)
        while True:
            with self._lock:
                if key in self._cache:
                    self._cache.move_to_end(key)
                    return self._cache[key]
                making = self._making.get(key)
                if making is None:  # this thread makes it; one asking for it meanwhile waits for it
                    making = self._making[key] = threading.Event()
                    break
            making.wait()  # then from the cache (or made again, if it has already left it)
        try:
            rows = self._made_block(kind, g, b)
            with self._lock:
                self._cache[key] = rows
                self._cached += rows.nbytes
                while self._cached > self.cache_bytes and len(self._cache) > 1:
                    self._cached -= self._cache.popitem(last=False)[1].nbytes
        finally:
            with self._lock:
                del self._making[key]
            making.set()
        return rows

    def _made_block(self, kind: int, g: int, b: int) -> np.ndarray:
        group = self._groups[kind][g]
        start, stop = int(group.starts[b]), int(group.starts[b + 1])
        d = self.refined.shape[1]
        out = np.empty((stop - start, group.weights.shape[0], d))
        with blas_on_one_thread(group.held):
            product_block(self.refined, group.slots, group.weights, start, stop, out,
                          None if self.rational else self.origin)
        return out.reshape(-1, self.layouts[kind].coefficients, d)


_local = threading.local()


def _thread_work(m: int, r: int, items: int, d: int) -> _ProductWork:
    """The calling thread's work arrays for product blocks of up to ``items`` items, made on first use and kept."""
    arrays = _local.__dict__.setdefault("products", {})
    key = (m, r, d)
    if key not in arrays or arrays[key].gathered.shape[1] < items:
        arrays[key] = _ProductWork(m, r, items, d)
    return arrays[key]


def patch_source(stage, refined: np.ndarray, origin: np.ndarray, rational: bool, **options) -> PatchSource:
    """The ``PatchSource`` of a patches stage (``stages.StackedStage`` of two ``PatchLayout``s)."""
    layouts = stage.parts
    if len(layouts) != 2 or not all(isinstance(layout, PatchLayout) for layout in layouts):
        raise ValueError("internal: the patches stage is not (biquadratic, bicubic) layouts")
    return PatchSource(layouts, refined, origin, rational, **options)
