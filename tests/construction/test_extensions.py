"""Issue 4: the paper's extensions and shape controls, each measured.

1. per-cell and per-vertex blend ratios (A1, section 4, Lemma 1.3.12)
2. A1a: interpolation of the input vertices, and of vertex normals
3. A3a (tangent rule), beta, Lemma 1.3.11 (convexity for symmetric data)
4. A2a: rational patches (homogeneous weights), the paper's worked example
5. section 1.3.4: 3-sided holes parametrically C1 to the biquadratic patches
6. extra coordinates (texture coordinates, colours) through the same stencils

Smoothness numbers come from ``measure_smoothness`` (shared edges found from
the geometry); it evaluates rational patches rationally.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from plyfile import PlyData
from scipy.spatial import cKDTree

from c1surf.cli.main import main
from c1surf.evaluation.bezier import bernstein_basis, evaluate_patches, raise_degree, unit_normals
from c1surf.construction.stencils.blend import corner_ratios, second_step_corner_ratios
from c1surf.construction.refine.doo_sabin import FACE_FROM_FACE, FACE_FROM_VERTEX, refine_doo_sabin
from c1surf.construction.stencils.doo_sabin import doo_sabin_matrix
from c1surf.evaluation.rational import evaluate_rational
from c1surf.evaluation.adjacency import match_patch_sides
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.tessellate import tessellate
from c1surf.mesh.halfedges import build_halfedges
from c1surf.construction.stencils.holes.triangles import triangle_hole_coefficients
from c1surf.io.meshes.obj import read_obj
from c1surf.io.patches.json_patches import read_patch_set_json
from c1surf.io.meshes.read import read_mesh
from c1surf.io.meshes.sidecars import read_blend_file
from c1surf.prepare.extension_data import Sidecars, surface_data
from c1surf.prepare.options import InputOptions

from conftest import CLOSED_SAMPLES, SAMPLES, polygon_mesh
from conftest import fan, grid, open_cylinder, single_polygon, slab_with_polygons

MAX_JUMP = 1e-10  # radians, as in test_construction
MAX_GAP = 1e-12  # relative to the bounding-box diagonal
SOME = ["twisted.obj", "hexagon_six_valent.obj", "high_valence.obj", "icosahedron.obj", "double_torus.obj"]


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def g1_report(surface: Surface):
    report = measure_smoothness([surface.biquadratic, surface.bicubic], weights=surface.patch_weights)
    assert report.boundary_edges == 0 and report.overshared_edges == 0
    assert report.shared_edges == 2 * surface.n_patches
    return report


def assert_g1(surface: Surface):
    report = g1_report(surface)
    assert report.max_normal_jump < MAX_JUMP, report
    assert report.relative_gap < MAX_GAP, report
    return report


def build(name, **kwargs):
    mesh = read_obj(SAMPLES / name)
    options = {k: kwargs.pop(k) for k in list(kwargs) if k in SurfaceOptions.__dataclass_fields__}
    return Surface(mesh.face_sizes, mesh.face_vertices, kwargs.pop("points", mesh.points), SurfaceOptions(**options), **kwargs), mesh


def corner_frames(surface: Surface):
    """Points and unit normals at the four corners of every patch (rational if the surface is)."""
    t = np.array([0.0, 1.0])
    points, normals = [], []
    weights = surface.patch_weights or [None, None]
    for g, w in zip((surface.biquadratic, surface.bicubic), weights):
        if not len(g):
            continue
        g = g[..., :3]
        if w is None:
            x = evaluate_patches(g, t, t)
            n = unit_normals(evaluate_patches(g, t, t, 1, 0), evaluate_patches(g, t, t, 0, 1))
        else:
            x, n = evaluate_rational(g, w, t, t)
        points.append(x.reshape(-1, 3))
        normals.append(n.reshape(-1, 3))
    return np.concatenate(points), np.concatenate(normals)


def scale_of(points):
    return float(np.linalg.norm(np.ptp(points[:, :3], axis=0)))


def face_centroids(mesh):
    offsets = mesh.face_offsets()
    return np.add.reduceat(mesh.points[mesh.face_vertices], offsets[:-1]) / mesh.face_sizes[:, None]


# ---------------------------------------------------------------------------------------------
# 1. blend ratios per cell and per vertex


def test_first_step_uses_the_vertex_ratio_at_its_corners():
    """Corner (f, v) becomes (1 - a) V + a S_f, a = v's ratio where given, else f's."""
    mesh = read_obj(SAMPLES / "twisted.obj")
    coarse = build_halfedges(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices)
    rng = np.random.default_rng(0)
    face_ratio = rng.uniform(0, 1, mesh.n_faces)
    vertex_ratio = np.where(rng.uniform(size=mesh.n_vertices) < 0.5, rng.uniform(0, 1, mesh.n_vertices), np.nan)
    corner = corner_ratios(coarse, face_ratio, vertex_ratio)
    fine = doo_sabin_matrix(coarse, corner, per_corner=True) @ mesh.points
    centroids = face_centroids(mesh)
    for h in range(coarse.n_halfedges):
        v, f = coarse.origin[h], coarse.face[h]
        a = face_ratio[f] if np.isnan(vertex_ratio[v]) else vertex_ratio[v]
        np.testing.assert_allclose(fine[h], (1 - a) * mesh.points[v] + a * centroids[f], atol=1e-14)
    # per-face ratios given per corner reproduce the per-face matrix
    same = doo_sabin_matrix(coarse, face_ratio[coarse.face], per_corner=True) - doo_sabin_matrix(coarse, face_ratio)
    assert abs(same).max() < 1e-15


def test_second_step_ratios_follow_the_corners_and_v_cells_take_the_minimum():
    """A point made from once-refined vertex (= input corner) h takes h's ratio; a V-cell the minimum of its corners'."""
    mesh = read_obj(SAMPLES / "cube.obj")
    coarse = build_halfedges(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices)
    faces1 = refine_doo_sabin(coarse)
    level1 = build_halfedges(faces1.face_sizes, faces1.face_vertices, coarse.n_halfedges)
    face_ratio = np.linspace(0.1, 0.6, mesh.n_faces)
    vertex_ratio = np.full(mesh.n_vertices, np.nan)
    vertex_ratio[[0, 1]] = [0.0, 0.9]
    corner = corner_ratios(coarse, face_ratio, vertex_ratio)
    is_v = faces1.kind == FACE_FROM_VERTEX
    ratio2 = second_step_corner_ratios(level1, is_v, corner)
    factor = 1 - np.cos(2 * np.pi / level1.face_sizes[level1.face])  # 1 for the quads of a cube
    base = ratio2 / factor
    in_v = is_v[level1.face]
    np.testing.assert_array_equal(base[~in_v], corner[level1.origin[~in_v]])
    for cell in np.flatnonzero(is_v):
        mine = level1.face == cell
        v = faces1.parent[cell]
        around = face_ratio[coarse.face[coarse.origin == v]]
        expected = vertex_ratio[v] if not np.isnan(vertex_ratio[v]) else around.min()
        assert np.all(base[mine] == expected)
    # F-cells keep their input cell's ratio where no vertex ratio is given
    in_f = (faces1.kind == FACE_FROM_FACE)[level1.face] & np.isnan(vertex_ratio[coarse.origin[level1.origin]])
    np.testing.assert_array_equal(base[in_f], face_ratio[faces1.parent[level1.face[in_f]]])


def test_one_ratio_everywhere_is_the_plain_construction():
    plain, mesh = build("twisted.obj", blend=0.3)
    same, _ = build("twisted.obj", blend=0.8, face_blend=np.full(mesh.n_faces, 0.3),
                    vertex_blend=np.full(mesh.n_vertices, 0.3))
    np.testing.assert_allclose(same.bicubic, plain.bicubic, atol=1e-14)
    np.testing.assert_allclose(same.biquadratic, plain.biquadratic, atol=1e-14)


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_g1_with_mixed_cell_and_vertex_ratios(name):
    mesh = read_obj(SAMPLES / name)
    rng = np.random.default_rng(len(name))
    face_blend = rng.uniform(0.05, 1.0, mesh.n_faces)
    vertex_blend = np.where(rng.uniform(size=mesh.n_vertices) < 0.4, rng.uniform(0.05, 1.0, mesh.n_vertices), np.nan)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, face_blend=face_blend, vertex_blend=vertex_blend)
    assert_g1(surface)


def slab_regions():
    """The slab of test_construction with its flat top (z = 1) and everything else."""
    sizes, vertices, points = slab_with_polygons()
    offsets = np.r_[0, np.cumsum(sizes)]
    faces = [vertices[offsets[f] : offsets[f + 1]] for f in range(len(sizes))]
    top = np.array([np.all(points[f, 2] == 1.0) for f in faces])
    rim = set(np.concatenate([f for f, t in zip(faces, top) if not t]).tolist())
    edges = {}
    for k, f in enumerate(faces):
        for a, b in zip(f, np.roll(f, -1)):
            edges.setdefault(tuple(sorted((int(a), int(b)))), []).append(k)
    return sizes, vertices, points, faces, top, rim, edges


def edge_reach(surface, points, edges):
    """For each input edge (a, b): how far from a (0..1) the patch boundary curves lying on it cover it."""
    patches = np.concatenate([raise_degree(surface.biquadratic[..., :3], 3, 3), surface.bicubic[..., :3]])
    curves = np.concatenate([patches[:, 0], patches[:, -1], patches[:, :, 0], patches[:, :, -1]])
    reach = []
    for a, b in points[np.asarray(edges)]:
        direction = b - a
        s = np.einsum("kcd,d->kc", curves - a, direction) / (direction @ direction)
        off_line = np.linalg.norm(curves - a - s[..., None] * direction, axis=-1).max(axis=1)
        on_edge = (off_line < 1e-12) & (s.min(axis=1) > -1e-12) & (s.max(axis=1) < 1 + 1e-12)
        intervals = np.sort(np.stack([s[on_edge, 0], s[on_edge, 3]], 1), axis=1)
        r = 0.0
        for lo, hi in intervals[np.argsort(intervals[:, 0])]:
            if lo > r + 1e-12:
                break
            r = max(r, hi)
        reach.append(r)
    return np.array(reach)


def test_zero_cell_ratio_puts_the_cells_edges_on_the_surface():
    """Lemma 1.3.12 with per-cell ratios (top cells 0, the rest 0.7): every edge of a zero cell lies on the
    surface (between two zero cells, and between a zero and a non-zero cell); edges between non-zero
    cells do not."""
    sizes, vertices, points, faces, top, rim, edges = slab_regions()
    surface = Surface(sizes, vertices, points, SurfaceOptions(blend=0.7), face_blend=np.where(top, 0.0, 0.7))
    zero_zero = [e for e, fs in edges.items() if all(top[f] for f in fs)]
    zero_other = [e for e, fs in edges.items() if top[fs[0]] != top[fs[1]]]
    top_vertices = {int(v) for f, t in zip(faces, top) if t for v in f}
    other = [e for e, fs in edges.items() if not (set(e) & top_vertices)]
    assert len(zero_zero) > 40 and len(zero_other) > 20 and len(other) > 20
    assert np.all(edge_reach(surface, points, zero_zero) >= 1 - 1e-12)
    assert np.all(edge_reach(surface, points, zero_other) >= 1 - 1e-12)
    assert np.all(edge_reach(surface, points, other) < 1e-3)
    # a vertex ratio 0 at both ends puts an edge between non-zero cells on the surface too
    vertex_blend = np.full(len(points), np.nan)
    vertex_blend[sorted({v for e in other for v in e})] = 0.0
    sharp = Surface(sizes, vertices, points, SurfaceOptions(blend=0.7), face_blend=np.where(top, 0.0, 0.7), vertex_blend=vertex_blend)
    assert np.all(edge_reach(sharp, points, other) >= 1 - 1e-12)


@pytest.mark.parametrize("mesh", ["cube", "dome"])
def test_planar_cells_with_zero_ratio_give_planar_surface_pieces(mesh):
    """Lemma 1.3.12: the patches made from a planar cell of ratio 0 lie in its plane, though its neighbours
    (ratio 0.5) bend away; with ratio 0.5 the same patches bulge out of the plane."""
    if mesh == "cube":
        m = read_obj(SAMPLES / "cube.obj")
        sizes, vertices, points = m.face_sizes, m.face_vertices, m.points
    else:
        sizes, vertices, points = dome(7)
    flat_face = 0
    offsets = np.r_[0, np.cumsum(sizes)]
    corners = points[vertices[offsets[flat_face] : offsets[flat_face + 1]]]
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    assert np.abs((corners - corners[0]) @ normal).max() < 1e-14
    face_blend = np.full(len(sizes), 0.5)
    face_blend[flat_face] = 0.0

    def heights(surface):
        kind, index, _ = surface.patch_sources()
        mine = (kind == FACE_FROM_FACE) & (index == flat_face)
        out = [np.abs((g[..., :3] - corners[0]) @ normal).reshape(len(g), -1).max(axis=1) for g in (surface.biquadratic, surface.bicubic)]
        return np.concatenate(out)[mine], int(mine.sum())

    flat, count = heights(Surface(sizes, vertices, points, face_blend=face_blend))
    assert count >= 4 and flat.max() < 1e-14
    bulge, _ = heights(Surface(sizes, vertices, points))
    assert bulge.max() > 1e-3


@pytest.mark.parametrize("name", ["twisted.obj", "high_valence.obj", "icosahedron.obj", "torus.obj"])
def test_zero_vertex_ratio_puts_the_vertex_on_the_surface(name):
    """Section 4's 'alpha = 0.15 except at the points labelled 0.0': a vertex of ratio 0 is interpolated."""
    mesh = read_obj(SAMPLES / name)
    chosen = np.arange(0, mesh.n_vertices, 3)
    vertex_blend = np.full(mesh.n_vertices, np.nan)
    vertex_blend[chosen] = 0.0
    vertex_blend[chosen[1::2] + 1] = 0.5
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(blend=0.15), vertex_blend=vertex_blend)
    corners, _ = corner_frames(surface)
    distance, _ = cKDTree(corners).query(mesh.points[chosen])
    assert distance.max() < 1e-12 * scale_of(mesh.points)


