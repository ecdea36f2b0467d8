"""``mesh.topology_counts``: components (edge-connected), Euler characteristic and rims of synthetic meshes and of
two shared scans whose counts ../shared/scans/MANIFEST.md states."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from c1surf.api import read_scan
from c1surf.mesh.topology_counts import TopologyCounts, compare_topology, topology_counts

SCANS = Path(__file__).resolve().parents[2].parent / "shared" / "scans"


def counts_of(mesh: trimesh.Trimesh):
    return topology_counts(np.full(len(mesh.faces), 3), mesh.faces.ravel(), len(mesh.vertices))


def grid_disc(n: int = 5):
    """An open n x n grid of quads: a disc."""
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], axis=-1).reshape(-1, 4)
    return np.full(len(quads), 4), quads.ravel(), (n + 1) ** 2


def test_a_torus_has_euler_characteristic_zero_and_no_rim():
    c = counts_of(trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12))
    assert (c.components, c.euler_characteristic, c.rims) == (1, 0, 0)


def test_a_disc_of_quads_has_one_rim():
    c = topology_counts(*grid_disc())
    assert (c.components, c.euler_characteristic, c.rims) == (1, 1, 1)
    assert c.component_faces == (25,)


def test_two_spheres_are_two_components():
    big, small = trimesh.creation.icosphere(3), trimesh.creation.icosphere(1, radius=0.1)
    small.apply_translation([5, 0, 0])
    c = counts_of(trimesh.util.concatenate([big, small]))
    assert (c.components, c.euler_characteristic, c.rims) == (2, 4, 0)
    assert sorted(c.component_faces) == [80, 1280] and c.component_euler == (2, 2)


def test_faces_touching_at_a_vertex_are_two_components():
    """Two tetrahedra sharing one vertex: edge-connected components, the pinched vertex counted once in each."""
    tetra = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    faces = np.r_[tetra, np.where(tetra == 0, 0, tetra + 3)]
    c = topology_counts(np.full(8, 3), faces.ravel(), 7)
    assert (c.components, c.euler_characteristic, c.rims) == (2, 4, 0)


def test_compare_names_every_difference():
    sphere, torus = counts_of(trimesh.creation.icosphere(1)), counts_of(trimesh.creation.torus(1.0, 0.3))
    disc = topology_counts(*grid_disc())
    assert compare_topology(sphere, sphere) == []
    assert compare_topology(sphere, torus) == ["Euler characteristic: scan 2, surface 0"]
    assert compare_topology(sphere, disc) == ["Euler characteristic: scan 2, surface 1",
                                             "rims (boundary loops): scan 0, surface 1"]
    # equal totals, different components: a sphere and a double torus against two tori
    two_tori = TopologyCounts(2, 0, 0, (0, 0), (0, 0), (10, 10))
    sphere_and_double_torus = TopologyCounts(2, 0, 0, (2, -2), (0, 0), (10, 10))
    (difference,) = compare_topology(two_tori, sphere_and_double_torus)
    assert difference.startswith("components' (Euler characteristic, rims): scan (0, 0), (0, 0), surface (-2, 0)")


@pytest.mark.parametrize("name, expected", [("plane_holes", (1, -25, 27)), ("boot", (1, -22, 0)),
                                            ("demosthenes-low-res", (1, 1, 1))])
def test_the_shared_scans_counts_are_the_manifests(name, expected):
    path = SCANS / f"{name}.obj"
    if not path.exists():
        pytest.skip("../shared/scans is absent")
    points, triangles, _ = read_scan(path)
    c = topology_counts(np.full(len(triangles), 3), triangles.ravel(), len(points))
    assert (c.components, c.euler_characteristic, c.rims) == expected
