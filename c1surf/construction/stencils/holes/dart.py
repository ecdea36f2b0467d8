"""A dart's hole: the n bicubic patches of an n-sided hole with one C0 spoke (docs/sharp-features.md, "Darts").

A crease that ends inside the surface (a dart) arrives, after the two Doo-Sabin steps, at the n-sided
cell of its end vertex along one spoke. Here that spoke is spoke n - 1, from M_{n-1} to S, between
p_{n-1} (the patch *before* the crease) and p_0 (the patch *after* it). Names as in ``bicubic``
(corners C_i, edge neighbours B_{i,1}, B_{i,2}, diagonal points A_i).

Outside the hole the crease is a C0 seam of biquadratic patches (``mesh.creases.sheets``): the patches
on each side read, across the crease, the *mirrors* of their own side's points about crease points.
The hole does the same at the crease spoke's outer end: p_{n-1} reads, in place of C_0 and B_{0,1}
(the points across the crease from C_{n-1} and B_{n-1,2}), its own side's mirrors ``C_before`` and
``B_before``; p_0 reads, in place of C_{n-1} and B_{n-1,2}, ``C_after`` and ``B_after``. With those
views A3's boundary rows are the paper's, so each patch joins its own side's biquadratic patches G1
(Lemmas 1.3.5 and 1.3.6 hold within each view). The rest:

- the crease spoke is C0 only: p_{n-1} and p_0 share its curve M_{n-1}, P_31, P_32, S (P_31 the mean
  of the two views' P_31: for mirrored views both are the same crease points, so this is each view's);
- the centre keeps one point S and one tangent plane: the P_32 of A3 (every t_i = P_32,i - S in the
  span of the first Fourier mode, which satisfies the n - 1 tangent conditions I_3 of the open chain);
- the other n - 1 spokes keep G1: the twist conditions I_4, P_22,i + P_22,i+1 = 2 E_i for
  i = 0..n-2, are an open chain, solvable for every n (no vertex-enclosure constraint, no
  perturbation needed); their one free vector is fixed by least squares to A3's own P_22 (the paper's
  choice, which satisfies the chain exactly for odd n).

Linear in the points, so it is one (16 n, 4 n + 4) weight matrix per n (``dart_hole_weights``).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .bicubic import boundary_rows, shift


def replaced(x: np.ndarray, index: int, value: np.ndarray) -> np.ndarray:
    """(..., n, d) float: ``x`` with row ``index`` (of the n) replaced by ``value`` (..., d)."""
    out = x.copy()
    out[..., index, :] = value
    return out


def open_chain_twists(E: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(..., n, d) float: the P_22,i nearest ``target`` (least squares) with P_22,i + P_22,i+1 = 2 E_i, i = 0..n-2.

    The chain's solutions are r + x h with r_0 = 0, r_{i+1} = 2 E_i - r_i and h_i = (-1)^i; the nearest
    to ``target`` takes x = <target - r, h> / n.

    Parameters
    ----------
    E : (..., n, d) float, E_i of spoke i (E_{n-1}, the C0 spoke's, is not used)
    target : (..., n, d) float, the desired P_22 (A3's)
    """
    n = E.shape[-2]
    h = np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    # r_i = 2 sum_{m < i} (-1)^(i - 1 - m) E_m = 2 h_{i-1} sum_{m < i} h_m E_m  (h_{i-1} = -h_i)
    signed = h[:, None] * E
    prefix = np.cumsum(signed, axis=-2) - signed  # sum_{m < i} h_m E_m
    r = -2.0 * h[:, None] * prefix
    x = np.einsum("i,...id->...d", h, target - r)[..., None, :] / n
    return r + x * h[:, None]