def test_blend_ratios_from_a_sidecar_file_and_from_ply_properties(tmp_path):
    src = tmp_path / "cube.obj"
    text = (SAMPLES / "cube.obj").read_text().splitlines()
    first_face = next(i for i, line in enumerate(text) if line.startswith("f "))
    text.insert(first_face + 2, "g lid")  # faces 2.. are in group "lid"
    src.write_text("\n".join(text) + "\n")
    mesh = read_mesh(src)
    assert mesh.group_names[-1] == "lid"
    blend_file = tmp_path / "blend.json"
    blend_file.write_text(json.dumps({"default": 0.2, "faces": {"0": 0.9, "lid": 0.4}, "vertices": {"3": 0.05}}))
    data = surface_data(mesh, InputOptions(), sidecars=Sidecars(None, *read_blend_file(blend_file, mesh)))
    expected = np.where(mesh.face_groups == mesh.group_names.index("lid"), 0.4, 0.2)
    expected[0] = 0.9
    np.testing.assert_array_equal(data.face_blend, expected)
    assert data.vertex_blend[3] == 0.05 and np.isnan(data.vertex_blend[[0, 1, 2, 4]]).all()
    # the same ratios as PLY face and vertex properties
    ply = tmp_path / "cube.ply"
    vertex = np.array([tuple(p) + (b,) for p, b in zip(mesh.points, np.where(np.isnan(data.vertex_blend), -1, data.vertex_blend))],
                      dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("blend", "f8")])
    offsets = mesh.face_offsets()
    face = np.array([(mesh.face_vertices[offsets[f] : offsets[f + 1]], data.face_blend[f]) for f in range(mesh.n_faces)],
                    dtype=[("vertex_indices", "i4", (4,)), ("blend", "f8")])
    from plyfile import PlyElement

    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")], text=True).write(str(ply))
    from_ply = surface_data(read_mesh(ply), InputOptions())
    np.testing.assert_array_equal(from_ply.face_blend, data.face_blend)
    np.testing.assert_array_equal(np.isnan(from_ply.vertex_blend), np.isnan(data.vertex_blend))
    # and through the command line: the same surface both ways
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert run("convert", src, "-o", tmp_path / "a.ply", "--patches", a, "--blend-file", blend_file).exit_code == 0
    assert run("convert", ply, "-o", tmp_path / "b.ply", "--patches", b).exit_code == 0
    pa, pb = read_patch_set_json(a), read_patch_set_json(b)
    for ga, gb in zip(pa.groups, pb.groups):
        np.testing.assert_allclose(ga, gb, atol=1e-14)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, **data.surface_kwargs())
    np.testing.assert_allclose(pa.groups[-1], surface.bicubic, atol=1e-14)
    assert_g1(surface)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"faces": {"nope": 0.3}}))
    result = CliRunner().invoke(main, ["convert", str(src), "-o", str(tmp_path / "c.ply"), "--blend-file", str(bad)])
    assert result.exit_code == 1 and "neither a face index nor a group" in result.output


