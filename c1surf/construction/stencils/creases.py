"""Creases and corners in the two Doo-Sabin steps of A1 (``construction.features``).

A Doo-Sabin point of corner h (vertex v of face f) is ``(1 - a) v + a S_f``.
Where f has a sharp edge at v, or v is a corner, the point is pulled towards a
*target* on the crease polygon or the corner:

- v a corner: the target is v;
- f's edge (v, w) sharp: ``(1 - b) v + b w``, the point Chaikin's rule puts on
  the crease polygon (b = a / 2, which is 1/4 at the default blend; the smooth
  point of a parallelogram face is this target plus the same step along the
  other edge, so sharpening removes the component across the crease);
- both of f's edges at v sharp (f alone on its side of the crease):
  ``(1 - b) v + b/2 (w + u)``, between the two Chaikin points;

by the weight ``w(s) = 1 - 2^(-s/2)`` with s the sharpness (of the edge, the
mean of both edges, or the corner's) less the steps already taken: 0 for
s <= 0, 0.29 at s = 1, 0.97 at the cap s = 10. (A steeper law, 1 - 2^-s, makes
cells so thin at s >= 6 that storing their coefficients in float64 far from the
origin alone breaks G1 by 3e-10 rad, measured on OpenSubdiv's bishop and rook;
with the half exponent they stay below 5e-11.) So a crease of sharpness s is sharp
"during the first steps of refinement and smooth after" as in OpenSubdiv: the
first step uses s, the second s - 1, and A2/A3 build smooth patches on the
result. Since w < 1 no cell collapses, every patch keeps a tangent plane, and
the surface is G1 for every sharpness (Theorem 1.3.3 holds for any points).

The second step sees the creases of the first on the once-refined mesh: the
edges of the F-cells along a sharp input edge (one per side of it, the long
sides of the thin E-cell between them) keep its sharpness, and every corner of
a corner vertex's V-cell is a corner.
"""
from __future__ import annotations

import numpy as np

from ...mesh.halfedges import HalfEdgeMesh


def crease_weight(sharpness: np.ndarray, step: int) -> np.ndarray:
    """(k,) float in [0, 1): how far step ``step`` (1 or 2) pulls a point of this sharpness to its target."""
    s = np.asarray(sharpness, dtype=np.float64) - (step - 1)
    return np.where(s > 0, 1.0 - np.exp2(-np.maximum(s, 0.0) / 2), 0.0)