def dart_hole_coefficients(A, B1, B2, C, mirrors, alpha: float = 1.0, beta: float = 0.0,
                           tangent_rule: str = "symmetric"):
    """The n bicubic patches of a dart's hole: C0 across spoke n - 1 (p_{n-1} | p_0), G1 across the others and at S.

    Parameters
    ----------
    A, B1, B2, C : (..., n, d) float, the refined points around the hole (``bicubic`` names)
    mirrors : (C_before, B_before, C_after, B_after), each (..., d) float: C_before, B_before are what p_{n-1}
        reads in place of C_0 and B_{0,1} (its own side's mirrors of C_{n-1} and B_{n-1,2} across the crease);
        C_after, B_after what p_0 reads in place of C_{n-1} and B_{n-1,2} (the mirrors of C_0 and B_{0,1})
    alpha, beta, tangent_rule : as ``bicubic.bicubic_hole_coefficients`` (A3's P_32 and S)

    Returns
    -------
    (..., n, 4, 4, d) float: P[..., i, k, l] is coefficient P_{kl,i} of patch p_i.
    """
    C_before, B_before, C_after, B_after = mirrors
    n = C.shape[-2]
    c = np.cos(2 * np.pi / n)
    a = c / (1 - c)
    # every patch's rows from the ring itself, but p_{n-1}'s from the view before the crease and p_0's from the
    # view after it (each view changes the rows of one patch only: P_31,n-2 and P_31,0 read no replaced point)
    P, P31 = boundary_rows(A, B1, B2, C, a)
    before, P31_before = boundary_rows(A, replaced(B1, 0, B_before), B2, replaced(C, 0, C_before), a)
    after, P31_after = boundary_rows(A, B1, replaced(B2, n - 1, B_after), replaced(C, n - 1, C_after), a)
    P[..., n - 1, :, :, :] = before[..., n - 1, :, :, :]
    P[..., 0, :, :, :] = after[..., 0, :, :, :]
    spoke_m = (before[..., n - 1, 3, 0, :] + after[..., 0, 0, 3, :]) / 2  # M_{n-1}, one point for both
    P31[..., n - 1, :] = (P31_before[..., n - 1, :] + P31_after[..., n - 1, :]) / 2
    P[..., n - 1, 3, 0, :] = spoke_m
    P[..., 0, 0, 3, :] = spoke_m
    P[..., n - 1, 3, 1, :] = P31[..., n - 1, :]
    P[..., 0, 1, 3, :] = P31[..., n - 1, :]
    # the centre, tangents and A3's twists from the same P31 (A3 on a ring whose P31 is this one)
    S_C = C.mean(axis=-2, keepdims=True)
    S = S_C + beta * (P31.mean(axis=-2, keepdims=True) - S_C)
    tangent_source = P31 if tangent_rule == "symmetric" else (C + shift(C, 1)) / 2
    i = np.arange(n)
    cosines = np.cos(2 * np.pi * ((i[None, :] - i[:, None]) % n) / n)  # [i, m] = cos(2 pi (m - i) / n)
    P32 = S + 4 * alpha / (3 * n) * np.einsum("im,...md->...id", cosines, tangent_source)
    E = (1 - 2 * c / 3) * P32 + (2 * c / 3) * P31
    j = (i[None, :] - i[:, None]) % n + 1
    sign = np.where(j % 2 == 0, 1.0, -1.0)
    Z = -sign if n % 2 else -2.0 / n * (n - j) * sign
    target = np.einsum("im,...md->...id", Z, E)  # A3's P_22 (E_{i+j-1}, NOTES-ON-THE-SEED.md item 2)
    P[..., 3, 3, :] = S
    P[..., 3, 2, :] = P32
    P[..., 2, 3, :] = shift(P32, -1)
    P[..., 2, 2, :] = open_chain_twists(E, target)
    return P


@lru_cache(maxsize=64)
def dart_hole_weights(n: int, alpha: float = 1.0, beta: float = 0.0, tangent_rule: str = "symmetric") -> np.ndarray:
    """(16 n, 4 n + 4) float: row 16 i + 4 k + l is P_{kl} of p_i, columns [A, B1, B2, C, C_before, B_before,
    C_after, B_after] (n, n, n, n, 1, 1, 1, 1 points)."""
    eye = np.eye(4 * n + 4)
    rows = [eye[k * n : (k + 1) * n] for k in range(4)] + [eye[4 * n + k] for k in range(4)]
    W = dart_hole_coefficients(*rows[:4], tuple(rows[4:]), alpha=alpha, beta=beta, tangent_rule=tangent_rule).reshape(16 * n, 4 * n + 4)
    W[np.abs(W) < 1e-15] = 0.0
    return W


@lru_cache(maxsize=64)
def dart_ring_weights(m: int, alpha: float = 1.0, beta: float = 0.0, tangent_rule: str = "symmetric") -> np.ndarray:
    """(16 m, 4 m) float: a dart's hole as the refined mesh has it (``refine.holes.split_dart_holes``), on its ring
    of m = n + 2 corners [A, B1, B2, C], the two ghost corners last: ghost corner n is the mirror of C_{n-1}
    across the crease (its C and B_{n,1} are the view before the crease), ghost corner n + 1 the mirror of C_0
    (its C and B_{n+1,2} the view after it). Rows of the real patches p_0..p_{n-1} from ``dart_hole_weights``;
    the ghost corners' rows (patches not kept) repeat the centre's row."""
    n = m - 2
    D = dart_hole_weights(n, alpha, beta, tangent_rule)
    i = np.arange(n)
    columns = np.r_[i, m + i, 2 * m + i, 3 * m + i, 3 * m + n, m + n, 3 * m + n + 1, 2 * m + n + 1]
    W = np.zeros((16 * m, 4 * m))
    W[: 16 * n, columns] = D
    W[16 * n :] = W[15]  # P_33 of p_0: S
    return W


__all__ = ["dart_hole_coefficients", "dart_hole_weights", "dart_ring_weights", "open_chain_twists"]
