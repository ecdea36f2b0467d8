"""Blend ratios per cell and per vertex (paper, A1 and section 4).

The paper gives every input cell f a blend ratio alpha_f and notes (section
4) that ratios can also be attached to mesh points: "alpha = 0.15 everywhere
except at the mesh points labelled 0.0 and 0.5". c1surf supports both:

- **first step**: the new point of corner (f, v) is ``(1 - a) V + a S_f`` with
  ``a`` the ratio of vertex v when v has one, else the ratio of cell f. So
  ``doo_sabin_matrix`` gets one ratio per corner (half-edge).
- **second step**: every once-refined cell is made of input corners (a
  once-refined vertex *is* an input corner), and takes the mean of their
  first-step ratios, times ``1 - cos(2 pi / n)`` as in A1. Hence
  - the cell made from input cell f (F-cell) keeps alpha_f when no corner of f
    has a vertex ratio;
  - the cell made at input vertex v (V-cell) takes v's ratio when v has one,
    else the mean ratio of the cells around v;
  - the quad made at an input edge (E-cell) takes the mean of the ratios of its
    four corners: the mean of the two end points' ratios when both have one,
    the mean of the two cells' ratios when neither has.
  With one ratio everywhere this is the paper's rule. Every cell gets one
  ratio in the second step, so a V-cell keeps its centroid (A1a needs that).

Vertex ratio 0 makes every first-step point at v coincide with v and the V-cell
shrink to v: the surface then passes through v (Lemma 1.3.12, proof). Cell
ratio 0 on two neighbouring cells puts their common edge on the surface
(Lemma 1.3.12).

Ratios are data, not geometry: the construction stays linear in the points.
"""
from __future__ import annotations

import numpy as np

from .topology import HalfEdgeMesh


def check_ratios(values, count: int, what: str, allow_unset: bool) -> np.ndarray:
    """Validate ratios: (count,) floats in [0, 1]; NaN (or any negative value) means unset when ``allow_unset``.

    Returns
    -------
    (count,) float64, unset entries as NaN
    """
    r = np.asarray(values, dtype=np.float64).reshape(-1)
    if r.size != count:
        raise ValueError(f"{what}: expected {count} values, got {r.size}")
    if allow_unset:
        r = np.where(r < 0, np.nan, r)
        bad = np.flatnonzero(r > 1)
    else:
        bad = np.flatnonzero(~((r >= 0) & (r <= 1)))
    if bad.size:
        raise ValueError(f"{what}: blend ratio {r[bad[0]]!r} at index {bad[0]} is not in [0, 1] ({bad.size} such)")
    return r


def corner_ratios(mesh: HalfEdgeMesh, face_ratio: np.ndarray, vertex_ratio: np.ndarray | None = None) -> np.ndarray:
    """First-step ratio of every corner (half-edge): the vertex's ratio where set, else the cell's.

    Parameters
    ----------
    mesh : HalfEdgeMesh (the coarse mesh)
    face_ratio : (F,) float
    vertex_ratio : (V,) float with NaN where unset, or None

    Returns
    -------
    (H,) float
    """
    ratio = np.asarray(face_ratio, dtype=np.float64)[mesh.face]
    if vertex_ratio is not None:
        at_vertex = np.asarray(vertex_ratio, dtype=np.float64)[mesh.origin]
        ratio = np.where(np.isnan(at_vertex), ratio, at_vertex)
    return ratio


def refined_cell_ratios(face_sizes: np.ndarray, face_vertices: np.ndarray, corner_ratio: np.ndarray) -> np.ndarray:
    """Blend ratio of each once-refined cell: the mean ratio of the input corners it is made of.

    Parameters
    ----------
    face_sizes, face_vertices : the once-refined cells (``RefinedFaces``); their
        vertices are input corners (half-edges)
    corner_ratio : (H,) float, from ``corner_ratios``

    Returns
    -------
    (F',) float (exactly the common value where all corners agree)
    """
    values = corner_ratio[face_vertices]
    offsets = np.concatenate([[0], np.cumsum(face_sizes)[:-1]])
    mean = np.add.reduceat(values, offsets) / face_sizes
    low, high = np.minimum.reduceat(values, offsets), np.maximum.reduceat(values, offsets)
    return np.where(low == high, low, mean)
