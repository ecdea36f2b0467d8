"""Welding by position (mesh/weld.py): triangle soups become surfaces, touching surfaces stay apart."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.surface import Surface
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.mesh.weld import coincident_representatives, overshared_vertices, weld_vertices

MAX_JUMP = 1e-10  # radians, as in test_open_and_repair

CUBE_QUADS = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])


def cube_points(offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(8, 3) corners of the unit cube moved by ``offset``; vertex 4x + 2y + z."""
    return np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) + offset


def soup(points: np.ndarray, quads: np.ndarray):
    """Every quad as two triangles with vertices of their own (STL): (points (6Q, 3), sizes (2Q,), vertices (6Q,))."""
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return points[triangles.ravel()], np.full(len(triangles), 3), np.arange(triangles.size)


def two_cube_soups(offset):
    """The soups of the unit cube and of the unit cube moved by ``offset``, one after the other."""
    pa, sa, va = soup(cube_points(), CUBE_QUADS)
    pb, sb, vb = soup(cube_points(offset), CUBE_QUADS)
    return np.r_[pa, pb], np.r_[sa, sb], np.r_[va, vb + len(pa)]


def edge_face_counts(sizes, vertices) -> np.ndarray:
    """How many faces each undirected edge lies in."""
    following = np.arange(vertices.size) + 1
    ends = np.cumsum(sizes) - 1
    following[ends] = ends - sizes + 1
    edges = np.sort(np.c_[vertices, vertices[following]], axis=1)
    return np.unique(edges, axis=0, return_counts=True)[1]


def assert_closed_g1(surface: Surface):
    report = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert report.boundary_edges == 0 and report.overshared_edges == 0
    assert report.max_normal_jump < MAX_JUMP, report


def test_a_cube_soup_welds_into_the_closed_cube():
    points, sizes, vertices = soup(cube_points(), CUBE_QUADS)
    new_sizes, new_vertices, kept, report = weld_vertices(points, sizes, vertices)
    assert kept.all() and np.array_equal(new_sizes, sizes)
    assert np.unique(new_vertices).size == 8 and report["welded_vertices"] == 36 - 8
    assert report["unwelded_vertices"] == 0 and report["dropped_faces"] == 0
    assert np.all(edge_face_counts(new_sizes, new_vertices) == 2)
    # faces refer to the lowest-numbered vertex at each position: the file's numbering, points as read
    assert np.array_equal(points[new_vertices], points[vertices])
    surface = Surface(new_sizes, new_vertices, points)
    assert surface.repairs["components"] == 1 and surface.repairs["boundary_edges"] == 0
    assert_closed_g1(surface)


def test_without_welding_a_soup_is_separate_triangles():
    points, sizes, vertices = soup(cube_points(), CUBE_QUADS)
    surface = Surface(sizes, vertices, points)
    assert surface.repairs["components"] == 12 and surface.repairs["boundary_edges"] == 36


def test_two_cubes_sharing_an_edge_stay_two_closed_cubes():
    points, sizes, vertices = two_cube_soups((1.0, 1.0, 0.0))  # the edge x = y = 1 is in both
    assert overshared_vertices(sizes, coincident_representatives(points, vertices)[vertices], len(points)).sum() == 2
    new_sizes, new_vertices, kept, report = weld_vertices(points, sizes, vertices)
    assert kept.all() and new_sizes.size == 24
    assert np.all(edge_face_counts(new_sizes, new_vertices) == 2)  # no edge in 3 or 4 faces
    assert np.unique(new_vertices).size == 16 and report["unwelded_vertices"] == 2
    surface = Surface(new_sizes, new_vertices, points)
    assert surface.repairs["components"] == 2 and surface.repairs["split_vertices"] == 0
    assert surface.repairs["boundary_edges"] == 0
    assert_closed_g1(surface)


def test_two_cubes_sharing_a_corner_become_a_pinch_the_repair_splits():
    points, sizes, vertices = two_cube_soups((1.0, 1.0, 1.0))
    new_sizes, new_vertices, kept, report = weld_vertices(points, sizes, vertices)
    assert np.unique(new_vertices).size == 15 and report["unwelded_vertices"] == 0  # one vertex in both cubes
    assert np.all(edge_face_counts(new_sizes, new_vertices) == 2)
    surface = Surface(new_sizes, new_vertices, points)
    assert surface.repairs["split_vertices"] == 1 and surface.repairs["components"] == 2
    assert surface.n_patches == 2 * Surface(*soup_welded_cube()).n_patches
    assert_closed_g1(surface)


def soup_welded_cube():
    points, sizes, vertices = soup(cube_points(), CUBE_QUADS)
    new_sizes, new_vertices, _, _ = weld_vertices(points, sizes, vertices)
    return new_sizes, new_vertices, points


