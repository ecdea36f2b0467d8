"""Tessellation to a chordal tolerance (evaluation.tolerance): watertight, no T-junctions, error within T.

The chordal error is measured here independently of the bound that chose the
resolutions: the exact patch (``bezier.evaluate_patches_at``, one sample at a
time, not the template basis products of ``chordal``) at many barycentric points
of every triangle against the triangle written, relative to the bounding box of
the output mesh (trimesh's).
"""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from c1surf.construction.surface import Surface
from c1surf.evaluation.adjacency import patch_adjacency
from c1surf.evaluation.bezier import evaluate_patches, evaluate_patches_at
from c1surf.evaluation.curvature import patch_curvature, tessellation_curvature
from c1surf.evaluation.rational import dehomogenize, homogeneous
from c1surf.evaluation.tessellate import tessellate_patches
from c1surf.evaluation.tolerance.chordal import measured_chordal_error
from c1surf.evaluation.tolerance.curvature import tolerance_curvature
from c1surf.evaluation.tolerance.resolution import (bound, fewer_triangles, patch_segments, second_derivative_bounds,
                                                    template_triangles)
from c1surf.evaluation.tolerance.tessellation import plan_tolerance, tessellate_to_tolerance
from c1surf.evaluation.tolerance.triangulate import template
from c1surf.io.meshes.obj import read_obj

from conftest import CLOSED_SAMPLES, SAMPLES, grid, surface_of

# barycentric points of every triangle: vertices' neighbourhoods, edges, the inside (not only centroid and midpoints)
BARYCENTRIC = np.array([[1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0], [0, 0.5, 0.5], [0.5, 0, 0.5], [0.6, 0.2, 0.2],
                        [0.2, 0.6, 0.2], [0.2, 0.2, 0.6], [0.45, 0.45, 0.1], [0.1, 0.45, 0.45], [0.45, 0.1, 0.45],
                        [0.8, 0.1, 0.1], [0.25, 0.75, 0.0], [0.7, 0.0, 0.3]])


def parts(surface: Surface):
    return [surface.biquadratic, surface.bicubic], patch_adjacency(surface.refined, surface.frames), surface.patch_weights


def independent_error(groups, tess, weights=None) -> float:
    """Largest |exact patch - triangle| over BARYCENTRIC points of every triangle, over the mesh's diagonal."""
    patch, uv = tess.triangle_patch, tess.triangle_parameters()  # (T,), (T, 3, 2)
    mesh = trimesh.Trimesh(tess.points[:, :3], tess.triangles, process=False)
    corners = mesh.vertices[tess.triangles]  # (T, 3, 3)
    starts = np.cumsum([0] + [len(g) for g in groups])
    worst = 0.0
    for b in BARYCENTRIC:
        u, v = uv[:, :, 0] @ b, uv[:, :, 1] @ b
        linear = np.einsum("k,tkc->tc", b, corners)
        for k, g in enumerate(groups):
            rows = np.flatnonzero((patch >= starts[k]) & (patch < starts[k + 1]))
            index = patch[rows] - starts[k]
            if weights is None:
                exact = evaluate_patches_at(g[index][..., :3], u[rows], v[rows])
            else:
                exact = dehomogenize(evaluate_patches_at(homogeneous(g[index][..., :3], weights[k][index]), u[rows], v[rows]))[0]
            worst = max(worst, float(np.linalg.norm(exact - linear[rows], axis=1).max(initial=0.0)))
    return worst / float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))


def assert_crack_free(tess, closed: bool = True) -> None:
    """Watertight (each edge in two triangles, consistently wound), no two vertices at one position,
    every vertex used: no T-junction (a vertex inside another triangle's edge would leave that edge single)."""
    mesh = trimesh.Trimesh(tess.points[:, :3], tess.triangles, process=False)
    if closed:
        assert mesh.is_watertight and mesh.is_winding_consistent
    assert len(np.unique(tess.points[:, :3], axis=0)) == len(tess.points)
    assert np.array_equal(np.unique(tess.triangles), np.arange(len(tess.points)))
    assert np.all(mesh.area_faces > 0)


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_every_sample_mesh_is_watertight_within_the_tolerance(name):
    groups, adjacency, weights = parts(surface_of(SAMPLES / name))
    counts = []
    for tolerance in (1e-2, 1e-3):
        tess = tessellate_to_tolerance(groups, adjacency, tolerance, weights)
        assert_crack_free(tess)
        error = independent_error(groups, tess)
        assert error <= tolerance
        # the library's measure (centroid and edge midpoints) is one of these samples' lower bounds
        assert measured_chordal_error(groups, tess) <= error * (1 + 1e-9)
        counts.append(len(tess.triangles))
        # outward normals, as the uniform tessellation: the enclosed volume is positive
        assert trimesh.Trimesh(tess.points[:, :3], tess.triangles, process=False).volume > 0
    assert counts[0] < counts[1]


