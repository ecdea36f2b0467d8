"""Memory of the construction's work on its many-sided cells, for the estimates made before building (``inspect``).

Most of the construction scales with the patches (the memory guard's bytes per patch count it). What
scales with the cells' sides instead:

- A3 on a hole of n <= ``LARGE_HOLE`` sides: the rule's dense (16 n, 4 n) weights, kept per size
  (``hole_rules.HoleRules.weights``), and the product of a block of holes;
- A3 on a larger hole (``hole_rules.HoleOperator``): per product block of ``items`` holes
  (``stencils.layout``: about 2^17 / (4 n) of them, at least one) the coefficients (16 n items d), the
  block's product (as many) and the ring's temporaries (``bicubic.boundary_rows``: about 15 n items d);
- A1 on a face of more than ``LARGE_FACE`` sides (``doo_sabin.doo_sabin_rows``): its corners, ratios and
  rows, 4 n d floats a face, all faces of one size at once.

Tested against tracemalloc's peak of ``convert`` on many-sided cells (tests/construction/test_large_cells.py).
"""
from __future__ import annotations

import numpy as np

from .stencils.doo_sabin import LARGE_FACE
from .stencils.holes.hole_rules import LARGE_HOLE
from .stencils.layout import _step

FLOAT = 8
RING_TEMPORARIES = 15  # (items d, n) arrays alive at once in ``bicubic.boundary_rows`` and the ring sums


def hole_bytes(n: int, count: int, d: int = 3) -> int:
    """Peak bytes of A3's work on ``count`` holes of n sides with points of d columns."""
    m = 4 * n
    items = min(count, _step(m))  # holes per product block
    if n <= LARGE_HOLE:
        return FLOAT * (16 * n * m + (16 * n + m) * items * d)
    return FLOAT * (16 + 16 + RING_TEMPORARIES) * n * items * d


def face_bytes(n: int, count: int, d: int = 3) -> int:
    """Peak bytes of the first Doo-Sabin step's work on ``count`` faces of n sides (more than ``LARGE_FACE``)."""
    return FLOAT * 4 * n * count * d if n > LARGE_FACE else 0


def cell_work_bytes(topology, d: int = 3) -> int:
    """Peak bytes of the work on the cells of ``topology`` (``SurfaceTopology``) beyond the bytes per patch: the
    largest of A3's (per hole size) and A1's (per face size of the coarse mesh), which do not run at once."""
    holes = max((hole_bytes(g.n, g.cells.size, d) for g in topology.holes), default=0)
    sizes, counts = np.unique(topology.input.face_sizes, return_counts=True)
    faces = max((face_bytes(int(n), int(k), d) for n, k in zip(sizes, counts)), default=0)
    return int(max(holes, faces))
