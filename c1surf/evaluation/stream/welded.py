"""The welded tessellation by blocks: what ``tessellate_patches`` gives, never held whole.

Vertices are numbered from the adjacency ids alone (``tessellate.welded_grid_from_ids``):
corners, then the inner samples of every edge, then every patch's interior.
So the counts are known before any geometry, a block of vertices is evaluated
from the patches that own it, and a block of triangles is integers only.

Every vertex block here is one block of ``tessellate._evaluate_welded`` (the
same ids, the same products, BLAS on as many threads as there), evaluated from
coefficients that ``construction.patch_blocks.PatchSource`` gives bit for bit,
so the numbers are the in-memory tessellation's exactly. One thing the
in-memory path does needs the whole mesh: a sample without a normal (a
degenerate patch point, e.g. at a zero blend ratio) takes its neighbours'
(``tessellate.defined_normals``). The blocks raise ``UndefinedNormals`` there
and the caller tessellates in memory.
"""
from __future__ import annotations

from functools import partial

import numpy as np

from ...arrays import unique_integers
from ...parallel import blas_on_one_thread, run_tasks, thread_count
from .. import tessellate
from ..tessellate import (_Bases, _corner_block, _work, _grid_block, _interior_block, _owned_block, _side_block, _Welding,
                          grid_triangles)

__all__ = ["StreamedTessellation", "UndefinedNormals"]

# The most bytes of corner points and normals made at once (``StreamedTessellation._corner_passes``).
CORNER_TABLE_BYTES = 3 << 29


_BLOCKS_PER_TASK = 32  # vertex blocks a thread of ``in_order_on_threads`` computes in a row (8: rounds too short)


def in_order_on_threads(jobs, compute, per_task: int = _BLOCKS_PER_TASK):
    """Yield ``compute(job)`` for every job of ``jobs``, in order, computed on the thread pool a round at a time
    (``per_task`` consecutive jobs per thread and round): the vertex blocks of a streamed tessellation, which
    otherwise ran on one core with BLAS held to one thread (held for the in-memory blocks' bits: a block's
    product then gives the same bits on any thread). One thread (``C1SURF_THREADS=1``): one job at a time.
    A round holds its results (threads x ``per_task`` blocks of ``tessellate._BLOCK_SAMPLES`` samples: 96 MB).
    Measured on the 100,000-triangle torus at -r 8 (58.8 M vertices): 4.1 s -> 3.0-3.2 s; much of a block is
    still GIL-bound (coefficient gathers), so two threads do not halve it."""
    jobs, threads = list(jobs), thread_count()
    if threads <= 1:
        yield from map(compute, jobs)
        return
    size = threads * per_task
    for a in range(0, len(jobs), size):
        chunk = jobs[a : a + size]
        tasks = [partial(_each, compute, chunk[i : i + per_task]) for i in range(0, len(chunk), per_task)]
        for results in run_tasks(tasks, uses_blas=True):
            yield from results


def _each(compute, jobs) -> list:
    return [compute(job) for job in jobs]


def _rows_as_records(rows: np.ndarray) -> np.ndarray:
    """(n,) void view of a C-contiguous (n, c) array: a row is one item, so ``np.put`` moves whole rows (fancy
    assignment of rows goes element by element: 0.46 s against 0.07 s for 2.9 M random rows of 6 doubles)."""
    return rows.view(np.dtype((np.void, rows.shape[1] * rows.itemsize))).reshape(-1)


class UndefinedNormals(Exception):
    """A sample has no normal (zero derivative): only the whole tessellation can give it one."""