def test_triangle_counts_shrink_as_the_tolerance_grows():
    groups, adjacency, weights = parts(surface_of(SAMPLES / "twisted.obj"))
    counts = [len(tessellate_to_tolerance(groups, adjacency, t, weights).triangles) for t in (3e-4, 1e-3, 3e-3, 1e-2, 3e-2)]
    assert all(a > b for a, b in zip(counts, counts[1:])), counts


def test_rational_patches_stay_within_the_tolerance():
    """A2a: weights from 0.5 to 2; the bound is made in homogeneous coordinates (no measuring)."""
    mesh = read_obj(SAMPLES / "twisted.obj")
    weights = np.random.default_rng(3).uniform(0.5, 2.0, mesh.n_vertices)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, weights=weights)
    groups, adjacency, patch_weights = parts(surface)
    assert patch_weights is not None
    for tolerance in (1e-2, 1e-3):
        tess = tessellate_to_tolerance(groups, adjacency, tolerance, patch_weights)
        assert_crack_free(tess)
        assert independent_error(groups, tess, patch_weights) <= tolerance


def test_open_surfaces_and_flat_patches():
    """An open grid: crack-free, and an affine patch (zero second differences: the inner patches of a
    flat grid) gets one segment each way, two triangles where its neighbours allow. The error is the
    parametric one, so a flat patch with a non-affine parametrisation (at the ghost layer) is refined."""
    flat = Surface(*grid(6))
    groups, adjacency, _ = parts(flat)
    tess = tessellate_to_tolerance(groups, adjacency, 1e-4)
    assert_crack_free(tess, closed=False)
    assert np.all(tess.points[:, 2] == 0)
    affine = np.concatenate([second_derivative_bounds(g) for g in groups]).max(axis=1) == 0
    assert affine.sum() >= 16
    assert np.all(tess.plan.segments[affine] == 1)
    two = np.diff(tess.plan.triangle_start) == 2
    assert np.all(affine[two]) and two.sum() >= 4
    assert independent_error(groups, tess) <= 1e-4
    bumpy = Surface(*grid(4, lambda x, y: 0.3 * np.sin(x) * np.cos(y)))
    groups, adjacency, _ = parts(bumpy)
    tess = tessellate_to_tolerance(groups, adjacency, 1e-4)
    assert_crack_free(tess, closed=False)
    mesh = trimesh.Trimesh(tess.points, tess.triangles, process=False)
    edges = mesh.edges_sorted
    _, count = np.unique(edges, axis=0, return_counts=True)
    assert set(count.tolist()) == {1, 2}  # boundary edges once, the rest twice
    assert independent_error(groups, tess) <= 1e-4


@pytest.mark.parametrize("degree", [2, 3])
def test_bounds_hold_for_random_patches(degree):
    """M_uu, M_uv, M_vv bound the second derivatives sampled densely, and a patch cut into the chosen
    segments (plain grid) is within tau everywhere sampled."""
    rng = np.random.default_rng(degree)
    patches = rng.normal(size=(40, degree + 1, degree + 1, 3))
    weights = rng.uniform(0.3, 3.0, size=(40, degree + 1, degree + 1))
    t = np.linspace(0.0, 1.0, 33)
    for w in (None, weights):
        m = second_derivative_bounds(patches, w)
        for k, order in enumerate([(2, 0), (1, 1), (0, 2)]):
            if w is None:
                second = evaluate_patches(patches, t, t, *order)
            else:  # central differences of the rational patch, on a fine grid
                h = 1e-4
                x = lambda uu, vv: dehomogenize(evaluate_patches(homogeneous(patches, w), uu, vv))[0]  # noqa: E731
                du, dv = order
                if order == (1, 1):
                    second = (x(t + h, t + h) - x(t + h, t - h) - x(t - h, t + h) + x(t - h, t - h)) / (4 * h * h)
                else:
                    a, b = (h, 0) if du else (0, h)
                    second = (x(t + a, t + b) - 2 * x(t, t) + x(t - a, t - b)) / (h * h)
            assert np.all(np.linalg.norm(second, axis=-1).max(axis=(1, 2)) <= m[:, k] * (1 + 1e-6) + 1e-6)
    tau = 0.01
    segments = patch_segments(second_derivative_bounds(patches), tau)
    assert np.all(bound(second_derivative_bounds(patches), segments) <= tau * (1 + 1e-12))
    for p in range(0, 40, 7):
        tpl = template((*segments[p], *segments[p][[0, 1, 0, 1]]))
        corners = evaluate_patches_at(np.repeat(patches[p : p + 1], tpl.uv.shape[0], 0), tpl.uv[:, 0], tpl.uv[:, 1])
        for b in BARYCENTRIC:
            uv = np.einsum("k,tkc->tc", b, tpl.uv[tpl.triangles])
            exact = evaluate_patches_at(np.repeat(patches[p : p + 1], len(uv), 0), uv[:, 0], uv[:, 1])
            linear = np.einsum("k,tkc->tc", b, corners[tpl.triangles])
            assert np.linalg.norm(exact - linear, axis=1).max() <= tau