def crease_correction(mesh: HalfEdgeMesh, ratio: np.ndarray, chaikin_ratio: np.ndarray, halfedge_sharpness: np.ndarray,
                      vertex_sharpness: np.ndarray, step: int, centroid_column: np.ndarray | None = None,
                      n_columns: int | None = None):
    """The change creases and corners make to one Doo-Sabin step, as a sparse matrix.

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices and H half-edges, the mesh the step refines
    ratio : (H,) float, the step's ratio a of every corner (``stencils.blend``)
    chaikin_ratio : (H,) float, the first-step ratio of every corner's vertex (b = ratio / 2 along creases)
    halfedge_sharpness : (H,) float, sharpness of every half-edge's edge
    vertex_sharpness : (V,) float, corner sharpness of every vertex
    step : 1 or 2
    centroid_column : (F,) int or None, the column of each face's centroid, -1 for none (faces of many sides:
        ``doo_sabin.centroid_columns``), where the smooth point's ``a / n`` on each corner is ``a`` on it
    n_columns : int or None, the columns (V, or V + those centroids)

    Returns
    -------
    (H, V) csr_matrix C, or None when no point moves: the sharp step is ``M + C``
    with M the smooth step (``doo_sabin_matrix``); row h is ``w (target - smooth point)``.
    """
    h = np.arange(mesh.n_halfedges)
    prev = mesh.prev
    s_next, s_prev, s_corner = halfedge_sharpness, halfedge_sharpness[prev], vertex_sharpness[mesh.origin]
    corner = s_corner > 0
    both = ~corner & (s_next > 0) & (s_prev > 0)
    along_next = ~corner & ~both & (s_next > 0)
    along_prev = ~corner & ~both & (s_prev > 0)
    sharpness = np.select([corner, both, along_next, along_prev], [s_corner, (s_next + s_prev) / 2, s_next, s_prev], 0.0)
    weight = crease_weight(sharpness, step)
    moved = np.flatnonzero(weight > 0)
    if moved.size == 0:
        return None
    h, weight, b = moved, weight[moved], np.minimum(chaikin_ratio[moved], 1.0) / 2
    corner, both, along_next, along_prev = corner[h], both[h], along_next[h], along_prev[h]
    # target: t_v v + t_w w + t_u u, with w = dest[h], u = origin[prev[h]]
    t_v = np.where(corner, 1.0, 1.0 - b)
    t_w = np.where(along_next, b, np.where(both, b / 2, 0.0))
    t_u = np.where(along_prev, b, np.where(both, b / 2, 0.0))
    rows = [h, h, h]
    cols = [mesh.origin[h], mesh.dest[h], mesh.origin[prev[h]]]
    vals = [weight * t_v, weight * t_w, weight * t_u]
    # minus w times the smooth point (1 - a) v + a/n (sum of the face's vertices)
    a, face = ratio[h], mesh.face[h]
    size = mesh.face_sizes[face]
    own = np.zeros(h.size, dtype=bool) if centroid_column is None else centroid_column[face] >= 0
    spread = np.where(own, 0, size)  # the corners of a face without a centroid column
    members = np.repeat(mesh.face_offsets[face], spread) + (np.arange(spread.sum()) - np.repeat(np.cumsum(spread) - spread, spread))
    rows += [h, np.repeat(h, spread), h[own]]
    cols += [mesh.origin[h], mesh.origin[members], np.zeros(0, dtype=np.int64) if centroid_column is None
             else centroid_column[face[own]]]
    vals += [-weight * (1.0 - a), np.repeat(-weight * a / size, spread), -weight[own] * a[own]]
    from scipy.sparse import csr_matrix  # sharp features only

    correction = csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                            shape=(mesh.n_halfedges, n_columns or mesh.n_vertices))
    correction.sum_duplicates()
    return correction


def refined_sharpness(coarse: HalfEdgeMesh, level1: HalfEdgeMesh, halfedge_sharpness: np.ndarray,
                      vertex_sharpness: np.ndarray):
    """Sharpness on the once-refined mesh, for the second step.

    Parameters
    ----------
    coarse : HalfEdgeMesh with H half-edges (level-1 vertex h is coarse corner h)
    level1 : HalfEdgeMesh, ``refine.doo_sabin.refined_halfedges(coarse, ...)``
    halfedge_sharpness : (H,) float, coarse
    vertex_sharpness : (V,) float, coarse

    Returns
    -------
    halfedge : (H1,) float: the F-cell edge h -> next[h] (level-1 half-edge h) and its twin,
        a long side of the E-cell of coarse edge h, keep the coarse edge's sharpness
    vertex : (H,) float: every level-1 vertex keeps the corner sharpness of its coarse vertex
    """
    n = coarse.n_halfedges
    halfedge = np.zeros(level1.n_halfedges)
    halfedge[:n] = halfedge_sharpness
    twin = level1.twin[:n]
    inner = twin >= 0
    halfedge[twin[inner]] = np.maximum(halfedge[twin[inner]], halfedge_sharpness[inner])
    return halfedge, vertex_sharpness[coarse.origin]




