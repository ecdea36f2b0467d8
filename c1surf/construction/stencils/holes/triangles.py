"""Section 1.3.4: triangular holes with parametric C1 joins to the biquadratic patches.

For n = 3 the paper chooses the connecting maps to the biquadratic complex to
be the identity (phi_ij = id), so the three bicubic patches continue the
biquadratic patches around the hole *parametrically* C1, and joins the three
bicubics to each other with psi_i = id + t1 (1 - t2)^2 [2c, 0]: a
reparametrization that is the identity at M_i (where four patches meet, as
in a regular grid) and turns by 2c at the centre S.

In the naming of ``bicubic`` (P_00 = L_i, P_30 = M_i, P_33 = S, edge
P_3k,i = P_k3,i+1 shared by p_i and p_i+1, t = 0 at M_i, t = 1 at S):

- boundary rows: A3's P_k0, P_0k, and P_k1, P_1k with a = 0 (the identity
  map: the C1 continuation of the biquadratic neighbours);
- the edges from M_i to S are quadratics
  M_i (1-t)^2 + (C_i + C_i+1) t (1-t) + S t^2 (paper), so P_33 = S (the
  centroid) and P_32,i = (4 C_i + 4 C_i+1 + C_i-1) / 9 (paper, as printed);
- the twists P_22 follow from the join with psi_i. With
  X(t) = D_u p_i(1, t) + D_v p_i+1(t, 1) (the two cross derivatives, each
  pointing out of its patch) and T(t) the derivative along the edge, psi_i
  means X(t) = 2c t^2 T(t). Its Bernstein coefficients k = 0, 1 vanish (C1 at
  M_i), k = 3 holds by the choice of P_32, and k = 2 gives
  P_22,i + P_22,i+1 = R_i := 2 P_32,i - (4c/9) ((C_i + C_i+1)/2 - M_i),
  solved (three equations around an odd cycle) by
  P_22,i = (R_i + R_i-1 - R_i+1) / 2, i.e.

      P_22,i = (15 C_i + 2 C_i+1 + 2 C_i-1) / 18
               - [(B_i,2 + B_i+1,1) + (B_i-1,2 + B_i,1) - (B_i+1,2 + B_i-1,1)] / 36.

The transcription prints
P_22,i = (7 C_i + C_i+1 + C_i-1)/9 + C_i/6 - 1/12 sum_j (-1)^j (B_j,2 + B_j+1,1):
that formula does not satisfy the join (measured normal jumps 0.1 rad on the
icosahedron to pi on the tetrahedron, tests/test_extensions.py), another misprint; the one above is
derived from the join condition and measured G1 at machine precision.
"""
from __future__ import annotations

from .bicubic import boundary_rows, shift


def triangle_hole_coefficients(A, B1, B2, C, paper_twist: bool = False):
    """The three bicubic patches of a 3-sided hole, section 1.3.4.

    Parameters
    ----------
    A, B1, B2, C : (..., 3, d) float, points around the hole (names as in ``bicubic``)
    paper_twist : bool, use the transcription's printed P_22 (for the test that shows it is wrong)

    Returns
    -------
    (..., 3, 4, 4, d) float, P[..., i, k, l] = P_{kl,i}
    """
    if C.shape[-2] != 3:
        raise ValueError("section 1.3.4 is for 3-sided holes")
    c = -0.5
    # A3's rows next to the biquadratic patches with a = 0: the identity connecting map
    P, _ = boundary_rows(A, B1, B2, C, 0.0)
    M = P[..., 3, 0, :]
    C_next, C_prev = shift(C, 1), shift(C, -1)
    S = C.mean(axis=-2, keepdims=True)
    P32 = (4 * C + 4 * C_next + C_prev) / 9
    P[..., 3, 3, :] = S
    P[..., 3, 2, :] = P32
    P[..., 2, 3, :] = shift(P32, -1)
    if paper_twist:
        total = sum((-1) ** j * (shift(B2, j) + shift(B1, j + 1)) for j in range(3))  # j relative to i
        P[..., 2, 2, :] = (7 * C + C_next + C_prev) / 9 + C / 6 - total / 12
        return P
    R = 2 * P32 - (4 * c / 9) * ((C + C_next) / 2 - M)
    P[..., 2, 2, :] = (R + shift(R, -1) - shift(R, 1)) / 2
    return P
