"""QuadriFlow's layout (issue 43): `auto`'s first candidate, split once, taken only where it keeps and covers the scan.

Irregular vertices are counted here on the control mesh's own edges (interior valence other than 4), independently
of ``bench/fit.py``'s column.
"""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from c1surf.fitting.control import control_mesh as control_module
from c1surf.fitting.control.control_mesh import control_mesh_from_scan
from c1surf.fitting.control.quadriflow import available, quadriflow_remesh

pytestmark = pytest.mark.skipif(not available(), reason="QuadriFlow's library does not load on this platform")


def ellipsoid():
    mesh = trimesh.creation.icosphere(4)
    mesh.apply_scale([1.5, 1.0, 0.7])
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def irregular_vertices(face_sizes, face_vertices, n_points) -> int:
    """Vertices of a closed polygon mesh with other than four edges."""
    offsets = np.r_[0, np.cumsum(face_sizes)]
    following = np.arange(face_vertices.size) + 1
    following[offsets[1:] - 1] = offsets[:-1]
    edges = np.unique(np.sort(np.stack([face_vertices, face_vertices[following]], axis=1), axis=1), axis=0)
    valence = np.bincount(edges.ravel(), minlength=n_points)
    return int(np.count_nonzero(valence[np.unique(face_vertices)] != 4))


def test_the_remesh_is_a_closed_quad_mesh_on_the_surface():
    points, triangles = ellipsoid()
    quad_points, quads, seconds = quadriflow_remesh(points, triangles, 200)
    assert quads.shape[1] == 4 and 0.6 * 200 <= quads.shape[0] <= 1.2 * 200 and seconds > 0
    edges = np.sort(quads[:, [0, 1, 1, 2, 2, 3, 3, 0]].reshape(-1, 2), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    assert np.all(count == 2)  # closed, no edge in three quads
    assert np.unique(quads).size - unique.shape[0] + quads.shape[0] == 2  # a sphere's Euler characteristic
    radius = np.linalg.norm(quad_points / [1.5, 1.0, 0.7], axis=1)  # 1 on the ellipsoid
    assert np.abs(radius - 1).max() < 0.02


def test_auto_takes_its_layout_with_fewer_irregular_vertices_than_instant_meshes():
    points, triangles = ellipsoid()
    flow = control_mesh_from_scan(points, triangles, 400)
    instant = control_mesh_from_scan(points, triangles, 400, remesher="instant")
    assert flow.report["remesher"] == "quadriflow" and "quadriflow_refused" not in flow.report
    assert flow.report["topology"] == flow.report["scan_topology"] and flow.report["doo_sabin_steps"] == 1
    assert np.all(flow.face_sizes == 4) and 0.8 * 400 <= flow.n_faces <= 1.6 * 400
    ours = irregular_vertices(flow.face_sizes, flow.face_vertices, flow.points.shape[0])
    theirs = irregular_vertices(instant.face_sizes, instant.face_vertices, instant.points.shape[0])
    assert ours <= 0.6 * theirs  # measured: 8 against 18


def test_without_the_library_auto_goes_on_with_instant_meshes(monkeypatch):
    monkeypatch.setattr(control_module, "quadriflow_available", lambda: False)
    points, triangles = ellipsoid()
    mesh = control_mesh_from_scan(points, triangles, 400)
    assert mesh.report["remesher"] == "instant" and "quadriflow_refused" not in mesh.report


def test_with_a_crease_angle_its_quads_follow_the_lines_it_sees():
    """A box's edges (90 degrees) are sharper than QuadriFlow's own 60: with --crease-angle 45 its layout is taken,
    aligned by its sharp flag, and the control edges along all twelve edges are tagged (each box edge about as many
    control edges as its length over the median control edge)."""
    box = trimesh.creation.box(extents=[2.0, 1.0, 1.0]).subdivide_to_size(0.08)
    mesh = control_mesh_from_scan(np.asarray(box.vertices), np.asarray(box.faces), 300, crease_angle=45.0)
    assert mesh.report["remesher"] == "quadriflow" and mesh.report["topology"] == mesh.report["scan_topology"]
    ends = mesh.points[mesh.crease_edges]  # (k, 2, 3)
    tagged = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).sum()
    assert tagged == pytest.approx(4 * (2.0 + 1.0 + 1.0), rel=0.05)  # every box edge, and nothing else


def test_a_line_quadriflow_does_not_see_keeps_instant_meshes_alignment():
    """A house-shaped prism: its ridge bends by 50 degrees, under QuadriFlow's fixed 60, so with --crease-angle 45
    its quads would cross the ridge: Instant Meshes, which takes the angle, remeshes instead; at 70 degrees
    QuadriFlow sees every line asked for (the prism's 90-degree edges)."""
    outline = np.array([[0, 0], [2, 0], [2, 1], [1, 1 + np.tan(np.radians(25))], [0, 1]])  # convex, counter-clockwise
    n = outline.shape[0]
    points = np.r_[np.c_[outline, np.zeros(n)], np.c_[outline, np.full(n, 3.0)]]
    k = np.arange(n)
    sides = np.r_[np.c_[k, (k + 1) % n, n + (k + 1) % n], np.c_[k, n + (k + 1) % n, n + k]]
    caps = np.r_[np.c_[np.zeros(n - 2), k[2:], k[1:-1]], np.c_[np.full(n - 2, n), n + k[1:-1], n + k[2:]]]
    house = trimesh.Trimesh(points, np.r_[sides, caps].astype(np.int64)).subdivide_to_size(0.08)
    assert house.is_watertight and house.volume > 0
    mesh = control_mesh_from_scan(np.asarray(house.vertices), np.asarray(house.faces), 300, crease_angle=45.0)
    assert mesh.report["remesher"] in ("instant", "decimate") and mesh.report["crease_edges"] > 0
    # at 70 degrees the ridge is not asked for, and every line that is (the eaves at 65 are not either) it sees
    mesh = control_mesh_from_scan(np.asarray(house.vertices), np.asarray(house.faces), 300, crease_angle=70.0)
    assert mesh.report["remesher"] == "quadriflow" and mesh.report["crease_edges"] > 0


def test_its_larger_scales_stop_at_the_most_faces(monkeypatch):
    """While its layout is refused, QuadriFlow is asked at 1, 1.25, 1.5 and 2 times the faces, never above
    ``most_faces`` (the default fit's cap: a second remesh is not taken at twice its own size)."""
    asked, real_layout, real_faults = [], control_module._quadriflow_layout, control_module._faults

    def layout(scan, faces, sharp=False):
        asked.append(faces)
        return real_layout(scan, faces, sharp)

    def faults(candidate, scan):  # every QuadriFlow layout refused, as on a scan with parts thinner than its edge
        why, coverage = real_faults(candidate, scan)
        return ("left a horn" if candidate[-1]["remesher"] == "quadriflow" else why), coverage

    monkeypatch.setattr(control_module, "_quadriflow_layout", layout)
    monkeypatch.setattr(control_module, "_faults", faults)
    points, triangles = ellipsoid()
    mesh = control_mesh_from_scan(points, triangles, 400, most_faces=500)
    assert asked == [400, 500] and mesh.report["remesher"] == "instant"
    assert mesh.report["quadriflow_refused"] == "QuadriFlow's remesh left a horn"
    asked.clear()
    control_mesh_from_scan(points, triangles, 400)
    assert asked == [400, 500, 600, 800]
