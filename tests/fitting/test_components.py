"""A scan of several components (issue 34): every component fitted, or the ones left out named in a note; the
fit report's topology side by side with the scan's (on real scans: test_topology_kept.py); the cleanup names the
stray components it drops."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from c1surf.fitting.control.cleanup import clean_control_mesh, cleanup_notes
from c1surf.fitting.options import FitOptions
from c1surf.fitting.scan_fit import ScanFitOptions, fit_scan, unfitted_components

from test_control_mesh import quad_sphere

FAR = np.array([3.0, 0.5, 0.0])  # the small sphere's centre


def two_spheres(radius: float):
    """(points, triangles): a unit icosphere (1,280 triangles) and one of ``radius`` (320) centred at ``FAR``."""
    big = trimesh.creation.icosphere(subdivisions=3)
    small = trimesh.creation.icosphere(subdivisions=2, radius=radius)
    small.apply_translation(FAR)
    both = trimesh.util.concatenate([big, small])
    return np.asarray(both.vertices), np.asarray(both.faces)


def fitted(radius: float, faces: int = 120, remesher: str = "instant"):
    points, triangles = two_spheres(radius)
    # the closest fit (no fairness continuation): what is measured here is whether each component is fitted; the
    # continuation's bounds are relative to the whole scan's diagonal (tests/fitting/test_fairness.py)
    # Instant Meshes alone: the parts its remesh of the whole misses are what this mechanism covers (``auto`` takes
    # the decimated scan there instead: test_auto_keeps_both_components_by_decimating)
    options = ScanFitOptions(faces=faces, fit=FitOptions(max_iterations=3, fairness_growth=0.0), remesher=remesher)
    return points, triangles, fit_scan(points, triangles, options)


@pytest.mark.parametrize("radius", [0.05, 0.6])
def test_a_small_component_is_fitted(radius):
    """At radius 0.05 (3 % of the diagonal) Instant Meshes makes nothing at the small sphere at 120 faces: it is
    remeshed on its own and fitted, and a note says so (before, it was dropped without a word and its samples
    dragged flaps of 0.23 of the diagonal out of the big sphere); at 0.6 the remesh of the whole has both."""
    points, triangles, fit = fitted(radius)
    topology = fit.topology
    assert topology["scan"]["components"] == 2 and topology["scan"]["euler_characteristic"] == 4
    assert topology["surface"] == {**topology["scan"], "component_faces": topology["surface"]["component_faces"]}
    assert not topology["differences"] and not [n for n in fit.notes if "left out" in n or "topology" in n]
    small = np.arange(len(points)) >= 642  # the big icosphere's 642 vertices come first
    assert fit.deviation.scan_to_surface[small].max() < 0.02 * radius  # fitted, at its own size
    assert fit.deviation.surface_stats["relative_max"] < 5e-3  # no flap between them (issue 34: 5e-3)
    own = [n for n in fit.notes if "remeshed on their own" in n]
    assert len(own) == (radius == 0.05)  # measured: the remesh of the whole misses it at 0.05
    if own:
        assert "162 vertices and 320 triangles around (3, 0.5, 0)" in own[0]
        assert fit.control.report["parts"] and fit.control.n_faces == fit.control.report["faces"]


def test_auto_keeps_both_components_by_decimating():
    """The default remesher: Instant Meshes' remesh of the whole misses the small sphere (its topology differs), so
    the control mesh is the scan decimated with its topology kept; both spheres fitted, the note says why."""
    points, triangles, fit = fitted(0.05, remesher="auto")
    topology = fit.topology
    assert topology["scan"]["components"] == 2 and not topology["differences"]
    assert fit.control.report["remesher"] == "decimate"
    assert [n for n in fit.notes if n.startswith("Instant Meshes' remesh changed the scan's topology")]
    small = np.arange(len(points)) >= 642
    assert fit.deviation.scan_to_surface[small].max() < 0.05 * 0.05  # fitted: within 5 % of its radius
    assert fit.deviation.surface_stats["relative_max"] < 5e-3


def test_a_component_too_small_to_remesh_is_named_and_left_out():
    """A sphere and an octahedron of 8 triangles far away: too few triangles for a remesh of its own
    (``MIN_PART_TRIANGLES``): named in a note, left out of the fit, its distances in the deviation."""
    sphere = trimesh.creation.icosphere(subdivisions=3)
    octahedron = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    speck = trimesh.Trimesh(0.05 * octahedron + FAR, [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5],
                                                      [1, 2, 5], [3, 1, 5], [0, 3, 5]], process=False)
    both = trimesh.util.concatenate([sphere, speck])
    points, triangles = np.asarray(both.vertices), np.asarray(both.faces)
    fit = fit_scan(points, triangles, ScanFitOptions(faces=120, fit=FitOptions(max_iterations=3), remesher="instant"))
    (note,) = [n for n in fit.notes if "left out of the fit" in n]
    assert "1 of the scan's 2 components got no control mesh" in note
    assert "6 vertices and 8 triangles around (3, 0.5, 0)" in note
    assert any(n.startswith("the surface's topology differs from the scan's: components: scan 2, surface 1")
               for n in fit.notes)
    small = np.arange(len(points)) >= 642
    assert fit.deviation.scan_to_surface[~small].max() < 2e-3 * fit.deviation.diagonal  # fitted as if alone
    assert fit.deviation.surface_stats["relative_max"] < 2e-3  # no flap towards the speck
    expected = np.linalg.norm(points[small], axis=1) - 1.0  # its distances stay: to the unit sphere
    assert np.allclose(fit.deviation.scan_to_surface[small], expected, atol=2e-3 * fit.deviation.diagonal)


def test_unfitted_components_are_the_ones_no_control_point_is_near():
    points, triangles = two_spheres(0.05)
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    keep, notes = unfitted_components(points, triangles, 1.1 * points[:642:7], diagonal, 99)
    assert keep is not None and np.array_equal(keep, np.arange(len(triangles)) < 1280)
    assert len(notes) == 1 and "1 of the scan's 2 components got no control mesh at 99 control faces" in notes[0]
    keep, notes = unfitted_components(points, triangles, np.r_[points[:5], points[-5:]], diagonal, 99)
    assert keep is None and notes == []


def test_the_cleanup_names_the_stray_components_it_drops():
    """A remesh with a stray 6-quad cube far from a sphere the scan has alone: dropped, and named."""
    sizes, vertices, points = quad_sphere(4)
    cube_sizes, cube_vertices, cube_points = quad_sphere(1)
    all_sizes = np.r_[sizes, cube_sizes]
    all_vertices = np.r_[vertices, cube_vertices + len(points)]
    all_points = np.r_[points, 0.1 * cube_points + [5.0, 0.0, 0.0]]
    scan = trimesh.creation.icosphere(subdivisions=3)
    out_sizes, _, _, report = clean_control_mesh(all_sizes, all_vertices, all_points,
                                                 scan=(np.asarray(scan.vertices), np.asarray(scan.faces)))
    assert report["stray_components"] == 1 and report["stray_faces"] == 6 and out_sizes.size == sizes.size
    (note,) = cleanup_notes(report)
    assert "dropped 1 stray components the scan does not have (6 faces, 8 vertices around (5, 0, 0))" in note
