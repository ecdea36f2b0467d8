"""Exact curvature of (rational) Bezier patches: closed forms, finite differences, invariances."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from c1surf.evaluation.bezier import bernstein_basis, bernstein_columns, evaluate_patches_at, raise_degree
from c1surf.evaluation.curvature import patch_curvature, surface_curvature, tessellation_curvature
from c1surf.evaluation.rational import dehomogenize
from c1surf.io.patches.formats import load_patch_set
from conftest import rational_sphere_patch

GOLDEN = Path(__file__).resolve().parents[1] / "golden"
RNG = np.random.default_rng(20240611)
NAMES = ("k1", "k2", "K", "H", "kmax")

# Bernstein coefficients (degree 2) of x^2 and x for x = 2u - 1 on [0, 1] -> [-1, 1].
SQUARE = np.array([1.0, -1.0, 1.0])
LINEAR = np.array([-1.0, 0.0, 1.0])


def quadric_graph_patch(a, b, c):
    """Biquadratic patch of z = a x^2 + b y^2 + c x y over [-1, 1]^2 (x = 2u - 1, y = 2v - 1), exactly."""
    P = np.zeros((3, 3, 3))
    P[..., 0] = LINEAR[:, None]
    P[..., 1] = LINEAR[None, :]
    P[..., 2] = a * SQUARE[:, None] + b * SQUARE[None, :] + c * np.outer(LINEAR, LINEAR)
    return P


def graph_curvature(a, b, c, x, y):
    """Closed-form curvature of z = a x^2 + b y^2 + c x y, normal (-f_x, -f_y, 1) (= x_u x x_v).

    Signs follow c1surf: positive where the surface bends away from the normal.
    """
    fx, fy = 2 * a * x + c * y, 2 * b * y + c * x
    fxx, fyy, fxy = 2 * a, 2 * b, c
    W = 1 + fx**2 + fy**2
    K = (fxx * fyy - fxy**2) / W**2
    H = -((1 + fy**2) * fxx - 2 * fx * fy * fxy + (1 + fx**2) * fyy) / (2 * W**1.5)
    root = np.sqrt(np.maximum(H**2 - K, 0))
    return {"K": K, "H": H, "k1": H + root, "k2": H - root, "kmax": np.abs(H) + root}


def evaluate(points, u, v, weights=None):
    """Curvature of one patch at many samples (rational with ``weights``)."""
    def each(a):
        return np.broadcast_to(a, (u.size,) + a.shape)

    return patch_curvature(each(points), u, v, None if weights is None else each(weights))


@pytest.mark.parametrize("a, b, c", [(0.7, 0.7, 0.0), (0.7, -0.3, 0.0), (0.4, 1.3, -0.8), (0.0, 0.0, 1.0)])
def test_quadric_graph_matches_closed_form(a, b, c):
    """Paraboloids (elliptic, hyperbolic, rotated, saddle z = xy) everywhere on the patch, to 1e-9."""
    P = quadric_graph_patch(a, b, c)
    u, v = RNG.random(500), RNG.random(500)
    u[:4], v[:4] = [0, 1, 0, 1], [0, 0, 1, 1]  # corners too
    got = evaluate(P, u, v)
    want = graph_curvature(a, b, c, 2 * u - 1, 2 * v - 1)
    for name in NAMES:
        np.testing.assert_allclose(got[name], want[name], rtol=0, atol=1e-9, err_msg=name)
    # x is the graph point and n the unit normal
    x, y = 2 * u - 1, 2 * v - 1
    np.testing.assert_allclose(got.point, np.stack([x, y, a * x**2 + b * y**2 + c * x * y], 1), atol=1e-12)
    n = np.stack([-(2 * a * x + c * y), -(2 * b * y + c * x), np.ones_like(x)], 1)
    np.testing.assert_allclose(got.normal, n / np.linalg.norm(n, axis=1, keepdims=True), atol=1e-12)


def test_degree_elevated_and_trivially_rational_patches_agree():
    """The same quadric as a bicubic patch, and as homogeneous points with varying constant weights."""
    P = quadric_graph_patch(0.4, 1.3, -0.8)
    u, v = RNG.random(300), RNG.random(300)
    want = graph_curvature(0.4, 1.3, -0.8, 2 * u - 1, 2 * v - 1)
    cubic = raise_degree(P[None], 3, 3)[0]
    for w in (1.0, 2.5):
        got = evaluate(cubic, u, v, weights=np.full((4, 4), w))
        for name in NAMES:
            np.testing.assert_allclose(got[name], want[name], atol=1e-9, err_msg=name)


def test_rational_sphere_patch():
    """k1 = k2 = 1/R, K = 1/R^2 on a rational sphere piece; the sign follows the normal's side."""
    radius, centre = 2.5, np.array([0.3, -1.0, 2.0])
    Q = rational_sphere_patch(radius, centre)
    u, v = RNG.random(400), RNG.random(400)
    x, w = dehomogenize(Q)
    got = evaluate(x, u, v, weights=w)
    np.testing.assert_allclose(np.linalg.norm(got.point - centre, axis=1), radius, atol=1e-12)
    side = np.sign(np.einsum("md,md->m", got.normal, got.point - centre))  # +1: normal points outward
    assert abs(side.sum()) == side.size  # one orientation over the patch
    for name in ("k1", "k2", "H"):
        np.testing.assert_allclose(got[name], side / radius, atol=1e-9, err_msg=name)
    np.testing.assert_allclose(got.K, 1 / radius**2, atol=1e-9)
    np.testing.assert_allclose(got.kmax, 1 / radius, atol=1e-9)
    # the weights matter: the same points without them are not a sphere
    plain = evaluate(Q[..., :3] / Q[..., 3:], u, v)
    assert np.abs(np.linalg.norm(plain.point - centre, axis=1) - radius).max() > 1e-3