# ---------------------------------------------------------------------------------------------
# 2. A1a: vertex interpolation (and normals)


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_interpolate_vertices(name):
    """Every input vertex is a patch corner: valence n != 4 as the hole centre, 4 as a biquadratic corner."""
    surface, mesh = build(name, interpolate_vertices=True)
    assert_g1(surface)
    corners, _ = corner_frames(surface)
    distance, _ = cKDTree(corners).query(mesh.points)
    assert distance.max() < 1e-12 * scale_of(mesh.points)
    # the centroids are no longer interpolated, in general (the construction moved)
    plain, _ = build(name)
    assert np.abs(plain.biquadratic - surface.biquadratic).max() > 1e-3


def test_vertex_interpolation_is_linear_and_valence_four_vertices_are_biquadratic_corners():
    surface, mesh = build("twisted.obj", interpolate_vertices=True)
    rng = np.random.default_rng(2)
    X, Y = rng.normal(size=(2, mesh.n_vertices, 3))
    combo = surface.update_points(0.3 * X - 1.2 * Y).bicubic.copy()
    np.testing.assert_allclose(combo, 0.3 * surface.update_points(X).bicubic - 1.2 * surface.update_points(Y).bicubic, atol=1e-12)
    surface.update_points(mesh.points)
    valence = np.bincount(mesh.face_vertices, minlength=mesh.n_vertices)
    t = np.array([0.0, 1.0])
    quad_corners = evaluate_patches(surface.biquadratic, t, t).reshape(-1, 3)
    distance, _ = cKDTree(quad_corners).query(mesh.points[valence == 4])
    assert (valence == 4).sum() > 0 and distance.max() < 1e-12 * scale_of(mesh.points)
    cubic_centres = surface.bicubic[:, 3, 3]
    distance, _ = cKDTree(cubic_centres).query(mesh.points[valence != 4])
    assert distance.max() < 1e-12 * scale_of(mesh.points)


@pytest.mark.parametrize("name, mesh", [("grid", grid(5, lambda x, y: 0.2 * np.sin(x) * np.cos(y))), ("fan", fan(9)),
                                        ("cylinder", open_cylinder()), ("hexagon", single_polygon(6))])
def test_interpolate_vertices_of_open_meshes(name, mesh):
    """With the ghost layer, boundary vertices are interpolated too (they are inner vertices of the ghosted mesh)."""
    sizes, vertices, points = mesh
    surface = Surface(sizes, vertices, points, SurfaceOptions(interpolate_vertices=True))
    report = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert report.max_normal_jump < MAX_JUMP and report.boundary_edges > 0
    corners, _ = corner_frames(surface)
    distance, _ = cKDTree(corners).query(points)
    assert distance.max() < 1e-12 * scale_of(points)


def mesh_normals(mesh, noise=0.0, seed=0):
    """Area-weighted vertex normals, optionally turned at random."""
    n = np.zeros_like(mesh.points)
    offsets = mesh.face_offsets()
    for f in range(mesh.n_faces):
        vs = mesh.face_vertices[offsets[f] : offsets[f + 1]]
        p = mesh.points[vs] - mesh.points[vs].mean(axis=0)
        n[vs] += np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
    n += noise * np.random.default_rng(seed).normal(size=n.shape) * np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def normal_errors(surface, mesh, normals):
    corners, corner_normals = corner_frames(surface)
    tree = cKDTree(corners)
    worst = 0.0
    for v, hits in enumerate(tree.query_ball_point(mesh.points, 1e-10 * scale_of(mesh.points))):
        assert hits, f"vertex {v} is not on the surface"
        for k in hits:
            cross = np.linalg.norm(np.cross(corner_normals[k], normals[v]))
            worst = max(worst, float(np.arctan2(cross, corner_normals[k] @ normals[v])))  # oriented angle
    return worst


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
@pytest.mark.parametrize("rule, triangles", [("symmetric", "g1"), ("corners", "g1"), ("symmetric", "parametric")])
def test_interpolate_vertex_normals(name, rule, triangles):
    mesh = read_obj(SAMPLES / name)
    normals = mesh_normals(mesh, noise=0.2, seed=len(name))
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points,
                      SurfaceOptions(interpolate_vertices=True, tangent_rule=rule, triangles=triangles, alpha=0.8),
                      vertex_normals=normals)
    assert_g1(surface)
    assert normal_errors(surface, mesh, normals) < 1e-9


