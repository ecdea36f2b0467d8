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

    def weights(self, n: int) -> np.ndarray:
        """(16 n, 4 n) float, the rule's patches as weights on the hole's points [A, B1, B2, C] (cached)."""
        return _dense_weights(self.rule(n), n, float(self.alpha), float(self.beta), self.tangent_rule)

    def tangent_datum(self, n: int):
        """(u, w): the tangent datum of n-sided holes (see the module docstring)."""
        return HOLE_RULES[self.rule(n)].tangent_datum(n, self.tangent_rule)