def crease_corner_ratios(corner_ratio: np.ndarray, mesh: HalfEdgeMesh, crease_vertex: np.ndarray) -> np.ndarray:
    """(H,) float: ``corner_ratio`` with every corner at a cut crease vertex given that vertex's smallest ratio.

    Both sheets of a C0 crease (``mesh.creases.sheets``) then refine their cells along it alike, so the
    mirrored pairs stay mirrored about the same crease points in the second step.

    Parameters
    ----------
    corner_ratio : (H,) float, first-step ratio of every corner of ``mesh``
    mesh : HalfEdgeMesh with V vertices, the coarse mesh (cut, ghost quads, any outer ghost layer)
    crease_vertex : (V0,) int, uncut vertex of each of the first V0 vertices on a cut crease, -1 elsewhere
    """
    key = np.full(mesh.n_vertices, -1, dtype=np.int64)
    key[: crease_vertex.size] = crease_vertex
    at = key[mesh.origin]
    on = at >= 0
    if not on.any():
        return corner_ratio
    smallest = np.full(int(at.max()) + 1, np.inf)
    np.minimum.at(smallest, at[on], corner_ratio[on])
    out = corner_ratio.copy()
    out[on] = smallest[at[on]]
    return out


def mirror_rows(step: csr_matrix, mesh: HalfEdgeMesh, sheets, corner_ratio: np.ndarray) -> csr_matrix:
    """The first Doo-Sabin step with the ghost points at cut crease vertices mirrored across the crease.

    A ghost quad's corner at crease vertex v, across crease edge (v, w) from real corner p, becomes
    ``2 chi - p`` with ``chi = (1 - a/2) v + (a/2) w`` (a: the corners' shared ratio at v): chi is the
    crease polygon's Chaikin point, where a face and its point reflection through the edge's midpoint
    put the midpoint of their two Doo-Sabin points. The diagonal ghost of a one-face sector becomes p
    at a smooth crease vertex (its cell's centre, the crease point between the sector's two chi) and
    ``4 v - p - m1 - m2`` at a corner (m1, m2 the two mirrors of p: the cell's centre is v).

    Parameters
    ----------
    step : (H, V) csr_matrix, the first step (coarse points to once-refined points)
    mesh : HalfEdgeMesh, the coarse mesh (``sheets.mesh``, possibly closed by an outer ghost layer)
    sheets : ``mesh.creases.sheets.CreaseSheets``
    corner_ratio : (H,) float, ``crease_corner_ratios`` of the step's ratios

    Returns
    -------
    (H, V) csr_matrix, ``step`` with the ghost rows replaced (still affine: every row sums to 1)
    """
    from scipy.sparse import csr_matrix, diags, vstack  # C0 creases only: a plain conversion imports no scipy

    n_rows, n_cols = step.shape
    real, ghost = sheets.mirror_real, sheets.mirror_ghost
    v, w, b = mesh.origin[real], sheets.mirror_toward, corner_ratio[real] / 2
    chi = csr_matrix((np.r_[2 * (1 - b), 2 * b], (np.r_[np.arange(real.size), np.arange(real.size)], np.r_[v, w])),
                     shape=(real.size, n_cols))
    mirrored = (chi - step[real]).tocsr()
    slot = np.full(n_rows, -1, dtype=np.int64)
    slot[ghost] = np.arange(ghost.size)
    at_real = step[sheets.diagonal_real]
    corner = sheets.diagonal_corner
    m1, m2 = mirrored[slot[sheets.diagonal_mirrors[:, 0]]], mirrored[slot[sheets.diagonal_mirrors[:, 1]]]
    vertex = csr_matrix((np.full(corner.sum(), 4.0), (np.flatnonzero(corner), mesh.origin[sheets.diagonal_ghost[corner]])),
                        shape=(corner.size, n_cols))
    square = (corner.size, corner.size)
    scale = csr_matrix((np.where(corner, -1.0, 1.0), (np.arange(corner.size), np.arange(corner.size))), shape=square)
    only_corner = csr_matrix((corner.astype(float), (np.arange(corner.size), np.arange(corner.size))), shape=square)
    diagonal = (vertex + scale @ at_real - only_corner @ (m1 + m2)).tocsr()
    replaced = np.r_[ghost, sheets.diagonal_ghost]
    keep = np.ones(n_rows)
    keep[replaced] = 0.0
    new = csr_matrix((np.ones(replaced.size), (replaced, np.arange(replaced.size))), shape=(n_rows, replaced.size))
    return (diags(keep) @ step + new @ vstack([mirrored, diagonal]).tocsr()).tocsr()



