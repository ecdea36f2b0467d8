"""One side numbering (adjacency.SIDE_CORNERS) and one geometric side matcher, checked against the
construction's bookkeeping: polynomial and rational surfaces, open and closed."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.surface import Surface
from c1surf.evaluation.adjacency import (SIDE_CORNERS, adjacency_from_geometry, corner_points, match_patch_sides,
                                         patch_adjacency, side_offsets, side_polygons)
from c1surf.evaluation.bezier import raise_degree
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.io.meshes.obj import read_obj

from conftest import SAMPLES, grid, surface_of


@pytest.mark.parametrize("d", [2, 3])
def test_side_tables_agree(d):
    """side_offsets (flat) and side_polygons (slices) name the same control points, and each
    polygon runs from corner SIDE_CORNERS[s, 0] to corner SIDE_CORNERS[s, 1]."""
    patch = np.arange((d + 1) ** 2).reshape(1, d + 1, d + 1)
    offsets = side_offsets(d)
    corners = corner_points(patch)[0]
    for s, polygon in enumerate(side_polygons(patch)):
        assert np.array_equal(offsets[s, 0], polygon[0])
        assert polygon[0, 0] == corners[SIDE_CORNERS[s, 0]] and polygon[0, -1] == corners[SIDE_CORNERS[s, 1]]
    # the next row lies one step inwards from the polygon, point by point
    i, j = np.divmod(offsets[:, 1], d + 1)
    pi, pj = np.divmod(offsets[:, 0], d + 1)
    assert np.array_equal(np.abs(i - pi) + np.abs(j - pj), np.ones((4, d + 1), dtype=int))
    assert np.all(j[0] == 1) and np.all(i[1] == d - 1) and np.all(j[2] == d - 1) and np.all(i[3] == 1)


def rational_twisted():
    mesh = read_obj(SAMPLES / "twisted.obj")
    weights = np.random.default_rng(3).uniform(0.5, 2.0, mesh.n_vertices)
    return Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, weights=weights)


@pytest.mark.parametrize("make", [lambda: surface_of(SAMPLES / "twisted.obj"), lambda: surface_of(SAMPLES / "cube.obj"),
                                  rational_twisted, lambda: Surface(*grid(3, lambda x, y: 0.2 * x * y))])
def test_matcher_finds_the_construction_adjacency(make):
    """Pairs, directions and boundary sides found from the geometry are the construction's."""
    surface = make()
    groups, weights = [surface.biquadratic, surface.bicubic], surface.patch_weights
    adjacency = patch_adjacency(surface.refined, surface.frames)
    assert adjacency_from_geometry(groups, weights=weights) == adjacency
    cubic = np.concatenate([raise_degree(g[..., :3], 3, 3) for g in groups])
    sides = match_patch_sides(groups, 1e-9 * np.ptp(cubic.reshape(-1, 3), axis=0).max(), weights)
    across = adjacency.neighbours().reshape(-1, 2)
    first, second = sides.first, sides.second
    assert np.array_equal(across[first, 0] * 4 + across[first, 1], second)
    flat_reversed = adjacency.reversed.ravel()
    assert np.array_equal(sides.reversed, flat_reversed[first] != flat_reversed[second])
    assert np.array_equal(np.sort(sides.lone), np.flatnonzero(across[:, 0] < 0))
    assert sides.overshared == 0
    report = measure_smoothness(groups, weights=weights)
    assert report.shared_edges == first.size and report.boundary_edges == sides.lone.size


def test_matcher_without_patches():
    sides = match_patch_sides([np.zeros((0, 3, 3, 3))], 1e-9)
    assert sides.first.size == sides.second.size == sides.lone.size == sides.overshared == 0
    assert adjacency_from_geometry([np.zeros((0, 4, 4, 3))]).n_patches == 0


@pytest.mark.parametrize("name", ["cube.obj", "twisted.obj", "high_valence.obj", "torus.obj", "double_torus.obj"])
def test_the_matching_tolerance_is_the_relative_one_on_ordinary_surfaces(name):
    """``sides.matching.matching_tolerance`` lowers the tolerance only where patches are small beside it (a cell
    of thousands of sides): on the sample meshes it is 1e-9 of the diagonal, unchanged; patches 1e-4 wide beside
    one 1e5 wide get a thousandth of their side, never less than 2^-40 of the largest coordinate."""
    from c1surf.evaluation.sides.matching import matching_tolerance

    surface = surface_of(SAMPLES / name)
    corners = np.concatenate([corner_points(g) for g in (surface.biquadratic, surface.bicubic) if len(g)])
    tolerance = 1e-9 * float(np.linalg.norm(np.ptp(corners.reshape(-1, 3), axis=0)))
    assert matching_tolerance(corners, tolerance) == tolerance
    # 10 x 10 patches 1e-4 wide, and one 1e5 wide: a thousandth of 1e-4, above the floor 2^-40 * 1e5 = 9.1e-8
    x, y = np.meshgrid(np.arange(10) * 1e-4, np.arange(10) * 1e-4, indexing="ij")
    small = np.stack([np.stack([x, y, 0 * x], -1) + np.array(offset) * 1e-4
                      for offset in ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0))], axis=2).reshape(-1, 4, 3)
    big = np.array([[[0.0, 0, 0], [1e5, 0, 0], [1e5, 1e5, 0], [0, 1e5, 0]]])
    corners = np.concatenate([small, big])
    assert matching_tolerance(corners, 1e-9 * 1e5 * np.sqrt(2)) == pytest.approx(1e-7, rel=1e-9)
    halved = np.concatenate([small * 0.5, big])  # a thousandth of 5e-5 is below the floor: the floor
    assert matching_tolerance(halved, 1e-9 * 1e5 * np.sqrt(2)) == pytest.approx(2.0**-40 * 1e5, rel=1e-9)