class StreamedTessellation:
    """The welded tessellation of a patch source, by blocks of vertices and of triangles.

    Parameters
    ----------
    source : ``construction.patch_blocks.PatchSource`` of a polynomial surface (``counts``, ``dim``,
        ``coefficients(kind, patches)``)
    adjacency : ``adjacency.PatchAdjacency`` of its patches (biquadratic first), with dense ids
    resolution : int >= 2, samples per patch side

    Attributes
    ----------
    n_vertices, n_triangles : int, as ``tessellate_patches`` would give
    dtype : int32 below 2^31 vertices, else int64 (the triangles' type)
    """

    def __init__(self, source, adjacency, resolution: int):
        if resolution < 2:
            raise ValueError("resolution must be at least 2")
        if getattr(source, "rational", False):
            raise ValueError("a rational surface is tessellated in memory")
        self.source, self.n = source, int(resolution)
        self.welding = w = _Welding.of(adjacency, self.n)
        if not w.dense or w.n_patches != sum(source.counts):
            raise ValueError("streamed tessellation needs dense adjacency ids of every patch")
        self.starts = np.cumsum([0, *source.counts])
        self.dim = source.dim
        self._bases = None  # (n-2)^2-sized matrices: made by the first vertex block, after the caller's size checks
        self._spans = None  # the product spans and the corners each covers (``_span_corners``), made on first use
        self.local = grid_triangles(self.n).ravel()
        self.n_vertices, self.dtype = w.n_vertices, w.dtype
        self.n_triangles = w.n_patches * 2 * (self.n - 1) ** 2
        self._groups = [np.empty((count, 0)) for count in source.counts]  # only their lengths are read
        self._hold = thread_count() > 1  # as run_tasks holds BLAS for the in-memory blocks

    @property
    def bases(self) -> list:
        """The sample matrices of the two degrees (``tessellate._Bases``), made on first use."""
        if self._bases is None:
            self._bases = [_Bases.of(d, self.n, self.dim) for d in (2, 3)]
        return self._bases

    def vertex_blocks(self, check: bool = True):
        """Yield (points (c, dim), normals (c, 3)) float for vertex ids 0, 1, ... in order.

        Raises UndefinedNormals at a block with a sample without a normal (``check``; without it
        such normals come as NaN: for a writer that reads the points only).
        """
        yield from self._shared_blocks(check)
        for _, _, points, normals in self._interior_blocks(check):
            yield points, normals

    def _shared_blocks(self, check: bool):
        """The vertex blocks of the corners, then of the edge samples (ids below ``welding.patch_base``)."""
        w, dim, samples = self.welding, self.dim, tessellate._BLOCK_SAMPLES  # the in-memory blocks, whatever they are
        checked = self._checked if check else (lambda points, normals: (points, normals))
        passes = self._corner_passes()
        for lo, hi in passes:
            corners, block = self._corner_table(lo, hi), None
            if check:
                self._checked(corners[:, :0], corners[:, dim:])
            for a in range(0, hi - lo, samples):
                z = min(a + samples, hi - lo)
                # the views of a pass's last block would keep its table alive (the caller holds the block it
                # writes) while the next pass makes its own: a copy then
                block = corners[a:z].copy() if z == hi - lo and hi < passes[-1][1] else corners[a:z]
                yield block[:, :dim], block[:, dim:]
            del corners, block
        inner = w.inner
        step = max(1, samples // max(inner, 1))
        _ = self.bases  # made here, not by two threads at once (``_side`` reads them)

        def edges(a):
            points, normals = self._owned(w.edge_owner[a : min(a + step, w.n_edges)], inner, self._side)
            return checked(points.reshape(-1, dim), normals)

        yield from in_order_on_threads(range(0, w.n_edges, step), edges)

    def _interior_blocks(self, check: bool):
        """Yield (lo, hi, points (c, dim), normals (c, 3)): the interior samples of patches lo..hi-1 (global
        ids), in the blocks of ``tessellate._evaluate_welded``; nothing when the patches have no interior."""
        w, dim = self.welding, self.dim
        m = w.inner * w.inner
        if not m:
            return
        step = max(1, tessellate._BLOCK_SAMPLES // m)
        bases = self.bases  # made here, not by two threads at once
        blocks = [(k, lo, min(lo + step, min(a + w.patch_block, self.starts[k + 1]))) for k in range(2)
                  for a in range(self.starts[k], self.starts[k + 1], w.patch_block)
                  for lo in range(a, min(a + w.patch_block, self.starts[k + 1]), step)]

        def interior(block):
            k, lo, hi = block
            flat = self.source.coefficients(k, np.arange(lo, hi) - self.starts[k])[0].reshape(hi - lo, -1)
            points, normals = np.empty((hi - lo, m * dim)), np.empty(((hi - lo) * m, 3))
            with blas_on_one_thread(self._hold):
                _interior_block(flat, bases[k], points, normals)
            points = points.reshape(-1, dim)
            return (lo, hi, *(self._checked(points, normals) if check else (points, normals)))

        yield from in_order_on_threads(blocks, interior)

    def _corner_passes(self) -> list:
        """[(lo, hi)]: the ranges of corner ids whose tables are made one after another, each within
        ``CORNER_TABLE_BYTES`` (one range but for the largest meshes: the 4,000,000-quad torus's table is
        3.1 GB at -r 2, beside the patch source's 4.4 GB; each more range makes the product blocks again)."""
        n, row = self.welding.n_corners, (self.dim + 3) * 8
        count = max(1, -(-n * row // CORNER_TABLE_BYTES))
        bounds = [n * i // count for i in range(count + 1)]
        return list(zip(bounds[:-1], bounds[1:]))

    def _corner_table(self, lo: int = 0, hi: int | None = None) -> np.ndarray:
        """(hi - lo, dim + 3) float: the point and the normal of corners lo..hi-1 (default: all), each from its
        owner as ``_owned`` evaluates it, made by the patches stage's product blocks in order (each block's
        coefficients made once per call, blocks on the thread pool). A corner is a control point and elementwise
        arithmetic on two more, so its bits do not depend on the corners evaluated beside it."""
        hi = self.welding.n_corners if hi is None else hi
        table = np.empty((hi - lo, self.dim + 3))
        bases = self.bases  # made here, not by two threads at once
        owns = np.zeros(self.welding.corners.size, dtype=bool)  # flat corner (patch * 4 + slot) evaluating its id
        owns[self.welding.corner_owner[lo:hi]] = True
        before = np.r_[0, np.cumsum(owns)]  # owners among the flat corners before each: a span's count in O(1)
        tasks = []
        for k, (spans, flat) in enumerate(self._span_corners()):
            for j in np.flatnonzero(before[flat[:, 1]] > before[flat[:, 0]]):  # the spans owning a corner of this pass
                tasks.append(partial(self._corner_span, k, spans[j], bases[k], owns, table, lo))
        if all(self.source.blas_held(k) for k in range(2)):
            run_tasks(tasks, uses_blas=True)
        else:  # a block computed with BLAS on its own threads: one after another, as the in-memory blocks ran
            for task in tasks:
                task()
        return table

    def _span_corners(self) -> list:
        """[(spans, flat (s, 2) int)] per kind: the product spans (``product_spans``) and the flat corners
        (patch * 4 + slot, global patch ids) each covers, [first, end); made once."""
        if self._spans is None:
            self._spans = []
            for k in range(2):
                spans = self.source.product_spans(k)
                bounds = np.array([span[2:] for span in spans], dtype=np.int64).reshape(-1, 2)
                self._spans.append((spans, 4 * (int(self.starts[k]) + bounds)))
        return self._spans

    def _corner_span(self, k: int, span, bases, owns: np.ndarray, table: np.ndarray, lo: int) -> None:
        """The rows of ``table`` (corner ids from ``lo``) of the corners whose owners are the patches of one
        product block (``product_spans``) and that ``owns`` marks."""
        g, b, p0, p1 = span
        a, z = int(self.starts[k]) + p0, int(self.starts[k]) + p1  # global patch ids
        owned = np.flatnonzero(owns[4 * a : 4 * z])
        if owned.size == 0:
            return
        rows = _work("corner table rows", (owned.size, self.dim + 3))
        _corner_block(partial(self.source.span_rows, k, g, b), bases, owned >> 2, owned & 3, rows[:, : self.dim],
                      rows[:, self.dim :])
        ids = np.take(self.welding.corners.reshape(-1), owned + 4 * a) - lo
        np.put(_rows_as_records(table), ids, _rows_as_records(rows))  # 6.5x faster than table[ids] = rows

    def triangle_point_blocks(self):
        """Yield (t, 3, 3) float: the positions (x, y, z) of the corners of triangles, in triangle order,
        bit for bit ``points[triangles, :3]`` of ``tessellate_patches`` (for STL, which stores no indices).

        Holds the positions of the vertices on patch corners and sides ((``welding.patch_base``, 3)
        float: at resolution 2 every vertex), evaluated first in their own blocks; the interiors come
        block by block with their patches. Normals are not checked (only points are given).
        """
        w = self.welding
        shared = np.empty((w.patch_base, 3))
        at = 0
        for points, _ in self._shared_blocks(check=False):
            shared[at : at + points.shape[0]] = points[:, :3]
            at += points.shape[0]
        if w.inner > 0:
            for lo, hi, points, _ in self._interior_blocks(check=False):
                yield self._corner_points(lo, hi, shared, points)
            return
        for a in range(0, w.n_patches, w.patch_block):  # no interiors: corners only
            yield self._corner_points(a, min(a + w.patch_block, w.n_patches), shared, None)

    def _corner_points(self, lo: int, hi: int, shared: np.ndarray, interior) -> np.ndarray:
        """(t, 3, 3) positions of the triangles of patches lo..hi-1: ``shared`` rows, or rows of ``interior``
        ((hi - lo) (n-2)^2, dim), the interior samples of these patches."""
        ids = self._triangles_of(lo, hi).reshape(-1)
        out = np.empty((ids.size, 3))
        if interior is None:
            np.take(shared, ids, axis=0, out=out)
        else:
            first = self.welding.patch_base + lo * self.welding.inner ** 2
            inside = ids >= first
            out[~inside] = shared[ids[~inside]]
            out[inside] = interior[ids[inside] - first, :3]
        return out.reshape(-1, 3, 3)

    def _triangles_of(self, a: int, z: int) -> np.ndarray:
        """(t, 3) int: the triangles of patches a..z-1, numbered as ``tessellate_patches`` numbers them."""
        grid = np.empty((z - a, self.n, self.n), dtype=self.dtype)
        _grid_block(self.welding, a, z, grid, alone=True)
        return np.take(grid.reshape(z - a, -1), self.local, axis=1).reshape(-1, 3)

    def triangle_blocks(self):
        """Yield (t, 3) int triangles (``dtype``), patch by patch in order, as ``tessellate_patches`` numbers them."""
        w = self.welding
        for a in range(0, w.n_patches, w.patch_block):
            yield self._triangles_of(a, min(a + w.patch_block, w.n_patches))

    # -- corners and edges, from the patches that own them ------------------------------------------

    def _owned(self, owner: np.ndarray, width: int, kernel):
        """(points (c, width dim), normals (c width, 3)) of c corners or edges, each from its owner (patch * 4 + slot).

        The owners' coefficients are fetched first (with BLAS as their own blocks had it), then
        ``tessellate._owned_block`` evaluates the block exactly as the in-memory pass does.
        """
        patch = owner >> 2
        fetched = {}
        for k in range(2):
            mine = patch[(patch >= self.starts[k]) & (patch < self.starts[k + 1])] - self.starts[k]
            if mine.size:
                unique = unique_integers(mine)  # np.unique's hash table is ~20x slower on these keys
                fetched[k] = (unique, self.source.coefficients(k, unique)[0].reshape(-1, self.dim))

        def evaluate(k, local, slot, points, normals):
            unique, control = fetched[k]
            kernel(k, control, np.searchsorted(unique, local), local, slot, points, normals)

        points, normals = np.empty((owner.size, width * self.dim)), np.empty((owner.size * width, 3))
        with blas_on_one_thread(self._hold):
            _owned_block(evaluate, self._groups, self.starts, owner, width, points, normals)
        return points, normals

    def _side(self, k, control, rows, local, slot, points, normals) -> None:
        flip = np.take(self.welding.reversed.reshape(-1), (local + self.starts[k]) * 4 + slot)
        _side_block(control, self.bases[k], rows, slot, flip.view(np.uint8), points, normals)

    @staticmethod
    def _checked(points: np.ndarray, normals: np.ndarray):
        if not np.isfinite(normals).all():
            raise UndefinedNormals("a tessellation sample has no normal")
        return points, normals
