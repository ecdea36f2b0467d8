"""Darts as C0 (docs/sharp-features.md, "Darts"): a crease line that ends inside the surface is cut up to its
end, whose vertex gets the dart's hole (``construction.stencils.holes.dart``): C0 across the crease spoke, G1
across every other spoke, at the centre and everywhere else. Measured by ``check``'s own measurement
(``api.check_surface``) and side by side from the geometry alone (``side_pairs``)."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.api import check_surface
from c1surf.construction.crease_sides import dart_spoke_pairs
from c1surf.construction.features import SharpFeatures
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.io.meshes.read import read_mesh

from dart_cell import side_samples
from dart_meshes import grid_dart, polar_dart
from conftest import shared_mesh
from test_c0_creases import side_pairs

# faces around the dart: ring edges of each face (1 a triangle, 2 a quad, 3 a pentagon); valence 3 to 8
AROUND = {3: [2, 2, 2], 4: [2, 1, 2, 2], 5: [2, 2, 2, 2, 2], 6: [3, 1, 2, 1, 2, 2], 7: [1] * 7,
          8: [2, 3, 1, 2, 2, 1, 2, 2]}
TRIANGLES = {3: [1, 1, 1], 5: [1, 2, 1, 2, 1], 6: [1] * 6, 8: [1] * 8}


def exact(points, sizes, corners, features) -> Surface:
    return Surface(sizes, corners, points, SurfaceOptions(exact_creases=True), features=features)


def assert_dart_surface(surface: Surface, darts: int = 1):
    """check's measurement; the dart's spoke measured on its own; every shared side matched from the geometry."""
    report = check_surface(surface)
    assert report.overshared_edges == 0 and report.unpaired_crease_sides == 0
    assert report.crease_edges == len(surface.crease_sides)
    assert report.max_normal_jump < 1e-10
    assert report.relative_gap < 1e-12 and report.relative_crease_gap < 1e-12
    spokes = dart_spoke_pairs(surface.topology)
    assert len(spokes) == darts and np.isin(spokes, surface.crease_sides).all()
    patches = np.concatenate([raise_to_cubic(surface.biquadratic), surface.bicubic])
    t = np.linspace(0.0, 1.0, 21)
    for before, after in spokes:  # side u = 1 of p_{n-1}, side v = 1 of p_0: both run from M to S
        (x, n_before), (y, n_after) = (side_samples(patches[c // 4], c % 4, t) for c in sorted((before, after),
                                                                                              key=lambda c: c % 4))
        jump = np.arctan2(np.linalg.norm(np.cross(n_before, n_after), axis=1), np.einsum("md,md->m", n_before, n_after))
        assert np.abs(x - y).max() < 1e-12 * report.bbox_diagonal
        assert jump[: t.size // 2].max() > 0.05  # a crease away from its end (the 90-degree valley)
        assert jump[-1] < 1e-10  # G1 at the dart's centre
    gap, jump, diagonal, unmatched = side_pairs(surface)  # independent of the construction's bookkeeping
    crease = ~np.all(jump <= 1e-6, axis=1)
    assert crease.sum() == len(surface.crease_sides)
    assert jump[~crease].max() < 1e-10 and gap.max() < 1e-12 * diagonal
    return report


def raise_to_cubic(quads):
    from c1surf.evaluation.bezier import raise_degree

    return raise_degree(quads, 3, 3)


@pytest.mark.parametrize("n", sorted(AROUND))
def test_a_dart_of_valence_n_is_c0_up_to_its_end_and_g1_elsewhere(n):
    points, sizes, corners, features, dart = polar_dart(AROUND[n], seed=n)
    surface = exact(points, sizes, corners, features)
    sheets = surface.topology.crease_sheets
    assert sheets.dart_vertex.size == 1 and len(sheets.kept_edges) == 0 and len(sheets.cut_edges) == 3
    assert [(g.n, g.cells.size) for g in surface.holes if g.dart] == [(n + 2, 1)]
    assert_dart_surface(surface)


@pytest.mark.parametrize("n", sorted(TRIANGLES))
def test_a_dart_among_triangles(n):
    assert_dart_surface(exact(*polar_dart(TRIANGLES[n], seed=20 + n)[:4]))


def test_a_dart_at_the_end_of_a_crease_that_crosses_another():
    points, sizes, corners, features, dart = grid_dart(cross=True)
    surface = exact(points, sizes, corners, features)
    assert len(surface.topology.crease_sheets.cut_edges) == 12  # the crossing is a corner, 1 | 1 | 1 | 1
    assert_dart_surface(surface)


def test_a_dart_of_a_crease_from_the_boundary():
    assert_dart_surface(exact(*grid_dart()[:4]))


@pytest.mark.parametrize("n", [3, 6])
def test_the_stencil_reproduces_darts(n):
    """``update_points`` equals a fresh construction to round-off (4e-16 here; not bit for bit, as without darts
    or creases: a plain surface's ``update_points`` differs from a fresh one in the last bits too), and the
    stencil gives the patches."""
    points, sizes, corners, features, _ = polar_dart(AROUND[n], seed=n)
    surface = exact(points, sizes, corners, features)
    moved = points + 0.1 * np.random.default_rng(7).standard_normal(points.shape)
    fresh = exact(moved, sizes, corners, features)
    surface.update_points(moved)
    assert np.abs(surface.biquadratic - fresh.biquadratic).max() <= 1e-13
    assert np.abs(surface.bicubic - fresh.bicubic).max() <= 1e-13
    stacked = np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)])
    assert np.abs(surface.stencil() @ moved - stacked).max() <= 1e-13 * np.abs(stacked).max()


@pytest.mark.parametrize("length", [2, 3])
def test_a_line_with_darts_at_both_ends(length):
    points, sizes, corners, _, _ = grid_dart()
    N = 8
    at = lambda a, b: a * (N + 1) + b
    line = np.array([[at(a, N // 2), at(a + 1, N // 2)] for a in range(2, 2 + length)])
    surface = exact(points, sizes, corners, SharpFeatures(line, np.full(length, 10.0)))
    assert surface.topology.crease_sheets.dart_vertex.size == 2
    assert_dart_surface(surface, darts=2)


@pytest.mark.parametrize("name", ["catmark_dart_edgeonly", "catmark_dart_edgecorner"])
def test_opensubdiv_darts_infinitely_sharp_are_c0_up_to_the_dart(name):
    """Their crease 8 - 17 - 20 (sharpness 2 in the files, semi-sharp: G1 as before) made infinitely sharp: cut
    from the boundary (8) to the dart (20), C0 along both edges up to the dart's centre."""
    mesh = read_mesh(shared_mesh(f"opensubdiv/{name}.obj"))
    tags = mesh.tags
    assert sorted(map(sorted, tags.crease_edges.tolist())) == [[8, 17], [17, 20]]
    features = SharpFeatures(tags.crease_edges, np.full(len(tags.crease_edges), 10.0))
    points = mesh.points.copy()
    points[[8, 17, 20], 1] += 0.5  # a ridge along the crease: a real crease to measure (the file is flat there)
    surface = exact(points, mesh.face_sizes, mesh.face_vertices, features)
    sheets = surface.topology.crease_sheets
    assert sheets.cut_edges.tolist() == [[8, 17], [17, 20]] and sheets.vertex_name[sheets.dart_vertex].tolist() == [20]
    report = check_surface(surface)
    assert report.crease_edges == len(surface.crease_sides) == 8 and report.unpaired_crease_sides == 0
    assert report.relative_crease_gap < 1e-12 and report.max_normal_jump < 1e-10


@pytest.mark.parametrize("hole", [0, 4, 2])
def test_a_hole_face_beside_the_dart(hole):
    """A face around the dart tagged as a hole (no patches): beside the crease (0 after it, 4 before it) the
    crease spoke has one side left, a boundary, and is not listed; elsewhere nothing changes."""
    points, sizes, corners, features, _ = polar_dart([2, 2, 2, 2, 2])
    tagged = SharpFeatures(features.crease_edges, features.crease_sharpness, hole_faces=np.array([hole]))
    surface = exact(points, sizes, corners, tagged)
    assert len(dart_spoke_pairs(surface.topology)) == (0 if hole in (0, 4) else 1)
    report = check_surface(surface)
    assert report.unpaired_crease_sides == 0 and report.crease_edges == len(surface.crease_sides)
    assert report.max_normal_jump < 1e-10 and report.relative_crease_gap < 1e-12