def test_segments_are_few_and_isotropic_where_the_patch_is():
    bounds = np.array([[8.0, 0.0, 8.0], [8.0, 0.0, 0.0], [0.0, 0.0, 0.0], [800.0, 0.0, 8.0]])
    segments = patch_segments(bounds, 0.01)
    assert np.array_equal(segments[2], [1, 1])  # flat: two triangles
    assert segments[1, 1] == 1  # flat across: one segment that way
    assert segments[0].max() <= 1.3 * segments[0].min()  # a symmetric bound: nearly square
    assert segments[3, 0] > 3 * segments[3, 1]
    assert np.all(bound(bounds, segments) <= 0.01 * (1 + 1e-12))
    # and within 2 % of the fewest cells that meet the bound (brute force), also for random bounds
    more = np.random.default_rng(5).uniform(0, 50, (60, 3)) * (np.random.default_rng(6).random((60, 3)) < 0.8)
    bounds = np.concatenate([bounds, more])
    segments = patch_segments(bounds, 0.01)
    assert np.all(bound(bounds, segments) <= 0.01 * (1 + 1e-12))
    mu, mv = np.meshgrid(np.arange(1, 300), np.arange(1, 300), indexing="ij")
    for p, (a, b, c) in enumerate(bounds):
        ok = (a / mu**2 + 2 * b / (mu * mv) + c / mv**2) / 8 <= 0.01
        assert segments[p].prod() <= 1.02 * (mu * mv)[ok].min()
    with pytest.raises(ValueError):
        patch_segments(bounds, 0.0)


