"""A Surface's stencil: input points to patch coefficients as one sparse matrix (OpenSubdiv's StencilTable).

The construction is linear in the points (Theorem 1.3.3), so the product of
its stages' matrices S gives every coefficient row as a fixed combination of
input points: ``S @ points`` (the biquadratic rows, then the bicubic rows).
Two cases leave that plain form:

- rational surfaces (A2a) run on homogeneous points (w x, w); for fixed
  weights the Euclidean coefficients (S (w x)) / (S w) are still linear in x,
  with the matrix diag(1 / (S w)) S diag(w);
- the vertex-normal constraint (A1a) mixes x, y and z, so no matrix acts on
  the rows alone: ``flat_stencil`` acts on ``points.ravel()``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # scipy.sparse is imported where a stencil is made: a conversion makes none
    from scipy.sparse import csr_matrix


def row_stencil(stages, weights: np.ndarray | None = None) -> csr_matrix:
    """(R, V) csr_matrix S: the coefficient rows are ``S @ points``.

    Parameters
    ----------
    stages : sequence of ``stages.Stage``, none of which mixes coordinates
    weights : (V,) float or None, the fixed homogeneous weights of a rational surface
    """
    mixing = [stage.name for stage in stages if stage.mixes_coordinates]
    if mixing:
        raise ValueError(f"the {mixing[0]!r} stage mixes the coordinates, so no matrix acts on the points' rows: "
                         "use stencil(flat=True), which acts on points.ravel()")
    total = compose(stages)
    return total if weights is None else euclidean(total, weights)


def compose(stages) -> csr_matrix:
    """The product of the stages' matrices, first stage rightmost."""
    total = None
    for stage in stages:
        total = stage.matrix() if total is None else stage.matrix() @ total
    return total.tocsr()


def euclidean(total: csr_matrix, weights: np.ndarray) -> csr_matrix:
    """diag(1 / (S w)) S diag(w): Euclidean coefficients from Euclidean points, for fixed weights w."""
    from scipy.sparse import diags

    return (diags(1.0 / (total @ weights)) @ total @ diags(weights)).tocsr()


def flat_stencil(stages, columns: int, weights: np.ndarray | None = None) -> csr_matrix:
    """(R d, V d) csr_matrix F: the coefficient rows, flattened, are ``F @ points.ravel()``.

    Row stages act on every column alike (kron with the d x d identity);
    a stage that mixes coordinates gives its own flattened matrix. A rational
    surface's stages see d + 1 columns (the weight last); the weight column
    never feeds the others, so dropping it and scaling as in ``euclidean``
    gives the Euclidean map for fixed weights.

    Parameters
    ----------
    stages : sequence of ``stages.Stage``
    columns : int, d, the columns of the (Euclidean) points
    weights : (V,) float or None, the fixed homogeneous weights of a rational surface
    """
    from scipy.sparse import diags, identity, kron

    width = columns + (weights is not None)
    rows = None  # product of the row stages so far, unflattened
    flat = None  # flattened product, from the first stage that mixes coordinates on
    for stage in stages:
        if stage.mixes_coordinates:
            before = flat if flat is not None else kron(rows, identity(width), format="csr")
            seen = None if weights is None else rows @ weights  # the weights this stage is applied to
            flat = stage.matrix(width, seen) @ before
            continue  # the weights pass it unchanged: ``rows`` stays their map
        if flat is not None:
            flat = kron(stage.matrix(), identity(width), format="csr") @ flat
        rows = stage.matrix() if rows is None else stage.matrix() @ rows
    if flat is None:
        flat = kron(rows, identity(width), format="csr")
    if weights is None:
        return flat.tocsr()
    out = (np.arange(rows.shape[0])[:, None] * width + np.arange(columns)).ravel()
    into = (np.arange(rows.shape[1])[:, None] * width + np.arange(columns)).ravel()
    scale_out = np.repeat(1.0 / (rows @ weights), columns)
    return (diags(scale_out) @ flat.tocsr()[out][:, into] @ diags(np.repeat(weights, columns))).tocsr()
