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

import numpy as np

from ...parallel import blas_on_one_thread, thread_count
from .. import tessellate
from ..tessellate import (_Bases, _corner_block, _grid_block, _interior_block, _owned_block, _side_block, _Welding,
                          grid_triangles)

__all__ = ["StreamedTessellation", "UndefinedNormals"]


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

    def vertex_blocks(self):
        """Yield (points (c, dim), normals (c, 3)) float for vertex ids 0, 1, ... in order.

        Raises UndefinedNormals at a block with a sample without a normal.
        """
        w, dim, samples = self.welding, self.dim, tessellate._BLOCK_SAMPLES  # the in-memory blocks, whatever they are
        for a in range(0, w.n_corners, samples):
            z = min(a + samples, w.n_corners)
            yield self._checked(*self._owned(w.corner_owner[a:z], 1, self._corner))
        inner = w.inner
        step = max(1, samples // max(inner, 1))
        for a in range(0, w.n_edges, step):
            z = min(a + step, w.n_edges)
            points, normals = self._owned(w.edge_owner[a:z], inner, self._side)
            yield self._checked(points.reshape(-1, dim), normals)
        m = inner * inner
        if not m:
            return
        for k in range(2):
            for a in range(self.starts[k], self.starts[k + 1], w.patch_block):
                z = min(a + w.patch_block, self.starts[k + 1])
                step = max(1, samples // m)
                for lo in range(a, z, step):
                    hi = min(lo + step, z)
                    flat = self.source.coefficients(k, np.arange(lo, hi) - self.starts[k])[0].reshape(hi - lo, -1)
                    points, normals = np.empty((hi - lo, m * dim)), np.empty(((hi - lo) * m, 3))
                    with blas_on_one_thread(self._hold):
                        _interior_block(flat, self.bases[k], points, normals)
                    yield self._checked(points.reshape(-1, dim), normals)

    def triangle_blocks(self):
        """Yield (t, 3) int triangles (``dtype``), patch by patch in order, as ``tessellate_patches`` numbers them."""
        w = self.welding
        for a in range(0, w.n_patches, w.patch_block):
            z = min(a + w.patch_block, w.n_patches)
            grid = np.empty((z - a, self.n, self.n), dtype=self.dtype)
            _grid_block(w, a, z, grid, alone=True)
            yield np.take(grid.reshape(z - a, -1), self.local, axis=1).reshape(-1, 3)

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
                unique = np.unique(mine)
                fetched[k] = (unique, self.source.coefficients(k, unique)[0].reshape(-1, self.dim))

        def evaluate(k, local, slot, points, normals):
            unique, control = fetched[k]
            kernel(k, control, np.searchsorted(unique, local), local, slot, points, normals)

        points, normals = np.empty((owner.size, width * self.dim)), np.empty((owner.size * width, 3))
        with blas_on_one_thread(self._hold):
            _owned_block(evaluate, self._groups, self.starts, owner, width, points, normals)
        return points, normals

    def _corner(self, k, control, rows, local, slot, points, normals) -> None:
        _corner_block(control, self.bases[k], rows, slot, points, normals)

    def _side(self, k, control, rows, local, slot, points, normals) -> None:
        flip = np.take(self.welding.reversed.reshape(-1), (local + self.starts[k]) * 4 + slot)
        _side_block(control, self.bases[k], rows, slot, flip.view(np.uint8), points, normals)

    @staticmethod
    def _checked(points: np.ndarray, normals: np.ndarray):
        if not np.isfinite(normals).all():
            raise UndefinedNormals("a tessellation sample has no normal")
        return points, normals
