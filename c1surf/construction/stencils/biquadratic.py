"""Step A2: a biquadratic patch at every regular refined vertex, as a gather of its 3 x 3 points.

The patch at refined vertex c with frame e0..e3 (``refine.holes``) reads the grid

    G = [[diag(e2), dest(e2), diag(e1)],
         [dest(e3), c,        dest(e1)],
         [diag(e3), dest(e0), diag(e0)]]

(diag(e): the vertex of face(e) opposite c) and has coefficients Q = M G M^T
(``BIQUADRATIC_FROM_GRID``): Q00 is the centroid of face(e2), Q01 the
midpoint of c and dest(e2), Q11 = c, and so on: the uniform biquadratic
B-spline of the grid. Nine indices per patch replace a 25-entries-per-patch
matrix, and nothing but the output is allocated at full size.
"""
from __future__ import annotations

import numpy as np

from ...mesh.halfedges import HalfEdgeMesh
from ...parallel import for_each_range
from .layout import PatchLayout

# A2 on the 3 x 3 refined points G around a regular vertex: Q = M G M^T, that is
# corners are quad centroids, edge coefficients midpoints and the centre the vertex.
_AVERAGE = np.array([[0.5, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.5, 0.5]])
BIQUADRATIC_FROM_GRID = np.kron(_AVERAGE, _AVERAGE)  # (9, 9): Q.ravel() = this @ G.ravel()


def biquadratic_grid(mesh: HalfEdgeMesh, frames: np.ndarray) -> np.ndarray:
    """(9, Nq) int: refined vertex of G.ravel()[k] of every patch with ``frames`` (Nq, 4).

    Slot-major, so each slot gathers into a contiguous block.
    """
    grid = np.empty((9, frames.shape[0]), dtype=_index_type(mesh))
    for_each_range(frames.shape[0], lambda a, b: [_fill_grid(mesh, frames[s : min(b, s + (1 << 16))], grid[:, s : b])
                                                  for s in range(a, b, 1 << 16)])
    return grid


def _index_type(mesh: HalfEdgeMesh):
    return np.int32 if mesh.n_vertices < 2**31 else np.int64


def _fill_grid(mesh: HalfEdgeMesh, f: np.ndarray, g: np.ndarray) -> None:
    """Write the grids of the patches with frames ``f`` (k, 4) into the first k columns of ``g`` (9, >= k)."""
    origin, nxt = mesh.origin, mesh.next
    after = np.take(nxt, f, mode="clip")  # random-access gathers, by blocks that stay in cache
    dest = np.take(origin, after, mode="clip")  # (k, 4)
    diagonal = np.take(origin, np.take(nxt, after, mode="clip"), mode="clip")
    g[0, : f.shape[0]], g[1, : f.shape[0]], g[2, : f.shape[0]] = diagonal[:, 2], dest[:, 2], diagonal[:, 1]
    g[3, : f.shape[0]], g[5, : f.shape[0]] = dest[:, 3], dest[:, 1]
    np.take(origin, f[:, 0], mode="clip", out=g[4, : f.shape[0]])
    g[6, : f.shape[0]], g[7, : f.shape[0]], g[8, : f.shape[0]] = diagonal[:, 3], dest[:, 0], diagonal[:, 0]


class GridSlots:
    """The slots (9, Nq) of ``biquadratic_grid``, made block by block when a product reads them.

    The whole table is the largest array of a surface's topology (104 MB for the
    180,000-quad torus's 2,880,000 patches) and is read once by a conversion:
    ``stencils.layout.product_block`` asks for the columns of its block
    (``block``), made from the frames there. ``hold`` makes the whole table and
    keeps it, for a surface applied again (``Surface.update_points``);
    ``np.asarray`` gives the whole table too (``layout.gathered_matrix``).

    Parameters
    ----------
    mesh : HalfEdgeMesh, the refined mesh
    frames : (Nq, 4) int, the patches' frames
    """

    ndim = 2
    offset_in_product = True  # its 9-term products sum in order: an offset may be their last term (``layout.block_product``)

    def __init__(self, mesh: HalfEdgeMesh, frames: np.ndarray):
        self.mesh, self.frames = mesh, frames
        self.dtype = np.dtype(_index_type(mesh))
        self.shape = (9, int(frames.shape[0]))
        self._whole = None

    def block(self, start: int, stop: int, out: np.ndarray | None = None) -> np.ndarray:
        """(9, stop - start) int: the slots of patches start:stop (written into ``out``'s first columns if given)."""
        if self._whole is not None:
            return self._whole[:, start:stop]
        grid = np.empty((9, stop - start), dtype=self.dtype) if out is None else out
        _fill_grid(self.mesh, self.frames[start:stop], grid)
        return grid[:, : stop - start]

    def keep_slot_arrays(self) -> None:
        """Keep of the refined mesh only what the slots are made from (``origin``, ``next``), for a holder that
        lets the rest of the topology go (the streamed conversion: on the 4,000,000-quad torus its ``face``,
        ``twin``, face sizes and offsets are 3 GB)."""
        mesh = self.mesh
        self.mesh = HalfEdgeMesh(mesh.n_vertices, None, None, mesh.origin, None, mesh.next, None, None)

    def hold(self) -> np.ndarray:
        """The whole (9, Nq) table, made once and kept from now on."""
        if self._whole is None:
            self._whole = biquadratic_grid(self.mesh, self.frames)
        return self._whole

    def __getitem__(self, key):
        """Indexing as the (9, Nq) array's: a slice of patches ([:, a:b], [j, a:b]) is made alone, else the whole."""
        if isinstance(key, tuple) and len(key) == 2 and isinstance(key[1], slice) and key[1].step in (None, 1):
            start, stop, _ = key[1].indices(self.shape[1])
            return self.block(start, max(start, stop))[key[0]]
        return np.asarray(self)[key]

    def __array__(self, dtype=None, copy=None):
        whole = self._whole if self._whole is not None else biquadratic_grid(self.mesh, self.frames)
        return whole if dtype is None else whole.astype(dtype)


def biquadratic_layout(mesh: HalfEdgeMesh, frames: np.ndarray) -> PatchLayout:
    """Step A2 for the patches with ``frames`` (Nq, 4): a stage from refined points (V, d) to (Nq 9, d) coefficients.

    Row ``9 p + 3 i + j`` of its output (and of its matrix) is coefficient Q[i, j] of patch p. Its slots
    are a ``GridSlots``, made by blocks as the products read them.
    """
    return PatchLayout("biquadratic", [(GridSlots(mesh, frames), BIQUADRATIC_FROM_GRID)], mesh.n_vertices, 9)
