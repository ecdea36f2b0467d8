"""The construction (A1-A3) against the paper's claims, measured on real meshes.

Every smoothness number here comes from ``measure_smoothness``, which finds
shared patch edges from geometry alone.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.interpolate import BSpline
from scipy.spatial import cKDTree

from c1surf.evaluation.bezier import evaluate_patches, raise_degree
from c1surf.construction.stencils.holes.bicubic import bicubic_hole_coefficients
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.tessellate import tessellate
from c1surf.io.meshes.obj import read_obj

from conftest import CLOSED_SAMPLES, CLOSED_SHARED, SAMPLES, misprinted_bicubic, shared_mesh, slab_with_polygons, surface_of
from reference import bicubic_stencil, biquadratic_stencil

MAX_JUMP = 1e-10  # radians
MAX_GAP = 1e-12  # relative to the bounding-box diagonal


def assert_g1(surface: Surface):
    report = measure_smoothness([surface.biquadratic, surface.bicubic])
    assert report.boundary_edges == 0 and report.overshared_edges == 0
    assert report.shared_edges == 2 * surface.n_patches  # closed quad layout: 4 sides, each shared by 2
    assert report.max_normal_jump < MAX_JUMP, report
    assert report.relative_gap < MAX_GAP, report
    return report


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_g1_on_sample_meshes(name):
    assert_g1(surface_of(SAMPLES / name))


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
@pytest.mark.parametrize("blend, alpha", [(0.2, 0.6), (0.9, 1.0)])
def test_g1_for_other_shape_parameters(name, blend, alpha):
    assert_g1(surface_of(SAMPLES / name, blend=blend, alpha=alpha))


@pytest.mark.parametrize("relative", CLOSED_SHARED)
def test_g1_on_shared_closed_meshes(relative):
    assert_g1(surface_of(shared_mesh(relative)))


def test_checker_catches_the_misprinted_p12():
    """The transcription's P_12 (NOTES item 1) must show as a normal jump."""
    surface = surface_of(SAMPLES / "twisted.obj")
    bad = misprinted_bicubic(surface)
    good = measure_smoothness([surface.biquadratic, surface.bicubic]).max_normal_jump
    broken = measure_smoothness([surface.biquadratic, bad]).max_normal_jump
    assert good < MAX_JUMP and broken > 1e-3


def test_local_formulas_match_the_stencil():
    """The sparse stencil is the formula applied to the basis: check against direct evaluation."""
    surface = surface_of(SAMPLES / "hexagon_six_valent.obj", alpha=0.7)
    x = surface.refined_points
    start = 0
    for g in surface.holes:
        direct = bicubic_hole_coefficients(x[g.A], x[g.B1], x[g.B2], x[g.C], alpha=0.7)
        count = g.cells.size * g.n
        np.testing.assert_allclose(surface.bicubic[start : start + count], direct.reshape(-1, 4, 4, 3), atol=1e-13)
        start += count


def test_even_holes_sharing_b_points_are_perturbed_jointly():
    """NOTES item 4: a hexagon with 6-valent corners couples two even holes."""
    for name in ("hexagon_six_valent.obj", "hexagon_all_six_valent.obj"):
        surface = surface_of(SAMPLES / name)
        x = surface.refined_points
        shared = 0
        b_sets = []
        for g in surface.holes:
            if g.n % 2 == 0 and g.n > 4:
                sign = np.where(np.arange(g.n) % 2 == 0, 1.0, -1.0)[None, :, None]
                alternating = (sign * (x[g.B1] - x[g.B2])).sum(axis=1)
                assert np.abs(alternating).max() < 1e-13
                b_sets += [set(np.r_[b1, b2]) for b1, b2 in zip(g.B1, g.B2)]
        for i in range(len(b_sets)):
            for j in range(i + 1, len(b_sets)):
                shared += len(b_sets[i] & b_sets[j])
        assert shared > 0, f"{name} should have even holes that share B points"
        assert_g1(surface)


def test_surface_passes_through_every_cell_centroid():
    for name in ("twisted.obj", "dodecahedron.obj", "double_torus.obj", "high_valence.obj"):
        mesh = read_obj(SAMPLES / name)
        surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points)
        offsets = mesh.face_offsets()
        centroids = np.add.reduceat(mesh.points[mesh.face_vertices], offsets[:-1]) / mesh.face_sizes[:, None]
        corners = np.concatenate(
            [evaluate_patches(g, np.array([0.0, 1.0]), np.array([0.0, 1.0])).reshape(-1, 3) for g in (surface.biquadratic, surface.bicubic)]
        )
        distance, _ = cKDTree(corners).query(centroids)
        scale = np.linalg.norm(np.ptp(mesh.points, axis=0))
        assert distance.max() < 1e-12 * scale