def test_rational_cylinder_patch():
    """Quarter circle (rational quadratic in u) times a line (v): k = 1/r around, 0 along, K = 0."""
    r, s = 0.8, np.sqrt(0.5)
    arc = np.array([[r, 0.0], [r, r], [0.0, r]])
    w = np.array([1.0, s, 1.0])
    Q = np.zeros((3, 3, 4))
    for i in range(3):
        for j in range(3):
            x = np.array([arc[i, 0], arc[i, 1], 1.5 * j / 2])
            Q[i, j] = np.append(x * w[i], w[i])
    u, v = RNG.random(300), RNG.random(300)
    x, w = dehomogenize(Q)
    got = evaluate(x, u, v, weights=w)
    np.testing.assert_allclose(np.hypot(got.point[:, 0], got.point[:, 1]), r, atol=1e-12)
    side = np.sign(np.einsum("md,md->m", got.normal[:, :2], got.point[:, :2]))
    np.testing.assert_allclose(got.K, 0, atol=1e-9)
    np.testing.assert_allclose(got.H, side / (2 * r), atol=1e-9)
    np.testing.assert_allclose(got.kmax, 1 / r, atol=1e-9)
    np.testing.assert_allclose(np.minimum(np.abs(got.k1), np.abs(got.k2)), 0, atol=1e-9)


def golden_groups(name="twisted.json"):
    return load_patch_set(GOLDEN / name).groups


