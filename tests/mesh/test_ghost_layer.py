"""The ghost layer's corner rule: convex or reflex, read from explicit points, and followed by update_points."""
from __future__ import annotations

import numpy as np

from c1surf.construction.surface import Surface
from c1surf.mesh.ghost_layer import add_ghost_layer, ghost_points_matrix, reflex_corners
from c1surf.mesh.repair import prepare_topology

from conftest import single_polygon

# A U-shaped octagon (one face, every vertex a single-face corner): the two corners of the notch
# are reflex. Numbered so that the face's half-edge order is not the vertex order.
U_SHAPE = np.array([[0, 0, 0], [3, 0, 0], [3, 2, 0], [2, 2, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)
RENUMBER = np.array([7, 6, 3, 5, 2, 1, 4, 0])  # new index of the k-th corner along the face


def u_shape():
    points = np.empty_like(U_SHAPE)
    points[RENUMBER] = U_SHAPE
    return np.array([8]), RENUMBER.copy(), points


def test_reflex_corners_complete_the_parallelogram_and_convex_ones_reflect_the_centroid():
    sizes, face, points = u_shape()
    mesh = prepare_topology(sizes, face, len(points))[0]
    layer = add_ghost_layer(mesh)
    reflex = reflex_corners(layer, points)
    notch = {int(RENUMBER[4]), int(RENUMBER[5])}
    assert set(layer.corners[reflex].tolist()) == notch and layer.corners.size == 8
    ghosts = ghost_points_matrix(layer, reflex) @ points
    np.testing.assert_array_equal(ghosts[:8], points)
    centroid = points.mean(axis=0)
    for k in range(8):  # corner k of the face, x before it, y after it
        a, x, y = RENUMBER[k], RENUMBER[k - 1], RENUMBER[(k + 1) % 8]
        ghost = ghosts[layer.ghost[a]]
        expected = points[x] + points[y] - points[a] if a in notch else 2 * points[a] - centroid
        np.testing.assert_allclose(ghost, expected, atol=1e-15)


def test_an_open_surface_moves_with_its_points():
    """Translating the input translates the surface (also at reflex corners)."""
    sizes, face, points = u_shape()
    shift = np.array([10.0, -3.0, 2.0])
    here, there = Surface(sizes, face, points), Surface(sizes, face, points + shift)
    np.testing.assert_allclose(there.biquadratic, here.biquadratic + shift, atol=1e-13)
    np.testing.assert_allclose(there.bicubic, here.bicubic + shift, atol=1e-13)


def test_update_points_classifies_the_corners_again():
    """A corner that turns from convex to reflex (and back) gives what a fresh Surface gives."""
    sizes, vertices, convex = single_polygon(6)
    dented = convex.copy()
    dented[2, :2] *= 0.2  # pushed towards the centre: reflex
    surface = Surface(sizes, vertices, convex)
    place = surface.stage("place")
    assert not place.reflex.any()
    others = list(surface.stages[1:])
    stencil = surface.stencil()
    for points, reflex in [(dented, 1), (convex, 0), (dented, 1)]:
        surface.update_points(points)
        fresh = Surface(sizes, vertices, points)
        assert place.reflex.sum() == reflex == fresh.stage("place").reflex.sum()
        np.testing.assert_allclose(surface.biquadratic, fresh.biquadratic, atol=1e-14)
        np.testing.assert_allclose(surface.bicubic, fresh.bicubic, atol=1e-14)
        np.testing.assert_allclose(surface.stencil() @ points, fresh.stencil() @ points, atol=1e-14)
    assert surface.stencil() is not stencil  # rebuilt for the new classification
    assert surface.stages[1:] == others  # only the placement stage followed the points
    # moving the points without changing the classification keeps the stencil
    stencil = surface.stencil()
    surface.update_points(dented * 1.01)
    assert surface.stencil() is stencil
