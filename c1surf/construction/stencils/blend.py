"""Blend ratios per cell and per vertex (paper, A1 and section 4).

The paper gives every input cell f a blend ratio alpha_f and notes (section
4) that ratios can also be attached to mesh points: "alpha = 0.15 everywhere
except at the mesh points labelled 0.0 and 0.5". c1surf supports both:

- **first step**: the new point of corner (f, v) is ``(1 - a) V + a S_f`` with
  ``a`` the ratio of vertex v when v has one, else the ratio of cell f. So
  ``doo_sabin_matrix`` gets one ratio per corner (half-edge).
- **second step**: a once-refined vertex *is* an input corner (f, v) and
  keeps that corner's first-step ratio: every new point the second step makes
  from it in an F-cell or E-cell uses it, times ``1 - cos(2 pi / n)`` as in
  A1. V-cells (made at input vertex v) take one ratio, the minimum of their
  corners' ratios: one ratio keeps the V-cell's centroid, which A1a needs,
  and the minimum lets a zero ratio win, which Lemma 1.3.12 needs. Hence
  - the F-cell of input cell f keeps alpha_f at the corners without a vertex ratio;
  - an E-cell's points follow the cells (or vertices) they come from;
  - the V-cell of v takes v's ratio when v has one, else the smallest ratio
    of the cells around v.
  With one ratio everywhere this is the paper's rule.

Zero ratios (Lemma 1.3.12 and its proof): cell ratio 0 makes the points A, B, C
around the cell coalesce into its vertices, so a planar cell becomes a planar
piece of surface bounded by its edges, and every edge of it lies on the
surface; vertex ratio 0 coalesces all points around the vertex into it, so
the surface passes through it. Coalesced points make patches degenerate
there (zero derivatives: no normal), as in the paper.

Ratios are data, not geometry: the construction stays linear in the points.
"""
from __future__ import annotations

import numpy as np

from ...mesh.halfedges import HalfEdgeMesh


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


def second_step_corner_ratios(level1: HalfEdgeMesh, is_vertex_cell: np.ndarray, corner_ratio: np.ndarray) -> np.ndarray:
    """Ratio of every corner (half-edge) of the once-refined mesh in the second step.

    Parameters
    ----------
    level1 : HalfEdgeMesh of the once-refined mesh (its vertices are input corners)
    is_vertex_cell : (F',) bool, the V-cells
    corner_ratio : (H,) float, first-step ratio of every input corner

    Returns
    -------
    (H',) float: ``r (1 - cos(2 pi / n))`` with r the ratio of the corner's
    vertex, or, in a V-cell, the minimum over the cell's vertices.
    """
    ratio = np.asarray(corner_ratio, dtype=np.float64)[level1.origin]
    cell_min = np.minimum.reduceat(ratio, level1.face_offsets[:-1])
    in_vertex_cell = is_vertex_cell[level1.face]
    ratio = np.where(in_vertex_cell, cell_min[level1.face], ratio)
    per_face = 1.0 - np.cos(2.0 * np.pi / level1.face_sizes)  # per face, then spread to its corners
    return ratio * np.take(per_face, level1.face)


def second_step_ratios(level1: HalfEdgeMesh, is_vertex_cell: np.ndarray, corner_ratio: np.ndarray,
                       block: int = 1 << 20) -> np.ndarray:
    """(H',) float: ``second_step_corner_ratios`` of the once-refined mesh, made by blocks of
    ``block`` faces (each face's corners read that face alone: the same bits), as ``doo_sabin.compact_ratio`` keeps them:
    one value broadcast if every corner has the same bits, else the whole array. A quad mesh's ratios are one
    value, and the whole array (0.5 GB for the 4,000,000-quad torus, and its temporaries 4 times that) is
    never made."""
    offsets, n_faces = level1.face_offsets, level1.n_faces
    whole, first = None, None
    alike = _one_value(corner_ratio)
    for f0 in range(0, n_faces, block):
        f1 = min(n_faces, f0 + block)
        h0, h1 = int(offsets[f0]), int(offsets[f1])
        part = HalfEdgeMesh(level1.n_vertices, level1.face_sizes[f0:f1], None, level1.origin[h0:h1], None, None, None,
                            None)  # its face and offsets are made from its sizes, numbered from f0
        ratio = (second_step_corner_ratios(part, is_vertex_cell[f0:f1], corner_ratio) if alike is None
                 else _alike_second_step_ratios(part, alike))
        if whole is None:
            first = ratio[:1].copy() if first is None else first
            same = ratio[:1] if ratio.strides[0] == 0 else ratio  # a broadcast value: its first entry says it
            if np.all(same.view(np.int64) == first.view(np.int64)[0]):
                continue  # the same bits so far
            whole = np.empty(level1.n_halfedges)
            whole[:h0] = first[0]
        whole[h0:h1] = ratio
    if whole is None:
        return np.zeros(0) if first is None else np.broadcast_to(first, (level1.n_halfedges,))
    return whole


def _one_value(ratio: np.ndarray) -> np.ndarray | None:
    """(1,) float: the value of every entry of ``ratio`` (H,) when they all have its bits (one blend ratio
    everywhere, the default), else None."""
    ratio = np.asarray(ratio, dtype=np.float64)
    if ratio.size == 0:
        return None
    if ratio.ndim == 1 and ratio.strides[0] == 0:  # broadcast already (doo_sabin.compact_ratio)
        return ratio[:1].copy()
    bits = ratio.reshape(-1).view(np.int64)
    return ratio.reshape(-1)[:1].copy() if np.all(bits == bits[0]) else None


def _alike_second_step_ratios(level1: HalfEdgeMesh, value: np.ndarray) -> np.ndarray:
    """``second_step_corner_ratios`` when every input corner has the ratio ``value`` (1,), with its bits: a V-cell's
    minimum is that value too, so a corner's ratio is ``value (1 - cos(2 pi / n))`` of its face's size n alone,
    made per face and spread to the corners (one value broadcast when every face has one size: a quad mesh's
    second step, 0.1-0.2 s of gathers and temporaries of 2.9 M corners on the 180,000-quad torus)."""
    sizes = level1.face_sizes
    per_face = value * (1.0 - np.cos(2.0 * np.pi / sizes))  # the products of second_step_corner_ratios, face by face
    if per_face.size and np.all(sizes == sizes[0]):
        return np.broadcast_to(per_face[:1], (level1.n_halfedges,))
    return np.repeat(per_face, sizes)