def finite_difference_curvature(points, u, v, h):
    """Curvature from positions only (``bezier.evaluate_patches_at``), with five-point
    central differences (their truncation error vanishes on polynomials of degree <= 3
    in each variable, so what remains is rounding, about 1e-16 / h^2 relative)."""
    w = {-2: 1 / 12, -1: -8 / 12, 1: 8 / 12, 2: -1 / 12}  # first derivative
    w2 = {-2: -1 / 12, -1: 16 / 12, 0: -30 / 12, 1: 16 / 12, 2: -1 / 12}  # second derivative

    def x(i, j):
        return evaluate_patches_at(points, u + i * h, v + j * h)

    xu = sum(c * x(i, 0) for i, c in w.items()) / h
    xv = sum(c * x(0, j) for j, c in w.items()) / h
    xuu = sum(c * x(i, 0) for i, c in w2.items()) / h**2
    xvv = sum(c * x(0, j) for j, c in w2.items()) / h**2
    xuv = sum(a * b * x(i, j) for i, a in w.items() for j, b in w.items()) / h**2
    n = np.cross(xu, xv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    E, F, G = (np.einsum("md,md->m", a, b) for a, b in ((xu, xu), (xu, xv), (xv, xv)))
    L, M, N = (-np.einsum("md,md->m", a, n) for a in (xuu, xuv, xvv))
    det = E * G - F * F
    K = (L * N - M * M) / det
    H = (E * N - 2 * F * M + G * L) / (2 * det)
    return K, H


@pytest.mark.parametrize("name", ["twisted.json", "high_valence.json"])
def test_matches_finite_differences_on_constructed_surfaces(name):
    """On every patch of real c1surf surfaces, at random interior points: exact = FD estimate."""
    for group in golden_groups(name):
        m = group.shape[0] * 8
        index = np.repeat(np.arange(group.shape[0]), 8)
        u, v = 0.05 + 0.9 * RNG.random(m), 0.05 + 0.9 * RNG.random(m)
        exact = patch_curvature(group, u, v, index=index)
        K, H = finite_difference_curvature(group[index], u, v, h=0.01)
        scale = np.maximum(1.0, exact.kmax)
        assert np.all(np.abs(exact.K - K) <= 1e-7 * scale**2)
        assert np.all(np.abs(exact.H - H) <= 1e-7 * scale)
        np.testing.assert_allclose(exact.k1 + exact.k2, 2 * exact.H, atol=1e-9 * scale.max())
        np.testing.assert_allclose(exact.k1 * exact.k2, exact.K, atol=1e-9 * scale.max() ** 2)


def test_invariant_under_rigid_motion_scaling_and_reparametrization():
    group = golden_groups()[1]  # bicubic patches
    m = group.shape[0]
    u, v = RNG.random(m), RNG.random(m)
    base = patch_curvature(group, u, v)
    q, _ = np.linalg.qr(RNG.normal(size=(3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1  # a rotation, not a reflection
    moved = patch_curvature(2.0 * group @ q.T + np.array([1.0, -2.0, 0.5]), u, v)
    for name, power in (("k1", 1), ("k2", 1), ("H", 1), ("kmax", 1), ("K", 2)):
        np.testing.assert_allclose(moved[name] * 2.0**power, base[name], rtol=1e-9, atol=1e-9)
    # swapping u and v flips the normal: H, k1, k2 change sign, K and kmax stay
    swapped = patch_curvature(group.transpose(0, 2, 1, 3), v, u)
    np.testing.assert_allclose(swapped.H, -base.H, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(swapped.k1, -base.k2, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(swapped.K, base.K, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(swapped.kmax, base.kmax, rtol=1e-9, atol=1e-9)


def test_global_patch_index_and_tessellation_vertices():
    """``surface_curvature`` indexes biquadratic then bicubic; a welded tessellation's interior
    vertices carry exactly their patch's curvature, shared ones the mean over their patches."""
    from c1surf.evaluation.tessellate import tessellate_patches
    from c1surf.io.patches.formats import load_patch_set

    patch_set = load_patch_set(GOLDEN / "twisted.json")
    groups = patch_set.groups
    nq = len(groups[0])
    k = np.array([0, nq - 1, nq, nq + len(groups[1]) - 1])
    u, v = np.array([0.1, 0.5, 0.7, 0.9]), np.array([0.3, 0.2, 0.6, 0.05])
    got = surface_curvature(groups, k, u, v)
    for i in range(4):
        g, local = (groups[0], k[i]) if k[i] < nq else (groups[1], k[i] - nq)
        one = patch_curvature(g[local : local + 1], u[i : i + 1], v[i : i + 1])
        assert got.kmax[i] == pytest.approx(one.kmax[0], rel=1e-12)

    tess = tessellate_patches(groups, patch_set.welding(), 5)
    vc = tessellation_curvature(groups, tess.grid, tess.points.shape[0])
    t = np.linspace(0, 1, 5)
    p = nq + 3
    inner = tess.grid[p, 2, 3]
    direct = patch_curvature(groups[1][3:4], t[2:3], t[3:4])
    assert vc["K"][inner] == pytest.approx(direct.K[0], rel=1e-12)
    corner = tess.grid[p, 0, 0]
    owners = [(q, i, j) for q, i, j in zip(*np.nonzero(tess.grid == corner))]
    assert len(owners) >= 3
    values = []
    for q, i, j in owners:
        g, local = (groups[0], q) if q < nq else (groups[1], q - nq)
        values.append(patch_curvature(g[local : local + 1], t[i : i + 1], t[j : j + 1]).H[0])
    assert vc["H"][corner] == pytest.approx(np.mean(values), rel=1e-12)


def test_bernstein_columns_match_the_reference_basis():
    t = RNG.random(50)
    for degree in range(5):
        for derivative in range(4):
            got = np.stack(bernstein_columns(degree, t, derivative), axis=1)
            np.testing.assert_allclose(got, bernstein_basis(degree, t, derivative), atol=1e-12)