def test_interpolate_normals_from_the_command_line(tmp_path):
    mesh = read_obj(SAMPLES / "twisted.obj")
    normals = mesh_normals(mesh, noise=0.3)
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in mesh.points] + [f"vn {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in normals]
    offsets = mesh.face_offsets()
    for f in range(mesh.n_faces):
        lines.append("f " + " ".join(f"{v + 1}//{v + 1}" for v in mesh.face_vertices[offsets[f] : offsets[f + 1]]))
    src = tmp_path / "n.obj"
    src.write_text("\n".join(lines) + "\n")
    patches = tmp_path / "n.json"
    result = run("convert", src, "-o", tmp_path / "n.ply", "--patches", patches, "--interpolate-normals")
    assert result.exit_code == 0, result.output
    doc = json.loads(patches.read_text())
    assert doc["options"]["interpolate_vertices"] is True
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(interpolate_vertices=True), vertex_normals=normals)
    np.testing.assert_allclose(read_patch_set_json(patches).groups[-1], surface.bicubic, atol=1e-14)
    assert normal_errors(surface, mesh, normals) < 1e-9
    assert run("check", patches).exit_code == 0
    bad = CliRunner().invoke(main, ["convert", str(src), "-o", str(tmp_path / "x.ply"), "--interpolate-vertices", "--beta", "1"])
    assert bad.exit_code == 2 and "--beta 0" in bad.output


# ---------------------------------------------------------------------------------------------
# 3. A3a, beta and Lemma 1.3.11


@pytest.mark.parametrize("rule", ["symmetric", "corners"])
@pytest.mark.parametrize("beta", [-0.5, 0.0, 0.5, 1.0, 2.0])
@pytest.mark.parametrize("name", SOME)
def test_g1_for_both_tangent_rules_and_several_beta(name, rule, beta):
    surface, _ = build(name, tangent_rule=rule, beta=beta, alpha=0.7)
    assert_g1(surface)


@pytest.mark.parametrize("rule", ["symmetric", "corners"])
def test_beta_zero_interpolates_the_centroid_and_beta_moves_it(rule):
    for beta, on in ((0.0, True), (1.0, False)):
        surface, mesh = build("twisted.obj", tangent_rule=rule, beta=beta)
        corners, _ = corner_frames(surface)
        distance, _ = cKDTree(corners).query(face_centroids(mesh)[mesh.face_sizes != 4])
        scale = scale_of(mesh.points)
        assert (distance.max() < 1e-12 * scale) if on else (distance.max() > 1e-4 * scale)


def dome(n, r_top=1.0, h_top=0.6, r_mid=2.0, z_bottom=-1.5):
    """A convex polyhedron with n-fold rotation and mirror symmetry: an n-gon on top, two rings of quads, an n-gon below."""
    a = 2 * np.pi * np.arange(n) / n
    ring = lambda r, z: np.c_[r * np.cos(a), r * np.sin(a), np.full(n, z)]  # noqa: E731
    points = np.r_[ring(r_top, h_top), ring(r_mid, 0.0), ring(r_top, z_bottom)]
    faces = [list(range(n))]
    for i in range(n):
        j = (i + 1) % n
        faces += [[n + i, n + j, j, i], [2 * n + i, 2 * n + j, n + j, n + i]]
    faces.append(list(range(3 * n - 1, 2 * n - 1, -1)))
    return polygon_mesh(faces, points)


def top_hole(n, beta, **shape):
    """Bicubic patches and A, B, C points of the hole made from the dome's top n-gon."""
    sizes, vertices, points = dome(n, **shape)
    surface = Surface(sizes, vertices, points, SurfaceOptions(beta=beta))
    x = surface.refined_points
    start = 0
    for g in surface.holes:
        for k in range(g.cells.size):
            C = x[g.C[k]]
            if g.n == n and np.ptp(C[:, 2]) < 1e-12 and C[0, 2] > 0.3:
                return surface.bicubic[start + k * n : start + (k + 1) * n], x[g.A[k]], x[g.B1[k]], x[g.B2[k]], C
        start += g.cells.size * g.n
    raise AssertionError("no top hole")