def test_indexed_cubes_sharing_an_edge_are_not_glued():
    # two quad cubes, each with its own 8 vertices (as OBJ or PLY files have them), sharing the edge x = y = 1
    points = np.r_[cube_points(), cube_points((1.0, 1.0, 0.0))]
    sizes = np.full(12, 4)
    vertices = np.r_[CUBE_QUADS.ravel(), CUBE_QUADS.ravel() + 8]
    new_sizes, new_vertices, _, report = weld_vertices(points, sizes, vertices)
    assert np.array_equal(new_vertices, vertices) and report["welded_vertices"] == 0
    assert report["unwelded_vertices"] == 2


def test_a_tolerance_welds_near_coincident_vertices():
    points, sizes, vertices = soup(cube_points(), CUBE_QUADS)
    jittered = points + np.random.default_rng(1).uniform(-1e-9, 1e-9, points.shape)
    exact = weld_vertices(jittered, sizes, vertices)
    assert exact[3]["welded_vertices"] == 0  # no two positions are equal
    near_sizes, near_vertices, _, report = weld_vertices(jittered, sizes, vertices, tolerance=1e-6)
    assert report["welded_vertices"] == 28 and np.unique(near_vertices).size == 8
    assert_closed_g1(Surface(near_sizes, near_vertices, jittered))
    # a tolerance below the distances welds nothing
    assert weld_vertices(jittered, sizes, vertices, tolerance=1e-12)[3]["welded_vertices"] == 0


def test_keys_keep_vertices_with_different_data_apart():
    points, sizes, vertices = soup(cube_points(), CUBE_QUADS)
    keys = np.zeros((len(points), 2))
    keys[:3] = [0.5, 0.25]  # the first triangle's corners have texture coordinates of their own
    representative = coincident_representatives(points, vertices, keys=keys)
    assert np.all(representative[:3] == np.arange(3))
    assert np.unique(representative).size == 8 + 3
    nan_keys = np.full((len(points), 1), np.nan)  # NaN (no data) equals NaN
    assert np.unique(coincident_representatives(points, vertices, keys=nan_keys)).size == 8


def test_faces_welding_collapses_are_dropped():
    points, sizes, vertices = soup(cube_points(), CUBE_QUADS)
    sliver = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])  # a zero-area triangle, as STL files have
    points = np.r_[points, sliver]
    sizes, vertices = np.r_[sizes, 3], np.r_[vertices, len(points) - 3 + np.arange(3)]
    new_sizes, new_vertices, kept, report = weld_vertices(points, sizes, vertices)
    assert report["dropped_faces"] == 1 and kept.sum() == 12 and not kept[-1]
    assert np.all(edge_face_counts(new_sizes, new_vertices) == 2)


def test_a_face_would_visit_a_vertex_twice_is_not_welded_there():
    # a quad whose opposite corners 0 and 2 coincide (a bow tie folded flat): welding them would repeat a vertex
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 0, 0], [0, 1, 0]])
    new_sizes, new_vertices, kept, report = weld_vertices(points, np.array([4]), np.arange(4))
    assert np.array_equal(new_vertices, np.arange(4)) and kept.all()
    assert report["welded_vertices"] == 0


@pytest.mark.parametrize("offset", [(1.0, 1.0, 0.0), (1.0, 1.0, 1.0), (3.0, 0.0, 0.0)])
def test_welding_keeps_the_face_count_of_touching_cubes(offset):
    points, sizes, vertices = two_cube_soups(offset)
    new_sizes, _, kept, _ = weld_vertices(points, sizes, vertices)
    assert kept.all() and np.array_equal(new_sizes, sizes)


def test_coincident_representatives_skip_the_sort_only_when_no_two_vertices_coincide(monkeypatch):
    """``weld._may_coincide`` says False only when no two used rows are equal (-0.0 equal to 0.0): the
    representatives are those of the lexicographic sort alone."""
    from c1surf.mesh import weld

    rng = np.random.default_rng(3)
    for _ in range(200):
        n = int(rng.integers(2, 40))
        points = rng.integers(-3, 3, (n, 3)).astype(float)  # a small grid: repeats happen
        points[rng.random((n, 3)) < 0.2] *= -1.0  # and signed zeros
        faces = rng.integers(0, n, 3 * n)
        with monkeypatch.context() as patch:
            patch.setattr(weld, "_may_coincide", lambda rows: True)
            expected = weld.coincident_representatives(points, faces)
        assert np.array_equal(weld.coincident_representatives(points, faces), expected)
        distinct = np.unique(points[np.unique(faces)] + 0.0, axis=0).shape[0] == np.unique(faces).size
        assert weld._may_coincide(points[np.unique(faces)]) or distinct