def random_keys(count, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        m = rng.integers(1, 7, 2)
        sides = m[[0, 1, 0, 1]] + rng.integers(0, 4, 4) * (rng.random(4) < 0.6)
        yield tuple(int(k) for k in (*m, *sides))


def test_templates_tile_the_square_without_t_junctions():
    for key in random_keys(400):
        tpl = template(key)
        uv, tri = tpl.uv, tpl.triangles
        a, b, c = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
        area = 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
        assert np.all(area > 0) and np.isclose(area.sum(), 1.0)  # counter-clockwise, covering the square once
        edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
        edge, count = np.unique(edges, axis=0, return_counts=True)
        assert count.max() == 2
        on_side = edge[count == 1]
        # the edges used once are exactly the side segments k/s -> (k+1)/s of the four sides
        assert len(on_side) == sum(key[2:])
        ends = uv[on_side]
        assert np.all(np.isclose(ends[:, 0, 0], ends[:, 1, 0]) | np.isclose(ends[:, 0, 1], ends[:, 1, 1]))
        assert np.all(np.isin(uv[on_side].ravel(), [0.0, 1.0]).reshape(-1, 2, 2).any(axis=2).all(axis=1))
        # every vertex is used, and every triangle fits the box 1/m_u x 1/m_v the bound assumes
        assert np.array_equal(np.unique(tri), np.arange(len(uv)))
        extent = np.ptp(uv[tri], axis=1)
        assert np.all(extent <= 1.0 / np.array(key[:2]) + 1e-12)
        assert template_triangles(np.array([key[:2]]), np.array([key[2:]]))[0] == len(tri)
        assert tpl.regular == (key[2:] == (key[0], key[1], key[0], key[1]))


def test_raising_interiors_never_adds_triangles_nor_changes_sides():
    keys = np.array(list(random_keys(300, seed=1)))
    segments, sides = keys[:, :2], keys[:, 2:]
    raised = fewer_triangles(segments, sides)
    assert np.all(raised >= segments)
    assert np.all(raised[:, [0, 1, 0, 1]] <= sides)
    assert np.all(template_triangles(raised, sides) <= template_triangles(segments, sides))


def test_plan_samples_every_shared_side_identically():
    """Both patches of a side name the same vertices for it, and those vertices sit at that side's samples."""
    surface = surface_of(SAMPLES / "high_valence.obj")
    groups, adjacency, _ = parts(surface)
    plan = plan_tolerance(groups, adjacency, 2e-3)
    across = adjacency.neighbours()
    assert len(np.unique(plan.keys[:, :2], axis=0)) > 3  # resolutions really differ between patches
    side_vertices = {}
    for tpl, patches, ids in plan.blocks():
        for s in range(4):
            run = ids[:, tpl.side_start[s] : tpl.side_start[s] + tpl.key[2 + s] - 1]
            for p, row in zip(patches.tolist(), run):
                side_vertices[p, s] = row
    for p in range(plan.n_patches):
        for s in range(4):
            q, r = across[p, s]
            mine, theirs = side_vertices[p, s], side_vertices[int(q), int(r)]
            same = adjacency.reversed[p, s] == adjacency.reversed[q, r]
            assert np.array_equal(mine, theirs if same else theirs[::-1])


def test_curvature_at_tolerance_vertices():
    """--curvature with --tolerance: the vertex mean of the patches' exact curvature; interior vertices
    carry their one patch's value, and with every patch at the same segments it is the uniform grid's."""
    surface = surface_of(SAMPLES / "twisted.obj")
    groups, adjacency, weights = parts(surface)
    tess = tessellate_to_tolerance(groups, adjacency, 2e-3)
    c = tolerance_curvature(groups, tess)
    plan = tess.plan
    tpl, patches, ids = next(plan.blocks())
    inner = ids[:, tpl.interior_start :]
    for k, p in enumerate(patches[:3]):
        g = 0 if p < len(groups[0]) else 1
        local = p - (0 if g == 0 else len(groups[0]))
        exact = patch_curvature(groups[g], tpl.uv[tpl.interior_start :, 0], tpl.uv[tpl.interior_start :, 1],
                                index=np.full(tpl.n_interior, local))
        np.testing.assert_allclose(c["kmax"][inner[k]], exact.kmax, rtol=1e-12)
    assert np.all(np.isfinite(c["kmax"]))
    uniform = tessellate_patches(groups, adjacency, 5)
    same = tessellation_curvature(groups, uniform.grid, len(uniform.points))
    assert np.isfinite(same["kmax"]).all()


def test_points_carry_attribute_columns_and_exact_normals():
    """Extra columns (texture coordinates, colours) are evaluated like x, y, z; normals are the patches'."""
    surface = surface_of(SAMPLES / "cube.obj")
    groups, adjacency, _ = parts(surface)
    extra = [np.concatenate([g, g[..., :1] * 2 + 1], axis=-1) for g in groups]
    tess = tessellate_to_tolerance(extra, adjacency, 1e-3)
    assert tess.points.shape[1] == 4
    np.testing.assert_allclose(tess.points[:, 3], tess.points[:, 0] * 2 + 1, atol=1e-12)
    mesh = trimesh.Trimesh(tess.points[:, :3], tess.triangles, process=False)
    assert np.all(np.einsum("ij,ij->i", mesh.vertex_normals, tess.normals) > 0.9)
    np.testing.assert_allclose(np.linalg.norm(tess.normals, axis=1), 1.0)


@pytest.mark.parametrize("name", ["torus.obj", "cube.obj", "high_valence.obj"])
def test_never_more_triangles_than_the_uniform_grid_with_the_same_guarantee(name):
    """The uniform N whose bound meets T on every patch is one of the plans tried: never beaten by transitions."""
    groups, adjacency, _ = parts(surface_of(SAMPLES / name))
    for tolerance in (1e-2, 1e-3):
        plan = plan_tolerance(groups, adjacency, tolerance)
        bounds = np.concatenate([second_derivative_bounds(g) for g in groups])
        m = 1
        while np.any(bound(bounds, np.full((len(bounds), 2), m)) > tolerance * plan.diagonal):
            m += 1
        assert plan.n_triangles <= 2 * m * m * plan.n_patches
        assert np.all(bound(bounds, plan.segments) <= tolerance * plan.diagonal * (1 + 1e-12))
