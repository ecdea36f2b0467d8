"""The fit's extra samples on a scan's facets (``scan_fit.fitting_samples``): lifted onto the smooth surface."""
from __future__ import annotations

import numpy as np
import trimesh

from c1surf.fitting.scan_fit import SAMPLES_PER_FACE, curved_midpoints, fitting_samples
from c1surf.fitting.system import vertex_normals


def test_curved_midpoints_land_on_a_sphere_to_second_order():
    """On a unit sphere with its exact normals, flat midpoints lie a sagitta c^2 / 8 inside; the lifted ones
    are nearer by orders of c (the error falls by about 16 when the edges halve: fourth order)."""
    errors = []
    for level in (2, 3):
        sphere = trimesh.creation.icosphere(subdivisions=level)
        points = np.asarray(sphere.vertices)
        edges = np.asarray(sphere.edges_unique)
        c = np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1)
        flat = np.abs(np.linalg.norm(0.5 * (points[edges[:, 0]] + points[edges[:, 1]]), axis=1) - 1)
        lifted = np.abs(np.linalg.norm(curved_midpoints(points, points, edges), axis=1) - 1)
        assert np.allclose(flat, c**2 / 8, rtol=0.02)
        assert np.all(lifted < 0.05 * flat)
        errors.append(lifted.max())
    assert errors[1] < errors[0] / 10


def test_fitting_samples_keep_the_scan_and_add_midpoints_until_enough():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    points, triangles = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    same, same_triangles = fitting_samples(points, triangles, points.shape[0] // SAMPLES_PER_FACE)
    assert same is points and same_triangles is triangles  # enough samples already: the scan as it is
    samples, sample_triangles = fitting_samples(points, triangles, 10 * points.shape[0])  # at most two rounds
    assert np.array_equal(samples[: points.shape[0]], points)
    assert sample_triangles.shape[0] == 16 * triangles.shape[0]
    assert samples.shape[0] == sample_triangles.shape[0] // 2 + 2  # a closed genus-0 mesh: every edge split once
    radius = np.linalg.norm(samples, axis=1)
    assert np.abs(radius - 1).max() < 0.2 * np.abs(np.linalg.norm(points[triangles].mean(axis=1), axis=1) - 1).max()
    # the refined mesh is closed and consistently oriented, as the scan was
    refined = trimesh.Trimesh(samples, sample_triangles, process=False)
    assert refined.is_watertight and refined.is_winding_consistent
    assert np.all(np.einsum("ij,ij->i", vertex_normals(samples, sample_triangles), samples) > 0)
