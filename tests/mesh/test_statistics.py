"""mesh.statistics on small meshes whose counts are known by hand."""
from __future__ import annotations

import numpy as np

from c1surf.mesh.statistics import degenerate_faces, mesh_statistics

from conftest import grid, polygon_mesh

CUBE = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]


def test_two_cubes_touching_at_a_vertex_are_two_spheres_and_one_pinch():
    second = [[v + 7 if v else 6 for v in f] for f in CUBE]  # vertex 0 of the second cube is vertex 6 of the first
    sizes, vertices, _ = polygon_mesh(CUBE + second, np.zeros((15, 3)))
    stats = mesh_statistics(sizes, vertices, 16)  # vertex 15 unused
    assert stats.pinched_vertices == 1 and stats.unused_vertices == 1 and stats.boundary_edges == 0
    c = stats.components
    assert c.vertices.tolist() == [8, 8] and c.euler_characteristic.tolist() == [2, 2] and c.genus.tolist() == [0, 0]
    assert stats.interior_valences.tolist() == [[3, 14], [6, 1]]


def test_open_grid_and_a_flipped_face():
    sizes, vertices, _ = grid(3)
    stats = mesh_statistics(sizes, vertices, 16)
    assert (stats.boundary_edges, stats.boundary_loops, stats.n_edges) == (12, 1, 24)
    assert stats.boundary_valences.tolist() == [[1, 4], [2, 8]] and stats.components.genus.tolist() == [0]
    vertices[:4] = vertices[:4][::-1]  # one face reversed: still orientable (the repair flips it)
    assert mesh_statistics(sizes, vertices, 16).components.orientable.tolist() == [True]


def test_degenerate_faces_are_those_repeating_a_vertex():
    sizes = np.array([4, 4, 3, 4])
    vertices = np.array([0, 1, 2, 3, 0, 1, 1, 2, 4, 5, 6, 0, 1, 0, 2])
    assert degenerate_faces(sizes, vertices).tolist() == [1, 3]
