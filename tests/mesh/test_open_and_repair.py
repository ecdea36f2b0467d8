"""Issue 3: open meshes, repaired topology, refused topology (all measured)."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from c1surf.evaluation.bezier import bernstein_basis, raise_degree
from c1surf.mesh.errors import TopologyError
from c1surf.evaluation.adjacency import match_patch_sides, side_polygons
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.construction.surface import Surface
from c1surf.evaluation.tessellate import tessellate
from c1surf.mesh.halfedges import build_halfedges
from c1surf.io.meshes.read import read_mesh

from conftest import SAMPLES, fan, single_polygon, grid, open_cylinder, polygon_mesh, shared_mesh

MAX_JUMP = 1e-10


def boundary_curves(surface: Surface):
    """Patch sides that no other patch shares, found from geometry: (k, 4, 3) cubic control points."""
    patches = np.concatenate([raise_degree(surface.biquadratic[..., :3], 3, 3), surface.bicubic[..., :3]])
    flat = patches.reshape(-1, 3)
    sides = match_patch_sides([patches], 1e-9 * np.linalg.norm(np.ptp(flat, axis=0)))
    patch, side = np.divmod(sides.lone, 4)
    curves = np.stack(side_polygons(patches), axis=1)
    return curves[patch, side]


def input_boundary(sizes, vertices, points):
    mesh = build_halfedges(sizes, vertices, len(points))
    b = np.flatnonzero(mesh.twin < 0)
    return points[mesh.origin[b]], points[mesh.dest[b]]


def check_open(sizes, vertices, points, jump=MAX_JUMP, reach=0.25):
    surface = Surface(sizes, vertices, points)
    report = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert report.overshared_edges == 0
    assert report.max_normal_jump < jump, report
    assert report.relative_gap < 1e-12
    assert report.boundary_edges > 0
    tess = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 4)
    assert np.isfinite(tess.points).all() and np.isfinite(tess.normals).all()
    mesh = trimesh.Trimesh(tess.points, tess.triangles, process=False)
    assert mesh.is_winding_consistent
    # The surface reaches the input boundary: every input boundary edge has a
    # surface boundary point within a fraction of its length, and the surface
    # boundary stays near the boundary polygon.
    a, b = input_boundary(sizes, vertices, points)
    length = np.linalg.norm(b - a, axis=1)
    t = np.linspace(0, 1, 65)
    samples = np.einsum("mi,kid->kmd", bernstein_basis(3, t), boundary_curves(surface)).reshape(-1, 3)
    distance, _ = cKDTree(samples).query((a + b) / 2)
    assert np.all(distance < reach * length)
    polygon = (a[:, None] * (1 - t[:, None]) + b[:, None] * t[:, None]).reshape(-1, 3)
    back, _ = cKDTree(polygon).query(samples)
    assert back.max() < 2 * reach * length.mean()
    return surface, report


@pytest.mark.parametrize(
    "name, mesh",
    [
        ("grid", grid(6, lambda x, y: 0.2 * np.sin(x) * np.cos(y))),
        ("disk fan of 12 triangles", fan(12)),
        ("disk fan of 30 triangles", fan(30)),
        ("open cylinder", open_cylinder()),
        ("single quad", single_polygon(4)),
        ("single hexagon", single_polygon(6)),
    ],
)
def test_open_meshes_are_g1_inside_and_reach_the_boundary(name, mesh):
    check_open(*mesh)


def test_single_many_sided_polygon():
    """Every vertex of a lone 30-gon is a corner; each stays a corner, so the
    boundary is inset between them: measured 0.45 of an edge at the midpoints
    (4.5% of the radius) and at most 0.6 of an edge anywhere."""
    check_open(*single_polygon(30), reach=0.5)


@pytest.mark.parametrize(
    "relative",
    [
        "opensubdiv/catmark_edgecorner.obj",
        "opensubdiv/catmark_xord_boundary.obj",
        "pmp-library/hole_capsule.obj",
        "odedstein-meshes/plane_holes.obj",
        "opensubdiv/catmark_pole360.obj",
        "opensubdiv/catmark_nonman_quadpole360.obj",
        "pmp-library/L.obj",
        "opensubdiv/bilinear_nonquads1.obj",
    ],
)
def test_shared_open_meshes(relative):
    mesh = read_mesh(shared_mesh(relative))
    check_open(mesh.face_sizes, mesh.face_vertices, mesh.points)


def test_straight_regular_boundary_is_the_bspline_of_the_boundary_polygon():
    """Reflected ghosts: away from corners the boundary passes exactly through edge midpoints."""
    sizes, vertices, points = grid(6)
    surface = Surface(sizes, vertices, points)
    a, b = input_boundary(sizes, vertices, points)
    samples = np.einsum("mi,kid->kmd", bernstein_basis(3, np.linspace(0, 1, 257)), boundary_curves(surface)).reshape(-1, 3)
    distance, _ = cKDTree(samples).query((a + b) / 2)
    at_corner = np.isin(a[:, 0], [0, 6]) & np.isin(a[:, 1], [0, 6]) | np.isin(b[:, 0], [0, 6]) & np.isin(b[:, 1], [0, 6])
    assert distance[~at_corner].max() < 1e-12
    # and the boundary stays in the plane of the flat grid
    assert np.abs(samples[:, 2]).max() < 1e-14


def test_boundary_corners_stay_corners():
    """A corner of the input boundary (a vertex in one face) is a corner of the surface boundary."""
    sizes, vertices, points = grid(4)
    surface = Surface(sizes, vertices, points)
    curves = boundary_curves(surface)
    ends = np.r_[curves[:, 0], curves[:, 3]]
    tangents = np.r_[curves[:, 1] - curves[:, 0], curves[:, 2] - curves[:, 3]]
    # group curve ends by point; at a smooth boundary point the two tangents are opposite
    _, label = np.unique(np.round(ends * 1e9).astype(np.int64), axis=0, return_inverse=True)
    label = label.ravel()
    turning = []
    for k in np.unique(label):
        t = tangents[label == k]
        if len(t) == 2:
            cos = t[0] @ t[1] / np.linalg.norm(t[0]) / np.linalg.norm(t[1])
            turning.append(np.degrees(np.arccos(np.clip(-cos, -1, 1))))
    turning = np.sort(turning)
    assert np.sum(turning > 30) == 4  # the grid's four corners, nothing else
    assert np.all(turning[:-4] < 1e-5)  # degrees: arccos round-off near 0


def flipped(sizes, vertices, which):
    from c1surf.mesh.repair import reverse_faces

    flip = np.zeros(sizes.size, dtype=bool)
    flip[which] = True
    return reverse_faces(sizes, vertices, flip)


def corner_points(surface):
    patches = np.concatenate([raise_degree(surface.biquadratic, 3, 3), surface.bicubic])
    return np.unique(np.round(patches[:, [0, 3, 0, 3], [0, 0, 3, 3]].reshape(-1, 3), 9), axis=0)


def test_inconsistent_winding_is_repaired_to_the_same_surface():
    mesh = read_mesh(SAMPLES / "torus.obj")
    rng = np.random.default_rng(3)
    which = rng.choice(mesh.n_faces, 17, replace=False)
    bad = flipped(mesh.face_sizes, mesh.face_vertices, which)
    repaired = Surface(mesh.face_sizes, bad, mesh.points)
    original = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points)
    assert repaired.repairs["flipped_faces"] == 17
    report = measure_smoothness([repaired.biquadratic, repaired.bicubic])
    assert report.max_normal_jump < MAX_JUMP and report.boundary_edges == 0
    np.testing.assert_allclose(corner_points(repaired), corner_points(original), atol=1e-12)


def test_shared_mesh_with_flipped_faces():
    mesh = read_mesh(SAMPLES / "twisted.obj")
    bad = flipped(mesh.face_sizes, mesh.face_vertices, [0, 3, 5])
    surface = Surface(mesh.face_sizes, bad, mesh.points)
    assert surface.repairs["flipped_faces"] == 3
    assert measure_smoothness([surface.biquadratic, surface.bicubic]).max_normal_jump < MAX_JUMP


def two_tetrahedra_sharing_a_vertex():
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    points = np.r_[tet, -tet[1:]]  # second tetrahedron mirrored through the shared vertex 0
    second = [[{0: 0, 1: 4, 2: 5, 3: 6}[v] for v in f] for f in faces]
    return polygon_mesh(faces + second, points)


def test_pinched_vertex_is_split_per_fan():
    sizes, vertices, points = two_tetrahedra_sharing_a_vertex()
    surface = Surface(sizes, vertices, points)
    assert surface.repairs["split_vertices"] == 1 and surface.repairs["components"] == 2
    report = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert report.max_normal_jump < MAX_JUMP and report.boundary_edges == 0
    tess = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 4)
    assert trimesh.Trimesh(tess.points, tess.triangles, process=False).is_watertight


def test_components_and_unused_vertices():
    a = read_mesh(SAMPLES / "cube.obj")
    b = read_mesh(SAMPLES / "tetrahedron.obj")
    points = np.r_[a.points, [[9, 9, 9]], b.points + 5]  # one unused vertex between them
    vertices = np.r_[a.face_vertices, b.face_vertices + a.n_vertices + 1]
    surface = Surface(np.r_[a.face_sizes, b.face_sizes], vertices, points)
    assert surface.repairs["components"] == 2 and surface.repairs["unused_vertices"] == 1
    alone = Surface(a.face_sizes, a.face_vertices, a.points).n_patches + Surface(b.face_sizes, b.face_vertices, b.points).n_patches
    assert surface.n_patches == alone
    assert measure_smoothness([surface.biquadratic, surface.bicubic]).max_normal_jump < MAX_JUMP


def test_interior_valence_two_vertex_is_refused_by_name():
    # two quads glued along two consecutive edges around vertex 1, closed by a fan elsewhere
    mesh = read_mesh(shared_mesh("opensubdiv/catmark_val2_interior.obj"))
    with pytest.raises(TopologyError) as info:
        Surface(mesh.face_sizes, mesh.face_vertices, mesh.points)
    assert "valence 2" in str(info.value) and info.value.vertices and info.value.faces.size == 2


def test_non_manifold_edge_is_refused_with_its_faces():
    mesh = read_mesh(shared_mesh("opensubdiv/catmark_nonman_edge100.obj"))
    with pytest.raises(TopologyError) as info:
        Surface(mesh.face_sizes, mesh.face_vertices, mesh.points)
    assert "shared by 100 faces" in str(info.value) and info.value.faces.size == 100
    assert len(info.value.vertices) == 2


def moebius_strip(n=12, width=0.3):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rings = [np.c_[(1 + w * np.cos(t / 2)) * np.cos(t), (1 + w * np.cos(t / 2)) * np.sin(t), w * np.sin(t / 2)] for w in (-width, width)]
    faces = [[i, i + 1, n + i + 1, n + i] for i in range(n - 1)]
    faces.append([n - 1, n, 0, 2 * n - 1])  # the half twist: inner joins outer
    return polygon_mesh(faces, np.concatenate(rings))


def test_moebius_strip_is_tangent_plane_continuous():
    """Non-orientable: built on the orientation double cover, one sheet kept; G1 with unoriented normals."""
    sizes, vertices, points = moebius_strip()
    surface = Surface(sizes, vertices, points)
    assert surface.repairs["non_orientable"]
    unoriented = measure_smoothness([surface.biquadratic, surface.bicubic], unoriented=True)
    assert unoriented.max_normal_jump < MAX_JUMP and unoriented.overshared_edges == 0
    # every patch edge is shared except the strip's one boundary loop
    annulus = Surface(*open_cylinder(12, 1))
    assert surface.n_patches == annulus.n_patches
    assert unoriented.boundary_edges == measure_smoothness([annulus.biquadratic, annulus.bicubic]).boundary_edges
    # orientation flips across the seam, as it must on a Moebius strip
    assert measure_smoothness([surface.biquadratic, surface.bicubic]).max_normal_jump > 3.0
    tess = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 4)
    assert np.isfinite(tess.points).all() and np.isfinite(tess.normals).all()