def mirror_perturbation(matrix: csr_matrix, refined: HalfEdgeMesh, real_vertex: np.ndarray,
                        sheet_ghost: np.ndarray) -> csr_matrix:
    """A1's perturbation with every ghost point next to a C0 crease moved opposite to its real partner.

    The second Doo-Sabin step keeps mirrored pairs mirrored; the perturbation of even holes may move
    a real point beside a crease, and its ghost partner (the refined point across the crease edge
    from it) then moves by minus as much, so the pair's midpoint, a control point of the crease
    curve, stays where both sheets put it.

    Parameters
    ----------
    matrix : (Vr, Vr) csr_matrix, the perturbation (identity plus the even holes' corrections)
    refined : HalfEdgeMesh, the twice-refined mesh
    real_vertex : (Vr,) bool, refined points whose patches are kept (the ghost quads' are not)
    sheet_ghost : (Vr,) bool, refined points of the sheets' ghost quads: only these mirror a partner (the
        ghost layer closing a boundary that no crease reaches is not mirrored: an even hole there keeps
        its own perturbation)
    """
    from scipy.sparse import csr_matrix, diags

    crossing = real_vertex[refined.origin] & sheet_ghost[refined.dest]
    ghost, real = refined.dest[crossing], refined.origin[crossing]
    ghost, first = np.unique(ghost, return_index=True)
    real = real[first]
    identity = diags(np.ones(matrix.shape[0]), format="csr")
    delta = (matrix - identity).tocsr()
    moved = np.diff(delta.indptr)[real] > 0
    if not moved.any():
        return matrix
    ghost, real = ghost[moved], real[moved]
    keep = np.ones(matrix.shape[0])
    keep[ghost] = 0.0
    select = csr_matrix((np.ones(ghost.size), (ghost, real)), shape=matrix.shape)
    return (identity + diags(keep) @ delta - select @ delta).tocsr()


def mirror_perturbation_left(constraints: csr_matrix, refined: HalfEdgeMesh, real_vertex: np.ndarray,
                             sheet_ghost: np.ndarray):
    """``mirror_perturbation`` for the factored perturbation ``x - A^T (G (A x))`` (``perturbation.PerturbationStep``):
    the (Vr, Vr) csr_matrix L, O(Vr) entries, with ``mirror_perturbation``'s matrix = ``I - L A^T G A``, or None
    when no ghost partner moves (L = I).

    A row of A^T G A is non-zero exactly where A has a column (G is invertible and A of full row rank),
    so the points that move are the B points of the even holes. Parameters: ``constraints`` A (m, Vr) csr_matrix,
    the rest as ``mirror_perturbation``.
    """
    from scipy.sparse import csr_matrix, diags

    crossing = real_vertex[refined.origin] & sheet_ghost[refined.dest]
    ghost, real = refined.dest[crossing], refined.origin[crossing]
    ghost, first = np.unique(ghost, return_index=True)
    real = real[first]
    moves = np.diff(constraints.tocsc().indptr) > 0
    moved = moves[real]
    if not moved.any():
        return None
    ghost, real = ghost[moved], real[moved]
    n = refined.n_vertices
    keep = np.ones(n)
    keep[ghost] = 0.0
    return (diags(keep, format="csr") - csr_matrix((np.ones(ghost.size), (ghost, real)), shape=(n, n))).tocsr()


__all__ = ["crease_weight", "crease_correction", "refined_sharpness", "crease_corner_ratios", "mirror_rows",
           "mirror_perturbation", "mirror_perturbation_left"]
