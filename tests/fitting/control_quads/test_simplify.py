"""Issue 43's acceptance on synthetic shapes: the scan turned into quads and simplified keeps its topology, ends
regular where a regular layout exists, coarse where flat, and keeps every thin limb resolved."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.fitting.control.decimated_quads import mesh_topology
from c1surf.fitting.control.quads.simplify import SimplifyOptions, simplify_scan
from c1surf.fitting.control.quads.validity import quad_mesh_problems, quad_topology

from . import shapes


def _topology(points, triangles):
    counts = mesh_topology(np.full(triangles.shape[0], 3), triangles.ravel(), points.shape[0])
    return counts["components"], counts["euler"], counts["rims"]


def _irregular_share(quads, n_vertices):
    """The share of the used vertices whose edge valence is not 4 (3 on a rim)."""
    a, b = quads.ravel(), np.roll(quads, -1, axis=1).ravel()
    rim = ~np.isin(b * n_vertices + a, a * n_vertices + b)
    on_rim = np.zeros(n_vertices, dtype=bool)
    on_rim[a[rim]] = True
    valence = np.bincount(quads.ravel(), minlength=n_vertices) + on_rim
    used = np.unique(quads)
    return float(np.mean(valence[used] != np.where(on_rim[used], 3, 4)))


@pytest.mark.parametrize("name", ["torus", "genus_two"])
def test_simplified_to_a_tenth_keeps_the_euler_characteristic(name):
    points, triangles = getattr(shapes, name)()
    quads, quad_points, info = simplify_scan(points, triangles, SimplifyOptions(faces=triangles.shape[0] // 10))
    assert quad_mesh_problems(quads, quad_points.shape[0]) == []
    assert quad_topology(quads, quad_points.shape[0]) == _topology(points, triangles) == \
        ((1, 0, 0) if name == "torus" else (1, -2, 0))
    assert quads.shape[0] <= triangles.shape[0] // 10
    assert info["start_faces"] >= 2 * triangles.shape[0] * 0.8  # from the scan itself, about two quads a triangle
    if name == "torus":  # a regular torus has no irregular vertex
        assert _irregular_share(quads, quad_points.shape[0]) <= 0.05
    # the control points lie on the scan (projected): within a hundredth of the diagonal of its vertices' surface
    from c1surf.fitting.deviation import closest_on_triangles

    distance, _ = closest_on_triangles(quad_points, points, triangles)
    assert distance.max() < 1e-2 * np.linalg.norm(np.ptp(points, axis=0))


def test_a_flat_outline_ends_coarse_with_its_faces_along_the_rim():
    points, triangles = shapes.flat_outline()
    assert 5_500 <= triangles.shape[0] <= 6_500
    quads, quad_points, _ = simplify_scan(points, triangles, SimplifyOptions())
    n = quad_points.shape[0]
    assert quad_mesh_problems(quads, n) == []
    assert quad_topology(quads, n) == (1, 1, 1)
    assert quads.shape[0] <= 300
    a, b = quads.ravel(), np.roll(quads, -1, axis=1).ravel()
    rim = ~np.isin(b * n + a, a * n + b)
    on_rim = np.zeros(n, dtype=bool)
    on_rim[a[rim]] = True
    assert on_rim[quads].any(axis=1).mean() > 0.5  # most faces touch the rim
    assert np.abs(quad_points[:, 2]).max() < 1e-9  # still the plane


def _faces_around(quads, points, axis: int, sign: float, at: float = 1.45) -> int:
    """The faces that cross the plane x_axis = sign * at near the limb's axis."""
    corners = points[quads]
    x = sign * corners[..., axis]
    across = (x.min(axis=1) < at) & (x.max(axis=1) > at)
    others = [i for i in range(3) if i != axis]
    near = np.linalg.norm(corners[..., others].mean(axis=1), axis=1) < 0.5
    return int((across & near).sum())


def test_limbs_thinner_than_the_control_edge_keep_four_faces_around():
    points, triangles = shapes.limbs()
    faces = 200
    area = 0.5 * np.linalg.norm(np.cross(points[triangles[:, 1]] - points[triangles[:, 0]],
                                         points[triangles[:, 2]] - points[triangles[:, 0]]), axis=1).sum()
    assert 2 * 0.11 < np.sqrt(area / faces)  # each limb is thinner than the control edge of the budget
    quads, quad_points, _ = simplify_scan(points, triangles, SimplifyOptions(faces=faces))
    assert quad_topology(quads, quad_points.shape[0]) == _topology(points, triangles) == (1, 2, 0)
    assert quad_mesh_problems(quads, quad_points.shape[0]) == []
    around = [_faces_around(quads, quad_points, 0, 1.0), _faces_around(quads, quad_points, 1, 1.0),
              _faces_around(quads, quad_points, 2, -1.0)]
    assert min(around) >= 4, around


def test_the_fit_s_simplify_remesher_gives_a_cleaned_quad_control_mesh_of_the_scan_s_topology():
    """``--remesher simplify`` (opt-in): a quarter of the faces simplified, split in four; one Doo-Sabin step on a
    closed mesh at most, the scan's counts, nothing the cleanup had to repair."""
    from c1surf.fitting.control.control_mesh import control_mesh_from_scan

    points, triangles = shapes.torus()
    mesh = control_mesh_from_scan(points, triangles, 800, remesher="simplify")
    report = mesh.report
    assert report["remesher"] == "simplify"
    assert np.all(mesh.face_sizes == 4) and 600 <= report["faces"] <= 800
    assert report["doo_sabin_steps"] <= 1  # 0: all regular (the torus)
    assert report["topology"] == report["scan_topology"] == {"components": 1, "euler": 0, "rims": 0}
    assert not any(report.get(k) for k in ("stray_components", "closed_holes", "split_vertices", "doublets"))