def boundary_turns(curve):
    """Turning of the control polygon P30, P31, P32, P33 (in its plane through the axis) and the curvature sign range."""
    side = np.cross(curve[3] - curve[0], [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    assert np.abs((curve - curve[3]) @ side).max() < 1e-12  # symmetric data: the curve is planar
    d = np.diff(curve, axis=0)
    turns = np.array([np.cross(d[0], d[1]) @ side, np.cross(d[1], d[2]) @ side])
    t = np.linspace(0, 1, 201)
    bending = np.cross(bernstein_basis(3, t, 1) @ curve, bernstein_basis(3, t, 2) @ curve) @ side
    return turns, bending


def is_convex(curve):
    turns, bending = boundary_turns(curve)
    return bool(turns.max() <= 1e-13 and bending.max() <= 1e-13)


def cone_beta(A, B1, B2, C, centre, direction):
    """beta* of Lemma 1.3.11: where S_C + beta (S_P - S_C) meets the planes of the cells around the hole."""
    n = len(C)
    betas = []
    for i in range(n):
        j = (i + 1) % n
        q = np.array([C[i], C[j], B1[j], B2[i]])
        normal = np.cross(q[2] - q[0], q[3] - q[1])
        betas.append(normal @ (q[0] - centre) / (normal @ direction))
    return float(np.min(betas))


@pytest.mark.parametrize("n", [3, 5, 6, 7, 8, 12])
def test_lemma_1_3_11_beta_one_gives_convex_boundary_curves(n):
    """Locally convex, symmetric data: with beta = 1 every boundary curve P30..P33 is convex."""
    for shape in ({}, {"h_top": 1.0, "r_mid": 1.5}):
        patches, *_ = top_hole(n, 1.0, **shape)
        assert all(is_convex(p[3, :]) for p in patches)


@pytest.mark.parametrize("n", [6, 7, 8, 12])
def test_lemma_1_3_11_the_centroid_gives_an_inflection(n):
    """For a = c / (1 - c) > 1/2 (n >= 6) P_31 lies above the C_i: beta = 0 makes the boundary curve inflect."""
    patches, A, B1, B2, C = top_hole(n, 0.0)
    assert patches[:, 3, 1, 2].mean() > C[:, 2].mean()
    assert not any(is_convex(p[3, :]) for p in patches)


def convexity_limit(n):
    low, high = 1.0, 20.0
    for _ in range(50):
        mid = (low + high) / 2
        patches, *_ = top_hole(n, mid)
        low, high = (mid, high) if is_convex(patches[0, 3, :]) else (low, mid)
    return low


@pytest.mark.parametrize("n", [6, 8, 10])
def test_lemma_1_3_11_upper_bound_measured(n):
    """Measured: convex for 1 <= beta <= beta_c, with 1 < beta_c < beta* (the cone of the surrounding cells).

    The paper states convexity up to beta*; on these domes the curves already
    inflect before S reaches the cone (e.g. n = 8: beta_c = 1.52, beta* = 2.57).
    """
    patches, A, B1, B2, C = top_hole(n, 0.0)
    centre = C.mean(axis=0)
    beta_star = cone_beta(A, B1, B2, C, centre, patches[:, 3, 1].mean(axis=0) - centre)
    beta_c = convexity_limit(n)
    assert 1.0 < beta_c < beta_star
    for beta in (1.0, (1 + beta_c) / 2, beta_c - 1e-6):
        assert is_convex(top_hole(n, beta)[0][0, 3, :])
    assert not is_convex(top_hole(n, beta_star)[0][0, 3, :])


def test_lemma_1_3_11_five_sides_have_the_centre_below():
    """n = 5: a = c / (1 - c) < 1/2, so S_P lies below S_C and beta in [0, 1] all give convex curves."""
    patches, A, B1, B2, C = top_hole(5, 0.0)
    assert patches[:, 3, 1, 2].mean() < C[:, 2].mean()
    for beta in (0.0, 0.5, 1.0):
        assert all(is_convex(p[3, :]) for p in top_hole(5, beta)[0])


# ---------------------------------------------------------------------------------------------
# 4. A2a: rational patches


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_rational_surfaces_are_g1(name):
    mesh = read_obj(SAMPLES / name)
    weights = np.random.default_rng(len(name)).uniform(0.3, 3.0, mesh.n_vertices)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, weights=weights)
    assert_g1(surface)
    # the check is really rational: read as polynomial patches the same coefficients are not G1
    as_polynomial = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert as_polynomial.max_normal_jump > 1e-4


def test_unit_weights_give_the_polynomial_surface():
    plain, mesh = build("twisted.obj")
    rational, _ = build("twisted.obj", weights=np.ones(mesh.n_vertices))
    np.testing.assert_allclose(rational.bicubic, plain.bicubic, atol=1e-14)
    assert np.abs(rational.bicubic_weights - 1).max() < 1e-14 and np.abs(rational.biquadratic_weights - 1).max() < 1e-14


def regular_torus(nu=10, nv=8, R=2.0, r=0.7):
    u, v = np.meshgrid(2 * np.pi * np.arange(nu) / nu, 2 * np.pi * np.arange(nv) / nv, indexing="ij")
    points = np.c_[((R + r * np.cos(v)) * np.cos(u)).ravel(), ((R + r * np.cos(v)) * np.sin(u)).ravel(), (r * np.sin(v)).ravel()]
    faces = [[i * nv + j, ((i + 1) % nu) * nv + j, ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv]
             for i in range(nu) for j in range(nv)]
    return polygon_mesh(faces, points)


def row_curve_weights(refined, quad_frames, r0, weights, homogeneous):
    """Bezier weights of the three patch boundary curves along the row through refined vertex r0,
    between its row and the next (towards frame edge e1), ordered along the row."""
    R = refined
    frame_of = {int(R.origin[f[0]]): f for f in quad_frames}
    patch_of = {int(R.origin[f[0]]): p for p, f in enumerate(quad_frames)}
    e = frame_of[r0]
    row = [int(R.dest[e[2]]), r0, int(R.dest[e[0]])]  # r0 and its two neighbours along the row
    partner = {row[0]: int(R.dest[R.next[e[1]]]), r0: int(R.dest[e[1]]), row[2]: int(R.dest[R.next[e[0]]])}
    sides = {0: lambda q: q[-1, :], 1: lambda q: q[:, -1], 2: lambda q: q[0, :], 3: lambda q: q[:, 0]}  # crossing e0..e3
    pieces = []
    for r in row:
        k = int(np.flatnonzero(R.dest[frame_of[r]] == partner[r])[0])
        pieces.append((sides[k](weights[patch_of[r]]), sides[k](homogeneous[patch_of[r]])))
    # orient the three curves along the row by their shared end points
    first_w, first_p = pieces[0]
    if not any(np.allclose(first_p[-1], end) for end in (pieces[1][1][0], pieces[1][1][-1])):
        first_w, first_p = first_w[::-1], first_p[::-1]
    ordered = [(first_w, first_p)]
    for wts, pts in pieces[1:]:
        if not np.allclose(pts[0], ordered[-1][1][-1]):
            wts, pts = wts[::-1], pts[::-1]
        assert np.allclose(pts[0], ordered[-1][1][-1])
        ordered.append((wts, pts))
    return [tuple(np.round(wts, 12)) for wts, _ in ordered]


EXAMPLE = ([(1, 1, 2), (2, 3, 2), (2, 1, 1)], [(2, 1, 1), (2, 3, 2), (1, 1, 2)])


def test_rational_worked_example():
    """A2a: control-point weights 1 1 3 1 1 on two neighbouring rows of the regular mesh give
    the boundary curves between the rows Bezier weights (1 1 2), (2 3 2), (2 1 1).

    Here the regular mesh is the twice-refined mesh (the B-spline control net
    of A2): its homogeneous points go through c1surf's A2 stencil. (See
    test_rational_worked_example_without_refinement for the whole pipeline.)
    """
    surface = Surface(*regular_torus())
    R, x = surface.refined, surface.refined_points
    r0 = int(R.origin[surface.quad_frames[0, 0]])
    r1 = int(R.dest[surface.quad_frames[0, 1]])  # the neighbour of r0 in the next row
    w = np.ones(len(x))
    w[[r0, r1]] = 3.0
    homogeneous = (surface.stage("patches").parts[0].matrix() @ np.c_[x * w[:, None], w]).reshape(-1, 3, 3, 4)
    weights = homogeneous[..., 3]
    assert row_curve_weights(R, surface.quad_frames, r0, weights, homogeneous) in EXAMPLE
    # conics: (1 1 2) an ellipse arc (w1^2 < w0 w2), (2 3 2) a hyperbola arc (w1^2 > w0 w2);
    # the rational biquadratic surface is G1 (here even C1: every patch is biquadratic)
    patches = homogeneous[..., :3] / homogeneous[..., 3:]
    report = measure_smoothness([patches], weights=[weights])
    assert report.max_normal_jump < MAX_JUMP and report.shared_edges == 2 * len(patches)


def test_rational_tessellation_divides_by_the_weight():
    mesh = read_obj(SAMPLES / "twisted.obj")
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points,
                      weights=np.random.default_rng(1).uniform(0.5, 2.0, mesh.n_vertices))
    tess = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 5, weights=surface.patch_weights)
    t = np.linspace(0, 1, 5)
    x, n = evaluate_rational(surface.bicubic, surface.bicubic_weights, t, t)
    nq = len(surface.biquadratic)
    np.testing.assert_allclose(tess.points[tess.grid[nq:]], x, atol=1e-13)
    np.testing.assert_allclose(tess.normals[tess.grid[nq:]], n, atol=1e-12)
    out = trimesh.Trimesh(tess.points, tess.triangles, process=False)
    assert out.is_watertight and out.volume > 0


def _iges_weights(path):
    """Weights of every entity 128 of an IGES file, in order."""
    lines = path.read_text().splitlines()
    bodies = {}
    for line in lines:
        if line[72] == "P":
            bodies.setdefault(int(line[64:72]), []).append(line[:64].strip())
    out = []
    for _, parts in sorted(bodies.items()):
        tokens = "".join(parts).rstrip(";").split(",")
        if tokens[0] != "128":
            continue
        k1, k2, m1, m2 = (int(t) for t in tokens[1:5])
        n1, n2 = k1 + m1 + 2, k2 + m2 + 2  # knot counts
        start = 10 + n1 + n2
        out.append(np.array([float(t.replace("D", "E")) for t in tokens[start : start + (k1 + 1) * (k2 + 1)]]))
    return out