def test_construction_is_linear_in_the_points():
    mesh = read_obj(SAMPLES / "twisted.obj")
    rng = np.random.default_rng(7)
    X, Y = rng.normal(size=(2, mesh.n_vertices, 3))
    a, b = 0.3, -1.7

    def build(points):
        return Surface(mesh.face_sizes, mesh.face_vertices, points)

    sx, sy, sxy = build(X), build(Y), build(a * X + b * Y)
    np.testing.assert_allclose(sxy.biquadratic, a * sx.biquadratic + b * sy.biquadratic, atol=1e-12)
    np.testing.assert_allclose(sxy.bicubic, a * sx.bicubic + b * sy.bicubic, atol=1e-12)
    # and update_points on the same connectivity agrees with a fresh build
    sx.update_points(a * X + b * Y)
    np.testing.assert_allclose(sx.bicubic, sxy.bicubic, atol=1e-13)


def total_operator(surface: Surface):
    op = surface.stencil()
    rows = 9 * len(surface.biquadratic)
    return op[:rows], op[rows:]


@pytest.mark.parametrize("blend", [0.5, 0.0])
def test_planar_region_gives_planar_patches(blend):
    """Prop. 1.3.8 / Lemma 1.3.12: patches fed only by the flat top are flat."""
    sizes, vertices, points = slab_with_polygons()
    surface = Surface(sizes, vertices, points, SurfaceOptions(blend=blend))
    on_top = points[:, 2] == 1.0
    counted = {"biquadratic": 0, "bicubic": 0}
    for kind, op, group in zip(counted, total_operator(surface), (surface.biquadratic, surface.bicubic)):
        op = op.tocsr()
        per_patch = group.shape[1] * group.shape[2]
        touches_off_plane = np.zeros(group.shape[0], dtype=bool)
        coo = op.tocoo()
        off = ~on_top[coo.col] & (np.abs(coo.data) > 0)
        touches_off_plane[np.unique(coo.row[off] // per_patch)] = True
        flat = ~touches_off_plane
        counted[kind] = int(flat.sum())
        assert np.abs(group[flat][..., 2] - 1.0).max() < 1e-14
    assert counted["biquadratic"] > 50 and counted["bicubic"] >= 14  # octagon (8) and hexagon (6) cells


def test_zero_blend_interpolates_the_edges_between_cells():
    """Lemma 1.3.12: with blend ratio 0 every input edge lies on the surface.

    Exactly: each input edge is covered by patch boundary curves whose control
    points all lie on that edge (so the curves lie on it).
    """
    mesh = read_obj(SAMPLES / "twisted.obj")
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(blend=0.0))
    patches = np.concatenate([raise_degree(surface.biquadratic, 3, 3), surface.bicubic])
    curves = np.concatenate([patches[:, 0], patches[:, -1], patches[:, :, 0], patches[:, :, -1]])  # (K, 4, 3)
    offsets = mesh.face_offsets()
    nxt = np.arange(mesh.face_vertices.size) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    edges = np.unique(np.sort(np.stack([mesh.face_vertices, mesh.face_vertices[nxt]], 1), axis=1), axis=0)
    for a, b in mesh.points[edges]:
        direction = b - a
        length2 = direction @ direction
        s = np.einsum("kcd,d->kc", curves - a, direction) / length2  # position along the edge
        off_line = np.linalg.norm(curves - a - s[..., None] * direction, axis=-1).max(axis=1)
        on_edge = (off_line < 1e-12) & (s.min(axis=1) > -1e-12) & (s.max(axis=1) < 1 + 1e-12)
        intervals = np.sort(np.stack([s[on_edge, 0], s[on_edge, 3]], 1), axis=1)
        intervals = intervals[np.argsort(intervals[:, 0])]
        reach = 0.0
        for lo, hi in intervals:
            assert lo <= reach + 1e-12, "a piece of the edge is not on the surface"
            reach = max(reach, hi)
        assert reach >= 1 - 1e-12


def test_regular_region_is_the_biquadratic_bspline():
    """A2: on a regular quad mesh every patch is the uniform biquadratic B-spline of the refined points."""
    surface = surface_of(SAMPLES / "torus.obj")
    assert len(surface.bicubic) == 0
    R, x = surface.refined, surface.refined_points
    e = surface.quad_frames
    # 3 x 3 control net around each regular vertex, indices [i, j] with i along e2 -> e0, j along e3 -> e1
    diag = lambda h: R.dest[R.next[h]]  # noqa: E731  (vertex opposite the centre in face(h))
    net = np.empty((len(e), 3, 3), dtype=np.int64)
    net[:, 1, 1] = R.origin[e[:, 0]]
    net[:, 2, 1], net[:, 1, 2], net[:, 0, 1], net[:, 1, 0] = (R.dest[e[:, k]] for k in range(4))
    net[:, 2, 2], net[:, 0, 2], net[:, 0, 0], net[:, 2, 0] = (diag(e[:, k]) for k in range(4))
    knots = np.arange(6.0)
    t = np.linspace(0, 1, 5)
    basis = BSpline(knots, np.eye(3), 2)(2.0 + t)  # (5, 3): the three B-splines alive on [2, 3]
    expected = np.einsum("ai,bj,pijd->pabd", basis, basis, x[net])
    np.testing.assert_allclose(evaluate_patches(surface.biquadratic, t, t), expected, atol=1e-13)


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_patch_counts_follow_the_paper(name):
    """One biquadratic per regular refined vertex, n bicubics per n-sided refined cell.

    Twice refined, a closed mesh with H face corners has 4H vertices; its
    non-quad cells are the input faces with n != 4 and the input vertices of
    valence != 4.
    """
    mesh = read_obj(SAMPLES / name)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points)
    valence = np.bincount(mesh.face_vertices, minlength=mesh.n_vertices)
    holes = np.r_[mesh.face_sizes[mesh.face_sizes != 4], valence[(valence != 4) & (valence > 0)]]
    assert len(surface.bicubic) == holes.sum()
    assert len(surface.biquadratic) == 4 * mesh.face_vertices.size - holes.sum()
    assert sorted(g.n for g in surface.holes for _ in range(g.cells.size)) == sorted(holes.tolist())


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_tessellation_is_watertight_and_outward(name):
    surface = surface_of(SAMPLES / name)
    tess = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 5)
    mesh = trimesh.Trimesh(tess.points, tess.triangles, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    assert np.all(np.isfinite(tess.normals))
    # exact normals agree with the faces' orientation
    face_normals = mesh.face_normals
    vertex_normals = tess.normals[tess.triangles].mean(axis=1)
    assert np.mean(np.einsum("ij,ij->i", face_normals, vertex_normals) > 0) > 0.99


def test_degree_raising_keeps_the_surface():
    rng = np.random.default_rng(1)
    quad = rng.normal(size=(4, 3, 3, 3))
    t = np.linspace(0, 1, 7)
    np.testing.assert_allclose(evaluate_patches(raise_degree(quad, 3, 3), t, t), evaluate_patches(quad, t, t), atol=1e-14)


OPEN_SHARED = ["opensubdiv/catmark_edgecorner.obj", "opensubdiv/catmark_tent.obj", "opensubdiv/catmark_hole_test2.obj",
               "opensubdiv/catmark_flap2.obj"]


@pytest.mark.parametrize("path", [SAMPLES / p.name for p in sorted(SAMPLES.glob("*.obj"))] + OPEN_SHARED, ids=str)
def test_refined_halfedges_by_arithmetic_match_a_fresh_sort(path):
    """The refined half-edges (twins by index arithmetic) are those a sort of edge keys finds."""
    from c1surf.mesh.ghost_layer import add_ghost_layer
    from c1surf.construction.refine.doo_sabin import refine_doo_sabin, refined_halfedges
    from c1surf.mesh.repair import prepare_topology
    from c1surf.mesh.halfedges import build_halfedges
    from c1surf.io.meshes.read import read_mesh

    mesh = read_mesh(path if isinstance(path, Path) else shared_mesh(path))
    coarse, source, report = prepare_topology(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices)
    if report["boundary_edges"]:
        coarse = add_ghost_layer(coarse).mesh
    for _ in range(2):
        faces = refine_doo_sabin(coarse)
        fast = refined_halfedges(coarse, faces)
        sorted_ = build_halfedges(faces.face_sizes, faces.face_vertices, coarse.n_halfedges)
        for field in ("face_sizes", "face_offsets", "origin", "face", "next", "prev", "twin"):
            np.testing.assert_array_equal(getattr(fast, field), getattr(sorted_, field), err_msg=field)
        # the last step's faces without their sources, and a twin let go and made again when read
        lean = refined_halfedges(coarse, refine_doo_sabin(coarse, sources=False))
        lean.release_twin()
        coarse.release_prev()
        for field in ("twin", "face_sizes", "face_offsets", "origin", "face", "next", "prev"):
            np.testing.assert_array_equal(getattr(lean, field), getattr(sorted_, field), err_msg=field)
        coarse = fast


@pytest.mark.parametrize("path", [SAMPLES / p.name for p in sorted(SAMPLES.glob("*.obj"))] + OPEN_SHARED[:2], ids=str)
def test_second_step_ratios_by_blocks_match_the_whole(path):
    """The second step's ratios made by blocks of faces (one broadcast value when all equal) are the whole
    computation's, bit for bit: for one ratio everywhere (the default: made per face size) and for ratios
    that differ from corner to corner (V-cells take their minimum)."""
    from c1surf.construction.refine.doo_sabin import FACE_FROM_VERTEX
    from c1surf.construction.stencils.blend import second_step_ratios
    from c1surf.construction.stencils.blend import second_step_corner_ratios

    surface = surface_of(path if isinstance(path, Path) else shared_mesh(path))
    topology = surface.topology
    is_vertex_cell = topology.faces1.kind == FACE_FROM_VERTEX
    default = surface.stage("doo_sabin_1").ratio
    varied = np.random.default_rng(3).uniform(0.1, 0.9, default.shape)
    for corner_ratio in (default, varied):
        whole = second_step_corner_ratios(topology.level1, is_vertex_cell, corner_ratio)
        for block in (1, 7, 1 << 20):
            by_blocks = second_step_ratios(topology.level1, is_vertex_cell, corner_ratio, block=block)
            np.testing.assert_array_equal(by_blocks.view(np.int64), whole.view(np.int64))


def test_a_large_mesh_build_lets_the_twin_go(monkeypatch):
    """Past ``RELEASED_TWIN_HALFEDGES`` the refined twin is let go after the frames and made again when read:
    the same patches and the same adjacency."""
    import c1surf.construction.topology as topology_module
    from c1surf.evaluation.adjacency import patch_adjacency

    kept = surface_of(SAMPLES / "twisted.obj")
    monkeypatch.setattr(topology_module, "RELEASED_TWIN_HALFEDGES", 0)
    lean = surface_of(SAMPLES / "twisted.obj")
    assert lean.refined._twin is None
    np.testing.assert_array_equal(lean.biquadratic, kept.biquadratic)
    np.testing.assert_array_equal(lean.bicubic, kept.bicubic)
    a, b = patch_adjacency(lean.refined, lean.frames), patch_adjacency(kept.refined, kept.frames)
    np.testing.assert_array_equal(np.asarray(a.corners), np.asarray(b.corners))
    np.testing.assert_array_equal(np.asarray(a.edges), np.asarray(b.edges))
    np.testing.assert_array_equal(lean.refined.twin, kept.refined.twin)


@pytest.mark.parametrize("path", [SAMPLES / "twisted.obj", SAMPLES / "high_valence.obj"] + OPEN_SHARED[:2], ids=str)
def test_patch_gathers_match_the_sparse_stencils(path):
    """A2 and A3 by gathers and dense products per block equal the plain per-patch sparse stencils."""
    surface = surface_of(path if isinstance(path, Path) else shared_mesh(path))
    x = surface.refined_points
    direct = (biquadratic_stencil(surface.refined, surface.quad_frames) @ x).reshape(-1, 3, 3, x.shape[1])
    np.testing.assert_allclose(surface.biquadratic, direct, rtol=0, atol=1e-14 * np.abs(x).max())
    assert surface.bicubic.shape[0] > 0
    cubic = bicubic_stencil(surface.refined, surface.holes, surface.options.hole_rules().weights, surface.topology.cubic_keep)
    direct = (cubic @ x).reshape(-1, 4, 4, x.shape[1])
    np.testing.assert_allclose(surface.bicubic, direct, rtol=0, atol=1e-13 * np.abs(x).max())


def test_factored_doo_sabin_step_is_its_matrix():
    """The second refinement step applied factored, as a matrix, and composed, gives one map."""
    from c1surf.construction.stencils.doo_sabin import DooSabinStep

    surface = surface_of(SAMPLES / "high_valence.obj")
    step = surface.stage("doo_sabin_2")
    assert isinstance(step, DooSabinStep) and step is surface.stages[2]
    x = np.random.default_rng(3).normal(size=(step.shape[1], 3))
    factored = step.apply(x)
    before = (surface.stages[1].matrix() @ surface.stages[0].matrix()).toarray()
    factored_before = step.apply(before)  # the factored map on a matrix's columns
    matrix = step.matrix()
    results = [factored] + [step.apply(x) for _ in range(3)]  # factored first, then the kept matrix
    for y in results:
        np.testing.assert_allclose(y, matrix @ x, rtol=0, atol=1e-14)
    np.testing.assert_allclose(factored_before,
                               (matrix @ before), atol=1e-15)
    quad = surface.stage("patches").parts[0].matrix()
    np.testing.assert_allclose(quad @ factored_before, (quad @ matrix).toarray() @ before, atol=1e-15)
