"""Step A3: n bicubic patches filling every n-sided hole, as gathers of the hole's 4n points.

Names as in ``refine.holes``: hole corners C_i, their edge neighbours
B_{i,1}, B_{i,2} and diagonal points A_i; patch p_i sits at C_i, with
P_00 = L_i (the corner it shares with the biquadratic patches), P_30 = M_i
(the middle of edge i), P_33 = S (the hole's centre).
"""
from __future__ import annotations

import numpy as np

from ...refine.holes import HoleGroup
from .cyclic_sums import cosine_sums, twist_sums
from ..layout import PatchLayout


def shift(x: np.ndarray, s: int) -> np.ndarray:
    """x_{i+s}: the points of (..., n, d) ``x`` renumbered around the hole."""
    return np.roll(x, -s, axis=-2)


def boundary_rows(A, B1, B2, C, a: float):
    """The coefficients of A3 that join the biquadratic patches around the hole (rows k = 0, 1 and their mirrors).

    Parameters
    ----------
    A, B1, B2, C : (..., n, d) float
    a : float, ``c / (1 - c)`` with ``c = cos(2 pi / n)`` (A3), or 0 for the
        identity connecting map (section 1.3.4's triangles)

    Returns
    -------
    P : (..., n, 4, 4, d) float with P_k0, P_0k, P_11, P_21, P_12, P_31, P_13 filled, the rest 0
    P31 : (..., n, d) float
    """
    C_next, C_prev = shift(C, 1), shift(C, -1)
    B1_next = shift(B1, 1)  # B_{i+1,1}
    B2_prev = shift(B2, -1)  # B_{i-1,2}
    P = np.zeros(C.shape[:-1] + (4, 4) + C.shape[-1:])
    P[..., 0, 0, :] = (B2 + B1 + C + A) / 4
    P[..., 1, 0, :] = (5 * B2 + B1 + 5 * C + A) / 12
    P[..., 2, 0, :] = (5 * B2 + B1_next + 5 * C + C_next) / 12
    P[..., 3, 0, :] = (B2 + B1_next + C + C_next) / 4
    P[..., 0, 1, :] = (5 * B1 + B2 + 5 * C + A) / 12
    P[..., 0, 2, :] = (5 * B1 + B2_prev + 5 * C + C_prev) / 12
    P[..., 0, 3, :] = shift(P[..., 3, 0, :], -1)  # P_{03,i} = P_{30,i-1}: the side shared inside the hole, bit for bit
    P[..., 1, 1, :] = (5 * B2 + 5 * B1 + A + 25 * C) / 36 + a / 9 * (C - A)
    P[..., 2, 1, :] = (5 * B2 + 5 * C_next + B1_next + 25 * C) / 36 + a / 18 * (-5 * B2 + B1_next + C_next + 3 * C)
    P[..., 1, 2, :] = (5 * B1 + 5 * C_prev + B2_prev + 25 * C) / 36 + a / 18 * (-5 * B1 + B2_prev + C_prev + 3 * C)
    P31 = (B2 + B1_next + 5 * C_next + 5 * C) / 12 + a / 6 * (C_next + C - B2 - B1_next)
    P[..., 3, 1, :] = P31
    P[..., 1, 3, :] = shift(P31, -1)  # P_{13,i} = P_{31,i-1}
    return P, P31


def bicubic_hole_coefficients(A, B1, B2, C, alpha: float = 1.0, beta: float = 0.0, tangent_rule: str = "symmetric",
                              sums: str = "dense"):
    """Step A3: the n bicubic patches covering one n-sided hole.

    Implements the paper's formulas with the corrections of
    NOTES-ON-THE-SEED.md (P_12 is the mirror of P_21; P_22 uses E_{i+j-1}).

    Parameters
    ----------
    A, B1, B2, C : (..., n, d) float, the (perturbed) refined points around the hole
    alpha : float, the shape parameter of P_32 (default 1)
    beta : float, S = S_C + beta (S_P - S_C) (section 1.3.3; 0 gives the centroid of the C_i)
    tangent_rule : "symmetric" (A3) or "corners" (A3a: P_32 from the C_i only)
    sums : "dense" (P_32 and P_22 as (n, n) matrices on the ring: n^2 per hole, the bits of the
        dense weights of small holes) or "ring" (the same sums formed once, ``cyclic_sums``: O(n) per hole)

    Returns
    -------
    (..., n, 4, 4, d) float: P[..., i, k, l] is coefficient P_{kl,i} of patch p_i.
    """
    n = C.shape[-2]
    c = np.cos(2 * np.pi / n)
    P, P31 = boundary_rows(A, B1, B2, C, c / (1 - c))
    S_C = C.mean(axis=-2, keepdims=True)
    S = S_C + beta * (P31.mean(axis=-2, keepdims=True) - S_C)
    tangent_source = P31 if tangent_rule == "symmetric" else (C + shift(C, 1)) / 2
    if sums == "ring":
        P32 = S + 4 * alpha / (3 * n) * cosine_sums(tangent_source)
    else:
        i = np.arange(n)
        cosines = np.cos(2 * np.pi * ((i[None, :] - i[:, None]) % n) / n)  # [i, m] = cos(2 pi (m - i) / n)
        P32 = S + 4 * alpha / (3 * n) * np.einsum("im,...md->...id", cosines, tangent_source)
    E = (1 - 2 * c / 3) * P32 + (2 * c / 3) * P31
    P[..., 3, 3, :] = S
    P[..., 3, 2, :] = P32
    P[..., 2, 3, :] = shift(P32, -1)  # P_{23,i} = P_{32,i-1}
    if sums == "ring":
        P[..., 2, 2, :] = twist_sums(E)
        return P
    # P_22,i = sum_m Z[i, m] E_m with m = i + j - 1 (the notes' index correction).
    j = (i[None, :] - i[:, None]) % n + 1
    sign = np.where(j % 2 == 0, 1.0, -1.0)
    Z = -sign if n % 2 else -2.0 / n * (n - j) * sign
    P[..., 2, 2, :] = np.einsum("im,...md->...id", Z, E)
    return P


def bicubic_layout(holes: list[HoleGroup], hole_weights, n_points: int, keep=None, dart_weights=None) -> PatchLayout:
    """Step A3 for all holes: a stage from refined points (V, d) to (Nc 16, d) coefficients.

    Patches are numbered hole by hole (``holes`` order), corner i within a hole;
    row ``16 p + 4 k + l`` is P_{kl} of patch p.

    Parameters
    ----------
    holes : list of HoleGroup
    hole_weights : callable n -> (16 n, 4 n) float, the weights of the rule that fills
        n-sided holes on the points [A, B1, B2, C] (``hole_rules.HoleRules.weights``)
    n_points : int, refined points
    keep : (Nc,) bool or None, the patches kept (open meshes: those at real corners)
    dart_weights : callable n -> (16 n, 4 n) float or None, the weights of the darts' holes (``HoleGroup.dart``:
        ``hole_rules.HoleRules.dart_weights``)
    """
    groups = [(np.concatenate([g.A, g.B1, g.B2, g.C], axis=1).T, dart_weights(g.n) if g.dart else hole_weights(g.n))
              for g in holes]
    return PatchLayout("bicubic", groups, n_points, 16, keep)