def test_rational_patch_files_and_the_command_line(tmp_path):
    mesh = read_obj(SAMPLES / "twisted.obj")
    weights = np.random.default_rng(5).uniform(0.5, 2.0, mesh.n_vertices)
    src = tmp_path / "w.obj"
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r} {float(w)!r}" for (x, y, z), w in zip(mesh.points, weights)]
    offsets = mesh.face_offsets()
    lines += ["f " + " ".join(str(v + 1) for v in mesh.face_vertices[offsets[f] : offsets[f + 1]]) for f in range(mesh.n_faces)]
    src.write_text("\n".join(lines) + "\n")
    json_path, iges_path = tmp_path / "w.json", tmp_path / "w.igs"
    result = run("convert", src, "-o", tmp_path / "w.ply", "--patches", json_path, "--patches", iges_path, "--no-merge")
    assert result.exit_code == 0, result.output
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, weights=weights)
    patch_set = read_patch_set_json(json_path)
    assert patch_set.weights is not None
    np.testing.assert_array_equal(patch_set.weights[0], surface.biquadratic_weights)
    np.testing.assert_array_equal(patch_set.weights[1], surface.bicubic_weights)
    doc = json.loads(json_path.read_text())
    assert np.asarray(doc["patches"][-1]["weights"]).shape == (4, 4)
    check = run("check", json_path)
    assert check.exit_code == 0 and "G1: yes" in check.output
    iges = _iges_weights(iges_path)
    assert len(iges) == surface.n_patches
    np.testing.assert_allclose(iges[0], surface.biquadratic_weights[0].T.ravel(), rtol=1e-15)  # IGES: first index fastest
    np.testing.assert_allclose(iges[-1], surface.bicubic_weights[-1].T.ravel(), rtol=1e-15)
    # --no-weights ignores them
    plain = tmp_path / "p.json"
    assert run("convert", src, "-o", tmp_path / "p.ply", "--patches", plain, "--no-weights").exit_code == 0
    assert "weights" not in json.loads(plain.read_text())["patches"][0]


# ---------------------------------------------------------------------------------------------
# 5. section 1.3.4: triangular holes, parametric C1


def side_derivatives(patches, side):
    """Outward cross-boundary derivative (Bernstein coefficients, in the patch's own direction along the side)."""
    outer = {0: patches[:, :, 0], 1: patches[:, -1, :], 2: patches[:, :, -1], 3: patches[:, 0, :]}[side]
    inner = {0: patches[:, :, 1], 1: patches[:, -2, :], 2: patches[:, :, -2], 3: patches[:, 1, :]}[side]
    return 3 * (outer - inner)


def shared_side_mismatch(surface, wanted):
    """Largest |X_a + X_b| over shared sides of the patch pairs with ``wanted(kind_a, kind_b)``.

    X is the outward cross derivative: parametric C1 (identity connecting
    map) means the two are opposite, X_a + X_b = 0.
    """
    quad = raise_degree(surface.biquadratic, 3, 3)
    patches = np.concatenate([quad, surface.bicubic])
    kinds = np.r_[np.zeros(len(quad), int), np.ones(len(surface.bicubic), int)]
    sides = match_patch_sides([patches], 1e-9 * scale_of(patches.reshape(-1, 3)))
    worst, count = 0.0, 0
    for a, b, rev in zip(sides.first, sides.second, sides.reversed):
        pa, sa = divmod(int(a), 4)
        pb, sb = divmod(int(b), 4)
        if not wanted(kinds[pa], kinds[pb], pa - len(quad), pb - len(quad)):
            continue
        xa = side_derivatives(patches[pa : pa + 1], sa)[0]
        xb = side_derivatives(patches[pb : pb + 1], sb)[0]
        worst = max(worst, float(np.abs(xa + (xb[::-1] if rev else xb)).max()))
        count += 1
    return worst, count


def triangle_patches(surface):
    sizes = np.concatenate([np.full(g.cells.size, g.n) for g in surface.holes])
    return sizes[surface.cubic_hole] == 3


@pytest.mark.parametrize("name", ["tetrahedron.obj", "icosahedron.obj", "twisted.obj", "triangular_prism.obj", "high_valence.obj"])
def test_parametric_triangles_are_c1_to_the_biquadratics(name):
    surface, _ = build(name, triangles="parametric")
    assert_g1(surface)
    three = triangle_patches(surface)
    worst, count = shared_side_mismatch(surface, lambda ka, kb, ia, ib: ka != kb and three[max(ia, ib)])
    assert count > 0 and worst < 1e-13
    # the default (A3) joins them G1 only, with a non-identity connecting map
    g1, _ = build(name)
    worst_g1, _ = shared_side_mismatch(g1, lambda ka, kb, ia, ib: ka != kb and three[max(ia, ib)])
    assert worst_g1 > 1e-3


@pytest.mark.parametrize("name", ["tetrahedron.obj", "icosahedron.obj", "twisted.obj"])
def test_parametric_triangles_join_each_other_by_psi(name):
    """Between the bicubics: X(t) = 2c t^2 T(t) (psi_i = id + t1 (1 - t2)^2 [2c, 0]), t = 0 at M_i, 1 at S.

    So the join is parametrically C1 at M_i (where four patches meet) and
    turns by 2c = -1 at the centre.
    """
    surface, _ = build(name, triangles="parametric")
    start, checked = 0, 0
    t = np.linspace(0, 1, 9)
    b, db = bernstein_basis(3, t), bernstein_basis(3, t, 1)
    for g in surface.holes:
        count = g.cells.size * g.n
        if g.n == 3:
            P = surface.bicubic[start : start + count].reshape(g.cells.size, 3, 4, 4, 3)
            Pn = np.roll(P, -1, axis=1)  # p_{i+1}
            X = 3 * ((P[:, :, 3, :] - P[:, :, 2, :]) + (Pn[:, :, :, 3] - Pn[:, :, :, 2]))
            T = np.einsum("tk,hikd->hitd", db, P[:, :, 3, :])
            lhs = np.einsum("tk,hikd->hitd", b, X)
            rhs = -1.0 * t[None, None, :, None] ** 2 * T
            scale = np.abs(T).max()
            assert np.abs(lhs - rhs).max() < 1e-13 * scale
            checked += g.cells.size
        start += count
    assert checked > 0


def test_the_printed_triangle_twist_is_a_misprint():
    """Section 1.3.4's printed P_22 breaks the join; the derived one (core.triangles) is G1."""
    surface, _ = build("icosahedron.obj", triangles="parametric")
    x = surface.refined_points
    bad = surface.bicubic.copy()
    start = 0
    for g in surface.holes:
        count = g.cells.size * g.n
        if g.n == 3:
            bad[start : start + count] = triangle_hole_coefficients(x[g.A], x[g.B1], x[g.B2], x[g.C], paper_twist=True).reshape(-1, 4, 4, 3)
        start += count
    assert measure_smoothness([surface.biquadratic, surface.bicubic]).max_normal_jump < MAX_JUMP
    assert measure_smoothness([surface.biquadratic, bad]).max_normal_jump > 1e-2


