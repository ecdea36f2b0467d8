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
    index_type = np.int32 if mesh.n_vertices < 2**31 else np.int64
    grid = np.empty((9, frames.shape[0]), dtype=index_type)
    origin, nxt = mesh.origin, mesh.next

    def fill(start: int, stop: int) -> None:  # random-access gathers: in threads, by blocks
        f = frames[start:stop]
        after = np.take(nxt, f, mode="clip")
        dest = np.take(origin, after, mode="clip")  # (k, 4)
        diagonal = np.take(origin, np.take(nxt, after, mode="clip"), mode="clip")
        g = grid[:, start:stop]
        g[0], g[1], g[2] = diagonal[:, 2], dest[:, 2], diagonal[:, 1]
        g[3], g[4], g[5] = dest[:, 3], np.take(origin, f[:, 0], mode="clip"), dest[:, 1]
        g[6], g[7], g[8] = diagonal[:, 3], dest[:, 0], diagonal[:, 0]

    for_each_range(frames.shape[0], lambda a, b: [fill(s, min(b, s + (1 << 16))) for s in range(a, b, 1 << 16)])
    return grid


def biquadratic_layout(mesh: HalfEdgeMesh, frames: np.ndarray) -> PatchLayout:
    """Step A2 for the patches with ``frames`` (Nq, 4): a stage from refined points (V, d) to (Nq 9, d) coefficients.

    Row ``9 p + 3 i + j`` of its output (and of its matrix) is coefficient Q[i, j] of patch p.
    """
    return PatchLayout("biquadratic", [(biquadratic_grid(mesh, frames), BIQUADRATIC_FROM_GRID)], mesh.n_vertices, 9)
