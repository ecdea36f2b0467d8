"""mesh.points.geometry_checks: coordinates out of the construction's range and meshes spanning no surface, refused
with the reason; everything else passes (issue 30)."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.mesh.points.geometry_checks import (MAX_COORDINATE, MAX_SIZE, MIN_SIZE, GeometryError, check_coordinate_range,
                                         check_geometry, check_spans_surface)

CUBE = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


@pytest.mark.parametrize("scale", [1.0, 1e-49, 1e49, 3.7, 1e-20, 1e20])
def test_cubes_within_range_pass(scale):
    check_geometry(CUBE * scale)


@pytest.mark.parametrize("scale,words", [(1e308, "coordinates reach 1e+308"), (1e80, "beyond 1e+50"),
                                         (1e-300, "underflow"), (1e-60, "underflow")])
def test_cubes_out_of_range_say_the_scale_that_works(scale, words):
    with pytest.raises(GeometryError) as info:
        check_geometry(CUBE * scale)
    message = info.value.message
    assert words in message and "scale" in message
    suggested = float(message.split("by ")[1].split()[0])  # the factor named brings the cube to about unit size
    scaled = CUBE * scale * suggested
    assert 0.1 < np.linalg.norm(np.ptp(scaled, axis=0)) < 100
    check_geometry(scaled)


def test_limits_are_ordered():
    assert 0 < MIN_SIZE < 1 < MAX_SIZE and MAX_COORDINATE >= MAX_SIZE


def test_non_finite_coordinates():
    for bad in (np.nan, np.inf, -np.inf):
        points = CUBE.copy()
        points[3, 1] = bad
        with pytest.raises(GeometryError, match="NaN or infinite"):
            check_coordinate_range(points)


@pytest.mark.parametrize("offset", [0.0, 1e6, -1e12])
def test_points_on_a_line(offset):
    t = np.linspace(-2, 5, 11)[:, None]
    points = offset + t * np.array([[1.0, -2.0, 0.5]])
    with pytest.raises(GeometryError, match="lie on one line"):
        check_spans_surface(points)
    points[4] += [0.0, 0.0, 1e-3]  # one vertex off the line: a surface
    check_spans_surface(points)


def test_points_at_one_point_also_after_rounding():
    with pytest.raises(GeometryError, match="at one point"):
        check_spans_surface(np.full((5, 3), 2.5))
    with pytest.raises(GeometryError, match="at one point"):
        check_spans_surface(1.0 + CUBE * 1e-30)  # 1 + 1e-30 == 1


def test_only_the_used_vertices_count():
    stray = np.vstack([CUBE, [[1e300, 0, 0]]])  # a vertex no face uses
    check_geometry(stray, used=np.arange(8))
    with pytest.raises(GeometryError):
        check_geometry(stray)
    line = np.array([[0.0, 0, 0], [1, 1, 1], [2, 2, 2], [5, 0, 0]])
    with pytest.raises(GeometryError, match="one line"):
        check_geometry(line, used=np.array([0, 1, 2, 0]))
    check_geometry(line, used=np.array([0, 1, 3]))


def test_a_thin_but_real_surface_passes():
    strip = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1e-9, 0], [1, 1e-9, 0]])
    check_spans_surface(strip)


def test_large_point_sets_by_chunks():
    rng = np.random.default_rng(3)
    t = rng.random((1_200_000, 1))  # two chunks
    points = t * np.array([[2.0, 1.0, -1.0]])
    with pytest.raises(GeometryError, match="one line"):
        check_spans_surface(points)
    points[1_100_123, 2] += 1e-6  # in the second
    check_spans_surface(points)