def test_parametric_triangles_from_the_command_line(tmp_path):
    patches = tmp_path / "t.json"
    assert run("convert", SAMPLES / "icosahedron.obj", "-o", tmp_path / "t.obj", "--patches", patches, "--triangles", "parametric").exit_code == 0
    assert json.loads(patches.read_text())["options"]["triangles"] == "parametric"
    surface, _ = build("icosahedron.obj", triangles="parametric")
    np.testing.assert_array_equal(read_patch_set_json(patches).groups[-1], surface.bicubic)


# ---------------------------------------------------------------------------------------------
# 6. more coordinates: texture coordinates and colours


AFFINE = np.array([[0.3, -0.2, 0.05, 0.1], [0.1, 0.25, -0.1, 0.2], [-0.2, 0.1, 0.2, -0.05]])  # 3 positions -> 4 attributes
SHIFT = np.array([0.5, 0.4, 0.5, 0.6])


@pytest.mark.parametrize("extra", [{}, {"interpolate_vertices": True}, {"weights": "random"}, {"triangles": "parametric"}])
def test_attributes_follow_the_same_map_as_the_positions(extra):
    """Attribute columns go through the same (affine) operators as the positions, so an attribute that is an
    affine function of the input positions stays that function of the surface points, exactly."""
    mesh = read_obj(SAMPLES / "twisted.obj")
    attributes = mesh.points @ AFFINE + SHIFT
    kwargs = dict(extra)
    if kwargs.get("weights") == "random":
        kwargs["weights"] = np.random.default_rng(3).uniform(0.5, 2.0, mesh.n_vertices)
    options = {k: kwargs.pop(k) for k in list(kwargs) if k in SurfaceOptions.__dataclass_fields__}
    surface = Surface(mesh.face_sizes, mesh.face_vertices, np.c_[mesh.points, attributes], SurfaceOptions(**options), **kwargs)
    tess = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 6, weights=surface.patch_weights)
    np.testing.assert_allclose(tess.points[:, 3:], tess.points[:, :3] @ AFFINE + SHIFT, atol=1e-12)
    # and the positions are those of the surface without attributes
    plain = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(**options), **kwargs)
    np.testing.assert_allclose(surface.bicubic[..., :3], plain.bicubic, atol=1e-13)
    if not kwargs:  # the very same sparse operator acts on every column
        total = surface.stencil()[9 * len(surface.biquadratic) :]  # the bicubic rows
        np.testing.assert_allclose(surface.bicubic[..., 3:].reshape(-1, 4), total @ attributes, atol=1e-13)


def test_attributes_are_written_to_ply_and_obj(tmp_path):
    mesh = read_obj(SAMPLES / "twisted.obj")
    uv = mesh.points @ AFFINE[:, :2] + SHIFT[:2]
    rgb = np.clip(mesh.points @ AFFINE[:, 1:] + SHIFT[1:], 0, 1)
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r} {float(r)!r} {float(g)!r} {float(b)!r}" for (x, y, z), (r, g, b) in zip(mesh.points, rgb)]
    lines += [f"vt {float(u)!r} {float(v)!r}" for u, v in uv]
    offsets = mesh.face_offsets()
    lines += ["f " + " ".join(f"{v + 1}/{v + 1}" for v in mesh.face_vertices[offsets[f] : offsets[f + 1]]) for f in range(mesh.n_faces)]
    src = tmp_path / "a.obj"
    src.write_text("\n".join(lines) + "\n")
    data = surface_data(read_mesh(src), InputOptions(attributes=True))
    assert data.attribute_names == ["u", "v", "red", "green", "blue"] and data.colour_scale == 1.0
    ply, obj = tmp_path / "out.ply", tmp_path / "out.obj"
    assert run("convert", src, "-o", ply, "--attributes", "-r", 4).exit_code == 0
    assert run("convert", src, "-o", obj, "--attributes", "-r", 4).exit_code == 0
    vertex = PlyData.read(str(ply))["vertex"].data
    points = np.c_[vertex["x"], vertex["y"], vertex["z"]]
    np.testing.assert_allclose(np.c_[vertex["s"], vertex["t"]], points @ AFFINE[:, :2] + SHIFT[:2], atol=1e-6)  # float32
    assert {"red", "green", "blue"} <= set(vertex.dtype.names)
    back = read_mesh(obj)
    assert back.vertex_uvs is not None and back.n_vertices == len(points)
    np.testing.assert_allclose(back.vertex_uvs, back.points @ AFFINE[:, :2] + SHIFT[:2], atol=1e-12)
    refused = CliRunner().invoke(main, ["convert", str(src), "-o", str(tmp_path / "x.stl"), "--attributes"])
    assert refused.exit_code == 2


# ---------------------------------------------------------------------------------------------
# 7. fewer refinements when the input allows (Prop. 1.3.1)


def split_cube():
    """A cube with every face split into 4 quads: valence-3 corners, none adjacent to another."""
    cube = read_obj(SAMPLES / "cube.obj")
    points = [tuple(p) for p in cube.points]
    index = {p: k for k, p in enumerate(points)}

    def vertex(p):
        p = tuple(np.round(p, 12))
        if p not in index:
            index[p] = len(points)
            points.append(p)
        return index[p]

    faces = []
    offsets = cube.face_offsets()
    for f in range(cube.n_faces):
        c = cube.points[cube.face_vertices[offsets[f] : offsets[f + 1]]]
        centre = vertex(c.mean(axis=0))
        mids = [vertex((c[i] + c[(i + 1) % 4]) / 2) for i in range(4)]
        corners = [vertex(p) for p in c]
        for i in range(4):
            faces.append([corners[i], mids[i], centre, mids[i - 1]])
    return polygon_mesh(faces, np.array(points))


def test_no_refinement_for_a_regular_mesh():
    """A regular closed quad mesh already is a B-spline control net: A2 applies to it directly."""
    sizes, vertices, points = regular_torus()
    surface = Surface(sizes, vertices, points, SurfaceOptions(refinements="auto"))
    assert surface.refinements == 0 and len(surface.bicubic) == 0
    assert len(surface.biquadratic) == len(points)  # one patch per control point
    np.testing.assert_allclose(np.sort(surface.biquadratic[:, 1, 1], axis=0), np.sort(points, axis=0), atol=1e-15)
    assert_g1(surface)
    kind, index, _ = surface.patch_sources()
    assert np.all(kind == FACE_FROM_VERTEX) and np.array_equal(np.sort(index), np.arange(len(points)))


def test_one_refinement_when_irregular_points_are_apart():
    sizes, vertices, points = split_cube()
    surface = Surface(sizes, vertices, points, SurfaceOptions(refinements="auto"))
    assert surface.refinements == 1
    two = Surface(sizes, vertices, points)
    assert surface.n_patches * 4 == two.n_patches  # a quarter of the patches
    assert_g1(surface)
    through = Surface(sizes, vertices, points, SurfaceOptions(refinements=1, interpolate_vertices=True))
    assert_g1(through)
    corners, _ = corner_frames(through)
    distance, _ = cKDTree(corners).query(points)
    assert distance.max() < 1e-12 * scale_of(points)


