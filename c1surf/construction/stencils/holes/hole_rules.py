"""The A3 hole rules as a table: which formula fills an n-sided hole, and what it needs.

A rule gives the n bicubic patches of a hole from its points [A, B1, B2, C]
(``refine.holes``), linearly, so the layout applies it as one (16 n, 4 n)
weight matrix per hole size (``HoleRules.weights``). It also names its
*tangent datum*: the combination q_l = w (C_l + C_l+1) + u (B_l,2 + B_l+1,1)
(q_l = C_l when w = 0) whose first Fourier mode around the hole spans the
surface's tangent plane at the centre; the vertex-normal constraint
(``extensions.interpolation``) moves the C_l to turn that plane.

- ``g1`` (A3, and A3a with ``tangent_rule="corners"``): every n;
- ``parametric`` (section 1.3.4): 3-sided holes, parametrically C1 to the
  biquadratic patches around.

To add a rule: write its coefficient function (the signature of
``bicubic_hole_coefficients``), its tangent datum, and add an entry here; the
option ``SurfaceOptions.triangles`` chooses among the rules that cover n = 3.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import numpy as np

from .bicubic import bicubic_hole_coefficients
from .dart import dart_ring_weights
from .triangles import triangle_hole_coefficients


def _g1_tangent_datum(n: int, tangent_rule: str):
    """(u, w) of A3's P_31 (symmetric rule) or of the corners' midpoints (A3a)."""
    if tangent_rule == "corners":
        return 0.0, 0.5
    c = np.cos(2 * np.pi / n)
    a = c / (1 - c)
    return 1.0 / 12 - a / 6, 5.0 / 12 + a / 6


def _parametric_coefficients(A, B1, B2, C, alpha, beta, tangent_rule):
    """Section 1.3.4's triangles (no shape parameters)."""
    return triangle_hole_coefficients(A, B1, B2, C)


def _parametric_tangent_datum(n: int, tangent_rule: str):
    """The tangent plane at the centre comes from the corners C_l alone (P_32 from the C_i)."""
    return 0.0, 0.0


@dataclass(frozen=True)
class HoleRule:
    """One way to fill a hole.

    sizes : frozenset of int, or None for every n
    coefficients : callable (A, B1, B2, C, alpha, beta, tangent_rule) -> (..., n, 4, 4, d)
    tangent_datum : callable (n, tangent_rule) -> (u, w)
    """

    sizes: frozenset | None
    coefficients: Callable
    tangent_datum: Callable

    def covers(self, n: int) -> bool:
        return self.sizes is None or n in self.sizes


HOLE_RULES = {
    "g1": HoleRule(None, bicubic_hole_coefficients, _g1_tangent_datum),
    "parametric": HoleRule(frozenset({3}), _parametric_coefficients, _parametric_tangent_datum),
}
TRIANGLE_RULES = tuple(name for name, rule in HOLE_RULES.items() if rule.covers(3))


@lru_cache(maxsize=64)
def _dense_weights(rule: str, n: int, alpha: float, beta: float, tangent_rule: str) -> np.ndarray:
    """(16 n, 4 n) float: row 16 i + 4 k + l is coefficient P_{kl} of patch p_i, columns [A, B1, B2, C]."""
    eye = np.eye(4 * n)
    W = HOLE_RULES[rule].coefficients(eye[:n], eye[n : 2 * n], eye[2 * n : 3 * n], eye[3 * n :], alpha, beta, tangent_rule)
    W = W.reshape(16 * n, 4 * n)
    W[np.abs(W) < 1e-15] = 0.0  # exact cancellations (e.g. a = 0 terms) left as round-off
    return W


LARGE_HOLE = 64
"""Holes of more sides apply their rule as a ``HoleOperator`` (O(n)), the others as a dense (16 n, 4 n)
block (64 n^2 floats: 2 MB at n = 64, 51 GB at n = 10,000), whose bits the golden files hold."""


class HoleOperator:
    """The (16 n, 4 n) weights of the g1 rule on [A, B1, B2, C] without the matrix: O(n) per column.

    ``product`` maps the gathered points of some holes as the dense block would (rows and
    columns as ``_dense_weights``), with A3's sums over the ring formed once
    (``bicubic_hole_coefficients(sums="ring")``, ``cyclic_sums``), in local coordinates per
    hole (the mean of its corners taken off and put back: every row sums to 1).
    ``np.asarray(operator)`` makes the dense block (``Surface.stencil``: 64 n^2 floats).
    """

    def __init__(self, n: int, alpha: float, beta: float, tangent_rule: str):
        self.n, self.alpha, self.beta, self.tangent_rule = n, alpha, beta, tangent_rule
        self.shape = (16 * n, 4 * n)

    def product(self, gathered: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """(16 n, c) float: the rows of the holes' patches from ``gathered`` (4 n, c) float, the points
        [A, B1, B2, C] of each hole in columns (one column per hole and coordinate); into ``out`` if given."""
        n = self.n
        origin = gathered[3 * n :].mean(axis=0)
        local = (gathered - origin).T[:, None, :]  # (c, 1, 4 n): every column is one ring of points
        A, B1, B2, C = (local[..., k * n : (k + 1) * n].transpose(0, 2, 1) for k in range(4))  # (c, n, 1)
        P = bicubic_hole_coefficients(A, B1, B2, C, self.alpha, self.beta, self.tangent_rule, sums="ring")
        rows = P.reshape(P.shape[0], 16 * n).T  # (16 n, c): row 16 i + 4 k + l
        if out is None:
            out = np.empty(rows.shape)
        np.add(rows, origin, out=out)
        return out

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        """(16 n, 4 n) float: the dense block (64 n^2 floats)."""
        W = self.product(np.eye(4 * self.n))
        W[np.abs(W) < 1e-15] = 0.0
        return W if dtype is None else W.astype(dtype)


@dataclass(frozen=True)
class HoleRules:
    """The rule of every hole size and its shape parameters: what the A3 layout and the normal constraint look up.

    triangles : name of the rule for 3-sided holes (one of ``TRIANGLE_RULES``); other sizes use ``g1``
    alpha, beta, tangent_rule : shape parameters of ``bicubic_hole_coefficients``
    """

    triangles: str = "g1"
    alpha: float = 1.0
    beta: float = 0.0
    tangent_rule: str = "symmetric"

    def rule(self, n: int) -> str:
        """Name of the rule that fills n-sided holes."""
        return self.triangles if n == 3 and HOLE_RULES[self.triangles].covers(n) else "g1"

    def weights(self, n: int, large: int = LARGE_HOLE):
        """(16 n, 4 n) float, the rule's patches as weights on the hole's points [A, B1, B2, C] (cached);
        for n > ``large``, a ``HoleOperator`` of that shape that applies them in O(n)."""
        if n > large and self.rule(n) == "g1":
            return HoleOperator(n, float(self.alpha), float(self.beta), self.tangent_rule)
        return _dense_weights(self.rule(n), n, float(self.alpha), float(self.beta), self.tangent_rule)

    def dart_weights(self, n: int):
        """(16 n, 4 n) float: the hole of a dart, n - 2 real corners and two ghost ones last, on its ring
        [A, B1, B2, C] (``dart.dart_ring_weights``; the shape parameters as A3's)."""
        return dart_ring_weights(n, float(self.alpha), float(self.beta), self.tangent_rule)

    def tangent_datum(self, n: int):
        """(u, w): the tangent datum of n-sided holes (see the module docstring)."""
        return HOLE_RULES[self.rule(n)].tangent_datum(n, self.tangent_rule)
