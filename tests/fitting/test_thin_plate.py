"""The thin-plate energy (c1surf.fitting.thin_plate): the exact integral, its null space, the stencil's form."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.surface import Surface
from c1surf.evaluation.bezier import evaluate_patches
from c1surf.fitting.thin_plate import gram_matrix, patch_weights, thin_plate_energy, thin_plate_matrix
from c1surf.io.meshes.obj import read_obj

from conftest import SAMPLES


def _quadrature_energy(patches: np.ndarray, order: int = 10) -> np.ndarray:
    """(p,) float: the integral of |S_uu|^2 + 2 |S_uv|^2 + |S_vv|^2 over [0, 1]^2 by a tensor Gauss-Legendre rule of
    ``order`` points a side (exact for these polynomials), the derivatives from the Bernstein evaluator."""
    x, w = np.polynomial.legendre.leggauss(order)
    t, w = (x + 1) / 2, w / 2
    weight = np.outer(w, w)
    total = np.zeros(patches.shape[0])
    for du, dv, factor in ((2, 0, 1.0), (1, 1, 2.0), (0, 2, 1.0)):
        d = evaluate_patches(patches, t, t, du, dv)  # (p, order, order, 3)
        total += factor * np.einsum("pijd,pijd,ij->p", d, d, weight)
    return total


@pytest.mark.parametrize("degree", [2, 3])
def test_gram_matrix_is_the_exact_integral(degree):
    """Random patches: c^T G c against a dense Gauss quadrature of the second derivatives."""
    patches = np.random.default_rng(degree).normal(size=(6, degree + 1, degree + 1, 3))
    empty = np.zeros((0, 5 - degree, 5 - degree, 3))
    energy = thin_plate_energy(*((patches, empty) if degree == 2 else (empty, patches)))
    assert np.allclose(energy, _quadrature_energy(patches), rtol=1e-13, atol=0)
    G = gram_matrix(degree)
    assert np.allclose(G, G.T, rtol=0, atol=0) and np.linalg.eigvalsh(G).min() > -1e-12


def test_affine_and_bilinear_patches_have_no_energy():
    """The null space: a plane (affine coefficients) and the twist u v have zero second derivatives in uu and vv,
    and only the twist has S_uv: its energy is 2 |c|^2 exactly."""
    for degree in (2, 3):
        t = np.arange(degree + 1) / degree
        u, v = np.meshgrid(t, t, indexing="ij")
        plane = np.stack([u, v, 0.3 * u - 0.7 * v + 2.0], axis=-1)[None]  # coefficients of an affine map
        assert abs(thin_plate_energy(plane[:, :3, :3] if degree == 2 else np.zeros((0, 3, 3, 3)),
                                     plane if degree == 3 else np.zeros((0, 4, 4, 3)))[0]) < 1e-12
        twist = np.zeros((1, degree + 1, degree + 1, 3))
        twist[0, :, :, 2] = u * v  # z = u v (Bernstein coefficients of a bilinear function: its values at i/n, j/n)
        pair = (twist, np.zeros((0, 4, 4, 3))) if degree == 2 else (np.zeros((0, 3, 3, 3)), twist)
        assert thin_plate_energy(*pair)[0] == pytest.approx(2.0, rel=1e-13)


@pytest.mark.parametrize("name", ["cube.obj", "dodecahedron.obj"])
def test_the_stencil_form_is_the_surface_energy(name):
    """X^T K X (the sparse form through Surface.stencil()) equals the sum of the patches' energies; on affine
    control points (every patch a piece of one plane) it vanishes."""
    mesh = read_obj(str(SAMPLES / name))
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points)
    n_quad, n_cubic = surface.biquadratic.shape[0], surface.bicubic.shape[0]
    weights = patch_weights(surface.biquadratic, surface.bicubic)
    K = thin_plate_matrix(surface.stencil(), n_quad, n_cubic, weights)
    assert K.shape == (mesh.points.shape[0],) * 2 and abs(K - K.T).max() == 0
    X = mesh.points
    form = float(np.einsum("vc,vc->", X, K @ X))
    per_patch = thin_plate_energy(surface.biquadratic, surface.bicubic, weights)
    assert form == pytest.approx(per_patch.sum(), rel=1e-11)
    assert form == pytest.approx(float(np.sum(weights * _quadrature_energy_all(surface))), rel=1e-11)


def test_a_plane_has_no_energy():
    """Control points on an affine map of a regular grid (a tilted plane): every patch at least one control edge
    inside the grid's boundary is a piece of that affine map (linear precision), so its energy vanishes, and the
    sparse form restricted to those patches vanishes too; the boundary's patches (ghost layer) do bend."""
    n = 5
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    index = lambda a, b: a * (n + 1) + b  # noqa: E731
    quads = np.array([[index(a, b), index(a + 1, b), index(a + 1, b + 1), index(a, b + 1)]
                      for a in range(n) for b in range(n)])
    linear = np.array([[1.0, 0.2, 0.3], [0.4, 1.1, -0.5]])
    X = np.stack([i.ravel(), j.ravel()], axis=1) @ linear + np.array([1.0, 2.0, 3.0])
    surface = Surface(np.full(len(quads), 4), quads.ravel(), X)
    inside = []
    for patches in (surface.biquadratic, surface.bicubic):  # grid coordinates of every coefficient
        ij = (patches.reshape(patches.shape[0], -1, 3)[..., :2] - np.array([1.0, 2.0])) @ np.linalg.inv(linear[:, :2])
        inside.append(((ij >= 1) & (ij <= n - 1)).all(axis=(1, 2)))
    inside = np.concatenate(inside)
    assert inside.sum() >= 100
    energy = thin_plate_energy(surface.biquadratic, surface.bicubic)
    assert np.abs(energy[inside]).max() < 1e-12 * n ** 2 and energy.max() > 1e-3
    K = thin_plate_matrix(surface.stencil(), surface.biquadratic.shape[0], surface.bicubic.shape[0],
                          inside.astype(float))
    assert abs(float(np.einsum("vc,vc->", X, K @ X))) < 1e-12 * n ** 2 * inside.sum()


def _quadrature_energy_all(surface: Surface) -> np.ndarray:
    return np.concatenate([_quadrature_energy(surface.biquadratic), _quadrature_energy(surface.bicubic)])