@pytest.mark.parametrize("relative, levels", [("pmp-library/chamfer-cube.obj", 1), ("opensubdiv/catmark_torus.obj", 0),
                                              ("spot/spot_quadrangulated.obj", 1)])
def test_fewer_refinements_on_shared_meshes(relative, levels):
    from conftest import shared_mesh

    mesh = read_mesh(shared_mesh(relative))
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(refinements="auto"))
    assert surface.refinements == levels
    assert_g1(surface)


def test_too_few_refinements_are_refused(tmp_path):
    from c1surf.mesh.errors import TopologyError

    cube = read_obj(SAMPLES / "cube.obj")
    for levels in (0, 1):
        with pytest.raises(TopologyError, match="not enough"):
            Surface(cube.face_sizes, cube.face_vertices, cube.points, SurfaceOptions(refinements=levels))
    assert Surface(cube.face_sizes, cube.face_vertices, cube.points, SurfaceOptions(refinements="auto")).refinements == 2
    result = CliRunner().invoke(main, ["convert", str(SAMPLES / "cube.obj"), "-o", str(tmp_path / "c.ply"), "--refinements", "0"])
    assert result.exit_code == 1 and "not enough" in result.output and "R1" in result.output


def test_rational_worked_example_without_refinement():
    """The paper's example through the whole pipeline: a regular mesh needs no refinement, so its
    control-point weights 1 1 3 1 1 (two neighbouring rows) reach A2 unchanged."""
    sizes, vertices, points = regular_torus()
    topology = Surface(sizes, vertices, points, SurfaceOptions(refinements=0))
    r0 = int(topology.refined.origin[topology.quad_frames[0, 0]])
    r1 = int(topology.refined.dest[topology.quad_frames[0, 1]])
    w = np.ones(len(points))
    w[[r0, r1]] = 3.0
    surface = Surface(sizes, vertices, points, SurfaceOptions(refinements=0), weights=w)
    assert_g1(surface)
    homogeneous = np.concatenate([surface.biquadratic * surface.biquadratic_weights[..., None],
                                  surface.biquadratic_weights[..., None]], axis=-1)
    assert row_curve_weights(surface.refined, surface.quad_frames, r0, surface.biquadratic_weights, homogeneous) in EXAMPLE


# merging rectangles of biquadratic patches into B-spline surfaces (--merge)


def bspline_values(piece, s):
    """Values of a merged piece on each span (a, b) at parameters a + s, b + s: (m, n, len(s), len(s), 3)."""
    from scipy.interpolate import BSpline

    m, n = piece.patches.shape
    Bu = BSpline(piece.knots_u, np.eye(m + 2), 2)
    Bv = BSpline(piece.knots_v, np.eye(n + 2), 2)
    net = piece.points if piece.weights is None else np.concatenate([piece.points * piece.weights[..., None], piece.weights[..., None]], -1)
    out = np.empty((m, n, len(s), len(s), 3))
    for a in range(m):
        for b in range(n):
            h = np.einsum("ai,bj,ijd->abd", Bu(a + s), Bv(b + s), net)
            out[a, b] = h if piece.weights is None else h[..., :3] / h[..., 3:]
    return out


@pytest.mark.parametrize("case", ["torus", "torus0", "twisted", "rational", "split_cube"])
def test_merged_bsplines_are_the_biquadratic_patches(case):
    from c1surf.evaluation.merge import merge_biquadratic

    if case.startswith("torus"):
        surface = Surface(*regular_torus(), SurfaceOptions(refinements=0 if case == "torus0" else 2))
    elif case == "split_cube":
        surface = Surface(*split_cube())
    else:
        surface, mesh = build("twisted.obj")
        if case == "rational":
            surface, _ = build("twisted.obj", weights=np.random.default_rng(4).uniform(0.5, 2.0, mesh.n_vertices))
    pieces = merge_biquadratic(surface)
    covered = np.concatenate([p.patches.ravel() for p in pieces])
    assert len(np.unique(covered)) == len(covered)  # no patch twice
    s = np.linspace(0, 1, 5)
    for piece in pieces:
        values = bspline_values(piece, s)
        for a in range(piece.patches.shape[0]):
            for b in range(piece.patches.shape[1]):
                p, k = piece.patches[a, b], piece.rotation[a, b]
                Q = np.rot90(surface.biquadratic[p], k=k, axes=(0, 1))
                if surface.rational:
                    W = np.rot90(surface.biquadratic_weights[p], k=k, axes=(0, 1))
                    h = evaluate_patches(np.concatenate([Q * W[..., None], W[..., None]], -1)[None], s, s)[0]
                    expected = h[..., :3] / h[..., 3:]
                else:
                    expected = evaluate_patches(Q[None], s, s)[0]
                np.testing.assert_allclose(values[a, b], expected, atol=1e-13)
    if case.startswith("torus"):
        assert len(pieces) == 1 and len(covered) == len(surface.biquadratic)  # one B-spline surface
    else:
        assert len(covered) > 0.9 * len(surface.biquadratic) and len(pieces) < len(covered) / 5


def test_merge_writes_bsplines_to_json_and_iges(tmp_path):
    json_path, iges_path = tmp_path / "m.json", tmp_path / "m.igs"
    result = run("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "m.ply", "--patches", json_path, "--patches", iges_path,
                 "--merge", "--cad-pieces")  # IGES: the pieces whole (by default cut into strips one span wide)
    assert result.exit_code == 0, result.output
    doc = json.loads(json_path.read_text())
    merged = doc["merged"]
    surface, _ = build("twisted.obj")
    spans = sum(np.asarray(m["patches"]).size for m in merged)
    assert len(doc["patches"]) == surface.n_patches  # every patch is still there
    first = merged[0]
    m, n = np.asarray(first["patches"]).shape
    assert np.asarray(first["points"]).shape == (m + 2, n + 2, 3) and len(first["knots_u"]) == m + 5
    entities = _iges_weights(iges_path)
    assert len(entities) == len(merged) + surface.n_patches - spans
    try:
        from OCP.BRep import BRep_Tool
        from OCP.IGESControl import IGESControl_Reader
        from OCP.TopAbs import TopAbs_FACE
        from OCP.TopExp import TopExp_Explorer
        from OCP.TopoDS import TopoDS
    except ImportError:  # pragma: no cover
        return
    reader = IGESControl_Reader()
    reader.ReadFile(str(iges_path))
    reader.TransferRoots()
    face = TopoDS.Face(TopExp_Explorer(reader.OneShape(), TopAbs_FACE).Current())
    geom = BRep_Tool.Surface_s(face)
    from c1surf.evaluation.merge import MergedPiece

    piece = MergedPiece(np.asarray(first["points"]), None, np.asarray(first["knots_u"]), np.asarray(first["knots_v"]),
                        np.asarray(first["patches"]), np.asarray(first["rotation"]))
    values = bspline_values(piece, np.array([0.0, 0.3, 1.0]))
    for a, b in ((0, 0), (m - 1, n - 1)):
        for i, u in enumerate((0.0, 0.3, 1.0)):
            p = geom.Value(float(a + u), float(b + 0.3))
            np.testing.assert_allclose([p.X(), p.Y(), p.Z()], values[a, b, i, 1], atol=1e-12)
