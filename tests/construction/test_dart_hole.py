"""A dart's hole (``construction.stencils.holes.dart``): C0 across the crease spoke, G1 across every other spoke, at the
centre and with the biquadratic patches around, on a cell built by hand (``dart_cell``) whose crease has a
90-degree dihedral angle. Sides are matched from the geometry and measured one by one, and by ``check``'s own
``measure_smoothness``."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.stencils.holes.bicubic import bicubic_hole_coefficients
from c1surf.construction.stencils.holes.dart import dart_hole_coefficients, dart_hole_weights, open_chain_twists
from c1surf.evaluation.smoothness import measure_smoothness

from dart_cell import crease_pair, dart_cell, measure_pairs, shared_sides, uniform_patches

SIZES = range(3, 9)


def measured(cell):
    patches = cell["patches"]
    pairs = shared_sides(patches, 1e-9 * cell["size"])
    gaps, jumps = measure_pairs(patches, pairs)
    crease = np.array([crease_pair(p, cell) for p in pairs])
    return pairs, gaps, jumps, crease


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("noise", [0.0, 0.05])
def test_dart_hole_is_c0_on_its_spoke_and_g1_elsewhere(n, noise):
    cell = dart_cell(n, noise=noise, seed=n)
    pairs, gaps, jumps, crease = measured(cell)
    hole = set(cell["hole"])
    # every side of every hole patch is shared: n spokes, 2 n sides with the biquadratic patches
    hole_sides = [side for pair in pairs for side in pair[:2] if side[0] in hole]
    assert sorted(hole_sides) == sorted((p, s) for p in hole for s in range(4))
    assert gaps.max() < 1e-12 * cell["size"]
    # the crease: its spoke and the biquadratic pieces along it, one patch on each side
    spoke = np.array([a[0] in hole and b[0] in hole for a, b, _ in pairs])
    assert (crease & spoke).sum() == 1 and crease.sum() == 1 + (cell["G"].shape[1] - 2)
    away = jumps[crease & spoke][0][: jumps.shape[1] // 2]  # from M to the spoke's middle
    assert away.max() > 0.05
    assert jumps[crease & ~spoke].min() > 0.05  # the seam outside stays sharp
    assert jumps[crease & spoke][0][-1] < 1e-10  # G1 at the centre: one tangent plane
    assert jumps[~crease].max() < 1e-10


@pytest.mark.parametrize("n", SIZES)
def test_check_measures_the_dart_hole(n):
    """``measure_smoothness`` (check's measurement) with the crease pieces listed: G1 elsewhere, C0 on them."""
    cell = dart_cell(n, noise=0.05, seed=10 + n)
    pairs, _, _, crease = measured(cell)
    crease_sides = np.array([[4 * a[0] + a[1], 4 * b[0] + b[1]] for (a, b, _), c in zip(pairs, crease) if c])
    report = measure_smoothness([uniform_patches(cell["patches"])], crease_sides=crease_sides)
    assert report.shared_edges == len(pairs) and report.overshared_edges == 0
    assert report.crease_edges == len(crease_sides) and report.unpaired_crease_sides == 0
    assert report.max_normal_jump < 1e-10
    assert report.relative_gap < 1e-12 and report.relative_crease_gap < 1e-12


@pytest.mark.parametrize("shape", [{"alpha": 0.6}, {"beta": 1.0}, {"tangent_rule": "corners"}])
@pytest.mark.parametrize("n", [3, 6])
def test_dart_hole_shape_parameters(n, shape):
    cell = dart_cell(n, noise=0.05, seed=3, **shape)
    _, gaps, jumps, crease = measured(cell)
    assert gaps.max() < 1e-12 * cell["size"] and jumps[~crease].max() < 1e-10


@pytest.mark.parametrize("n", SIZES)
def test_dart_hole_without_a_crease_is_a3(n):
    """Views that are the real points across (crease points the midpoints) and a ring with A1's alternating
    sum zero: the dart's hole is the paper's hole (its twists satisfy the closed chain, so least squares
    returns them)."""
    rng = np.random.default_rng(n)
    A, B1, B2, C = rng.standard_normal((4, n, 3))
    if n % 2 == 0:  # A1's perturbation
        sign = (-1.0) ** np.arange(n)
        E = (np.einsum("i,id->d", -sign, B1) + np.einsum("i,id->d", sign, B2)) / (-2 * n)
        B1, B2 = B1 - sign[:, None] * E, B2 + sign[:, None] * E
    dart = dart_hole_coefficients(A, B1, B2, C, (C[0], B1[0], C[n - 1], B2[n - 1]))
    np.testing.assert_allclose(dart, bicubic_hole_coefficients(A, B1, B2, C), atol=1e-12)


@pytest.mark.parametrize("n", SIZES)
def test_dart_hole_weights_are_the_rule(n):
    """The (16 n, 4 n + 4) weights give the coefficients; every row sums to 1 (affine: translations commute)."""
    rng = np.random.default_rng(n)
    points = rng.standard_normal((4 * n + 4, 3))
    W = dart_hole_weights(n)
    A, B1, B2, C = (points[k * n : (k + 1) * n] for k in range(4))
    direct = dart_hole_coefficients(A, B1, B2, C, tuple(points[4 * n :]))
    np.testing.assert_allclose(W @ points, direct.reshape(16 * n, 3), atol=1e-12)
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-13)


def test_open_chain_twists():
    rng = np.random.default_rng(1)
    for n in SIZES:
        E, target = rng.standard_normal((2, n, 3))
        P = open_chain_twists(E, target)
        np.testing.assert_allclose(P[:-1] + P[1:], 2 * E[:-1], atol=1e-12)
        h = (-1.0) ** np.arange(n)
        assert abs(np.einsum("i,id->d", h, P - target)).max() < 1e-12  # the nearest: residual orthogonal to h
