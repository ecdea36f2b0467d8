"""One patch's triangulation in parameter space, for its interior and four side segment counts.

A patch with (m_u, m_v) segments whose four sides have (s_0, s_1, s_2, s_3)
segments (sides 0 and 2 run along u, 1 and 3 along v; ``adjacency``'s side
numbering; each s at least the patch's own count, since a side takes the
larger count of its two patches) is triangulated once per distinct tuple and
that template is applied to every patch of the tuple.

- All sides at the patch's own counts: the plain (m_u+1) x (m_v+1) grid, cut as
  ``evaluation.tessellate.grid_triangles`` cuts it.
- Otherwise the interior grid (u = i / m_u, v = j / m_v for 0 < i < m_u, 0 < j < m_v;
  a direction with one segment puts its single interior line at 1/2) is
  surrounded by a border strip: four trapezoids, each between one side's samples
  and the interior's outermost row or column, "zipped" by merging the two sorted
  parameter sequences. The trapezoids meet along the diagonals from the patch
  corners to the interior's corners, so every edge of the template is shared by
  two of its triangles or lies on a side: no T-junction, and patches sharing a side
  sample it at the same parameters (k / s).

The bound of ``resolution`` holds for every template triangle: a zipped triangle
spans at most one interior step or one side step in the along direction (the
merge takes the smaller next parameter, and s >= m), and one strip in the
across direction, so its parameter box is within 1/m_u x 1/m_v.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

CORNER_UV = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


@dataclass(frozen=True)
class Template:
    """The triangulation of one (m_u, m_v, s_0, s_1, s_2, s_3).

    key : the tuple
    uv : (L, 2) float, local samples: corners 0..3, the inner samples of sides 0..3 (side s:
        ``side_start[s] + k - 1`` is sample k / s_s, in increasing parameter), then the
        interior (``interior_start`` on, u slowest)
    triangles : (T, 3) int64 local indices, counter-clockwise in (u, v) (so, on the surface,
        counter-clockwise about x_u x x_v, as the uniform grid)
    side_start : (4,) int64; interior_start : int
    """

    key: tuple
    uv: np.ndarray
    triangles: np.ndarray
    side_start: np.ndarray
    interior_start: int

    @property
    def n_interior(self) -> int:
        return int(self.uv.shape[0] - self.interior_start)

    @property
    def regular(self) -> bool:
        m_u, m_v, s0, s1, s2, s3 = self.key
        return s0 == s2 == m_u and s1 == s3 == m_v


def cell_triangles(ids: np.ndarray) -> np.ndarray:
    """Two triangles per cell of a grid of local ids, counter-clockwise in (u, v).

    ids : (a, b) int, id of sample (i, j) (i along u); returns (2 (a-1) (b-1), 3) int64, the cut of
    ``evaluation.tessellate.grid_triangles``: (i,j) (i+1,j) (i+1,j+1) and (i,j) (i+1,j+1) (i,j+1)
    """
    p, q, r, s = ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]
    return np.stack([np.stack([p, q, r], -1), np.stack([p, r, s], -1)], axis=2).reshape(-1, 3).astype(np.int64)


def zip_rows(outer_ids, outer_t, inner_ids, inner_t) -> list:
    """Triangles between two sorted rows of samples: a side's and the interior's outermost one.

    The two parameter sequences are merged: at every step the row whose next
    parameter is smaller advances, giving one triangle (two samples of that row,
    the current one of the other). ``len(outer) + len(inner) - 2`` triangles, in
    any orientation (``template`` orients them).
    """
    tris, k, i = [], 0, 0
    last_k, last_i = len(outer_ids) - 1, len(inner_ids) - 1
    while k < last_k or i < last_i:
        if i == last_i or (k < last_k and outer_t[k + 1] <= inner_t[i + 1]):
            tris.append((outer_ids[k], outer_ids[k + 1], inner_ids[i]))
            k += 1
        else:
            tris.append((outer_ids[k], inner_ids[i + 1], inner_ids[i]))
            i += 1
    return tris


@lru_cache(maxsize=None)
def template(key: tuple) -> Template:
    """The Template of ``key`` = (m_u, m_v, s_0, s_1, s_2, s_3), every count >= 1, each s >= its m."""
    m_u, m_v, *sides = (int(k) for k in key)
    if min(m_u, m_v, *sides) < 1 or sides[0] < m_u or sides[2] < m_u or sides[1] < m_v or sides[3] < m_v:
        raise ValueError(f"invalid segment counts {key}")
    regular = sides[0] == sides[2] == m_u and sides[1] == sides[3] == m_v
    side_t = [np.arange(1, s) / s for s in sides]
    side_uv = [np.stack([side_t[0], np.zeros(sides[0] - 1)], 1), np.stack([np.ones(sides[1] - 1), side_t[1]], 1),
               np.stack([side_t[2], np.ones(sides[2] - 1)], 1), np.stack([np.zeros(sides[3] - 1), side_t[3]], 1)]
    side_start = 4 + np.concatenate([[0], np.cumsum([s - 1 for s in sides])[:-1]]).astype(np.int64)
    interior_start = 4 + sum(s - 1 for s in sides)
    inner_u = np.arange(1, m_u) / m_u if regular or m_u > 1 else np.array([0.5])
    inner_v = np.arange(1, m_v) / m_v if regular or m_v > 1 else np.array([0.5])
    iu, iv = np.meshgrid(inner_u, inner_v, indexing="ij")
    uv = np.concatenate([CORNER_UV, *side_uv, np.stack([iu.ravel(), iv.ravel()], 1)])
    inner = interior_start + np.arange(iu.size).reshape(iu.shape)
    run = [side_start[s] + np.arange(sides[s] - 1) for s in range(4)]
    if regular:
        ids = np.empty((m_u + 1, m_v + 1), dtype=np.int64)
        ids[0, 0], ids[-1, 0], ids[-1, -1], ids[0, -1] = 0, 1, 2, 3
        ids[1:-1, 0], ids[-1, 1:-1], ids[1:-1, -1], ids[0, 1:-1] = run
        ids[1:-1, 1:-1] = inner
        triangles = cell_triangles(ids)
    else:
        # each side from corner to corner in increasing parameter, and the interior row or column beside it
        rows = [([0, *run[0], 1], 0, inner[:, 0], inner_u), ([1, *run[1], 2], 1, inner[-1, :], inner_v),
                ([3, *run[2], 2], 0, inner[:, -1], inner_u), ([0, *run[3], 3], 1, inner[0, :], inner_v)]
        strips = [zip_rows(outer, uv[outer, axis], list(row), t) for outer, axis, row, t in rows]
        triangles = np.concatenate([cell_triangles(inner), np.array(sum(strips, []), dtype=np.int64).reshape(-1, 3)])
        triangles = _counter_clockwise(uv, triangles)
    return Template((m_u, m_v, *sides), uv, triangles, side_start, interior_start)


def _counter_clockwise(uv: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``triangles`` (T, 3) with the clockwise ones in (u, v) reversed; a ValueError for a flat one."""
    a, b, c = uv[triangles[:, 0]], uv[triangles[:, 1]], uv[triangles[:, 2]]
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    if not np.all(area != 0):
        raise ValueError("internal: a template triangle has no area")
    out = triangles.copy()
    out[area < 0] = out[area < 0][:, ::-1]
    return out


__all__ = ["Template", "template", "zip_rows", "cell_triangles"]
