"""Issue 39: ``fit`` never loses a part of the scan.

Three small scans built in code (``thin_shapes``): a ball with five horns thinner than the control edge and a second
ball on a neck far thinner still; a curved sheet with five holes each smaller than two control edges; two spheres
touching at one pinched vertex beside a separate small one. Each keeps its parts and rims (counted independently on
the control mesh and the surface), every scan vertex lies within a local control edge of the control mesh (measured
here against the exact closest points), nothing in the control mesh is pinched, and the report says so truthfully.
"""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.fitting.control.control_mesh import control_mesh_from_scan, manifold_scan
from c1surf.fitting.control.coverage import mesh_coverage
from c1surf.fitting.control.decimated_quads import _decimate_keeping_topology, decimate_scan, manifold_faults
from c1surf.fitting.options import FitOptions
from c1surf.fitting.scan_fit import ScanFitOptions, fit_scan
from c1surf.mesh.topology_counts import counts_as_read

from thin_shapes import holed_sheet, horned, pinched_pair
from test_topology_kept import triangle_topology

QUICK = FitOptions(max_iterations=2, fairness_growth=0.0)


def control_edge(points, triangles, faces):
    """The control edge of ``faces`` squares over the scan's area."""
    c = points[triangles]
    return np.sqrt(0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum() / faces)


def far_from(mesh, points) -> float:
    """The largest distance of a scan point to the control mesh's quads (two triangles each), over the longest control
    edge: an independent bound (brute force over every triangle) on what ``coverage`` measures locally."""
    quads = mesh.face_vertices.reshape(-1, 4)
    tris = np.concatenate([quads[:, :3], quads[:, [0, 2, 3]]])
    import trimesh

    distance = trimesh.proximity.closest_point(trimesh.Trimesh(mesh.points, tris, process=False), points)[1]
    edges = np.linalg.norm(mesh.points[quads] - mesh.points[np.roll(quads, -1, axis=1)], axis=2)
    return float(distance.max() / edges.max())


def assert_manifold_control(mesh, counts):
    read = counts_as_read(mesh.face_sizes, mesh.face_vertices, mesh.points.shape[0])
    assert read["pinched_vertices"] == 0 and read["non_manifold_edges"] == 0
    assert (read["components"], read["euler_characteristic"], read["rims"]) == counts
    for key in ("split_vertices", "stray_components", "closed_holes", "non_manifold_faces"):
        assert mesh.report[key] == 0, key


def test_horns_and_a_neck_far_thinner_than_the_control_edge_are_kept():
    points, triangles = horned()
    assert triangle_topology(points, triangles) == (1, 2, 0)
    edge = control_edge(points, triangles, 300)
    assert 2 * edge > 0.1 and 20 * edge > 0.3  # horns about 0.1 across, the neck about 0.012: far thinner
    mesh = control_mesh_from_scan(points, triangles, 300)
    assert_manifold_control(mesh, (1, 2, 0))
    assert mesh.report["coverage"]["lost_vertices"] == 0 and mesh.report["coverage"]["max_edges"] <= 1.0
    assert far_from(mesh, points) < 1.0
    # the neck's middle (x = -1.6, the tube 0.012 across) has control points near it: not pinched, not dropped
    assert np.linalg.norm(mesh.points - [-1.6, 0, 0], axis=1).min() < edge
    # Instant Meshes alone breaks it at this size; auto says so and takes the decimated scan
    assert any("Instant Meshes' remesh" in n and "decimated instead" in n for n in mesh.notes)
    fit = fit_scan(points, triangles, ScanFitOptions(faces=300, fit=QUICK))
    assert not fit.topology["differences"] and fit.topology["scan"]["euler_characteristic"] == 2
    assert fit.deviation.scan_stats["relative_max"] < 0.02


def test_the_decimation_never_pinches_where_the_library_would():
    """pymeshlab's ``preservetopology`` with the thin-part weights pinches the holed sheet (measured: 5 pinched
    vertices, 3 components); the decimation c1surf uses redoes it and returns a manifold with the scan's counts."""
    points, triangles = holed_sheet()
    from c1surf.fitting.control.decimated_quads import thin_part_weights

    weights = thin_part_weights(points, triangles, 300)
    library = decimate_scan(points, triangles, 138, weights, keep_rims=False)
    kept = _decimate_keeping_topology(points, triangles, 138, weights)
    assert manifold_faults(*kept).size == 0
    assert triangle_topology(*kept) == triangle_topology(points, triangles) == (1, -4, 6)
    if manifold_faults(*library).size == 0:  # a pymeshlab that no longer pinches here: nothing to redo
        pytest.skip("this pymeshlab's decimation kept the sheet a manifold")
    assert triangle_topology(*library) != (1, -4, 6)


@pytest.mark.parametrize("faces", [120, 300])
def test_five_holes_smaller_than_two_control_edges_stay_open(faces):
    points, triangles = holed_sheet()
    edge = control_edge(points, triangles, faces)
    assert 0.09 < 2 * edge  # each hole about 0.09 across
    mesh = control_mesh_from_scan(points, triangles, faces)
    assert_manifold_control(mesh, (1, -4, 6))
    coverage = mesh_coverage(points, triangles, mesh.face_sizes, mesh.face_vertices, mesh.points)
    assert coverage.ok and not coverage.lost_rims and not coverage.extra_rims
    assert mesh.report["coverage"]["lost_rims"] == 0
    instant = control_mesh_from_scan(points, triangles, faces, remesher="instant")
    spanned = mesh_coverage(points, triangles, instant.face_sizes, instant.face_vertices, instant.points)
    assert spanned.lost_rims  # Instant Meshes spans them: the check sees it whatever the counts
    assert instant.report["coverage"]["lost_rims"] == len(spanned.lost_rims)


def test_a_pinched_vertex_and_a_small_part_keep_their_counts_and_the_report_says_both():
    points, triangles = pinched_pair()
    split, manifold, faults = manifold_scan(points, triangles)
    assert faults == 1 and counts_as_read(np.full(len(manifold), 3), manifold.ravel(), len(split)) == {
        "components": 3, "euler_characteristic": 6, "rims": 0, "pinched_vertices": 0, "non_manifold_edges": 0}
    fit = fit_scan(points, triangles, ScanFitOptions(faces=200, fit=QUICK))
    topology = fit.topology
    assert (topology["scan"]["components"], topology["scan"]["euler_characteristic"], topology["scan"]["rims"]) \
        == (3, 6, 0)
    assert topology["scan_as_read"] == {"components": 2, "euler_characteristic": 5, "rims": 0, "pinched_vertices": 1,
                                        "non_manifold_edges": 0}
    assert not topology["differences"]
    assert_manifold_control(fit.control, (3, 6, 0))
    assert any("the scan is not a manifold (1 pinched vertices" in n and "3 components, Euler characteristic 6" in n
               for n in fit.notes)
    small = np.linalg.norm(points - [0, 2.5, 0], axis=1) < 0.2
    assert fit.deviation.scan_to_surface[small].max() < 0.05 * 0.15  # the small sphere fitted at its own size


def test_a_candidate_that_drops_a_part_is_named_with_where():
    """Coverage of a control mesh that lacks the small sphere: its vertices are lost, and the phrase names where."""
    points, triangles = pinched_pair()
    big = np.unique(triangles[:2560])
    mesh = control_mesh_from_scan(points[big], np.searchsorted(big, triangles[:2560]), 120, remesher="decimate")
    coverage = mesh_coverage(points, triangles, mesh.face_sizes, mesh.face_vertices, mesh.points)
    assert not coverage.ok and coverage.lost.sum() == len(points) - len(big)
    phrase, = coverage.phrases(points)
    assert "162 scan vertices farther than 1.5 local control edges" in phrase and "at (0, 2.65, 0)" in phrase
