"""C0 creases (SurfaceOptions.exact_creases; mesh.creases.sheets, stencils.creases.mirror_rows): the
sheets on either side of an infinitely sharp crease meet exactly along one curve and stay G1 inside.

Shared patch sides are found from the geometry alone (``adjacency_from_geometry``) and measured
independently: a crease pair is a pair of sides whose normals differ (by the crease's angle), every
other pair must be G1.
"""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.features import SharpFeatures
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.adjacency import adjacency_from_geometry
from c1surf.evaluation.bezier import raise_degree
from c1surf.evaluation.smoothness import side_frames
from c1surf.io.meshes.read import read_mesh
from c1surf.mesh.creases.sheets import exact_crease_vertices
from c1surf.mesh.halfedges import build_halfedges

from conftest import SAMPLES, shared_mesh

SHARP = 10.0


def all_edges(sizes, corners) -> np.ndarray:
    faces = np.split(corners, np.cumsum(sizes)[:-1])
    return np.array(sorted({tuple(sorted((int(f[i]), int(f[(i + 1) % len(f)])))) for f in faces for i in range(len(f))}))


def side_pairs(surface: Surface):
    """Every shared side pair found from the geometry: (gap (k,), normal jump (k,) in rad, diagonal)."""
    quads, cubics = surface.biquadratic, surface.bicubic
    cubic = np.concatenate([raise_degree(quads, 3, 3), cubics])
    adjacency = adjacency_from_geometry([quads, cubics], 1e-9)
    across = adjacency.neighbours()
    p, side = np.nonzero(across[:, :, 0] >= 0)
    q, q_side = across[p, side, 0], across[p, side, 1]
    once = p < q
    p, side, q, q_side = p[once], side[once], q[once], q_side[once]
    t = np.linspace(0.0, 1.0, 11)
    flip = adjacency.reversed[p, side] != adjacency.reversed[q, q_side]
    a, na = side_frames(cubic, 4 * p + side, t)
    b, nb = side_frames(cubic, 4 * q + q_side, t, reverse=flip)
    gap = np.abs(a - b).reshape(p.size, -1).max(axis=1)
    # the angle from the cross product: arccos of a dot product near 1 keeps only half the digits
    angle = np.arctan2(np.linalg.norm(np.cross(na, nb), axis=1), np.abs(np.einsum("ij,ij->i", na, nb)))
    jump = angle.reshape(p.size, -1)
    points = np.concatenate([quads.reshape(-1, 3), cubics.reshape(-1, 3)])
    unmatched = int((across[:, :, 0] < 0).sum())
    return gap, jump, float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))), unmatched


def crease_and_smooth(surface: Surface):
    """(crease gap, smooth gap, smooth jump, crease pairs, unmatched sides), gaps relative to the diagonal.

    A crease pair has a normal jump above 1e-6 rad somewhere along it (a one-face sector's patch has
    a straight angle where the crease passes its corner: its normal there is undefined, NaN)."""
    gap, jump, diagonal, unmatched = side_pairs(surface)
    crease = ~np.all(jump <= 1e-6, axis=1)
    smooth_jump = float(jump[~crease].max()) if (~crease).any() else 0.0
    return (float(gap[crease].max(initial=0)) / diagonal, float(gap[~crease].max(initial=0)) / diagonal, smooth_jump,
            int(crease.sum()), unmatched)


def exact_surface(mesh, features, points=None) -> Surface:
    return Surface(mesh.face_sizes, mesh.face_vertices, mesh.points if points is None else points,
                   SurfaceOptions(exact_creases=True), features=features)


def sharp_everywhere(mesh) -> SharpFeatures:
    edges = all_edges(mesh.face_sizes, mesh.face_vertices)
    return SharpFeatures(edges, np.full(len(edges), SHARP))


def creased_torus(nu=10, nv=8, noise=0.03, hexagon=False, seed=0):
    """A quad torus with a ring of crease edges (every crease vertex 2 | 2), two triangles away from
    it (A3 holes) and, with ``hexagon``, a hexagon against it (an even hole perturbed beside the crease)."""
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    u, v = 2 * np.pi * i / nu, 2 * np.pi * j / nv
    points = np.stack([(1 + 0.4 * np.cos(v)) * np.cos(u), (1 + 0.4 * np.cos(v)) * np.sin(u), 0.4 * np.sin(v)], -1).reshape(-1, 3)
    points += noise * rng.standard_normal(points.shape)
    at = lambda a, b: (a % nu) * nv + (b % nv)
    faces = [[at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)] for a in range(nu) for b in range(nv)]
    split = faces.index([at(3, 4), at(4, 4), at(4, 5), at(3, 5)])
    q = faces.pop(split)
    faces += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    if hexagon:
        gone = (faces.index([at(6, 0), at(7, 0), at(7, 1), at(6, 1)]), faces.index([at(7, 0), at(8, 0), at(8, 1), at(7, 1)]))
        faces = [f for n, f in enumerate(faces) if n not in gone] + [[at(6, 0), at(7, 0), at(8, 0), at(8, 1), at(7, 1), at(6, 1)]]
    crease = np.array([[at(a, 0), at(a + 1, 0)] for a in range(nu)])
    sizes = np.array([len(f) for f in faces])
    return points, sizes, np.concatenate(faces), SharpFeatures(crease, np.full(len(crease), SHARP))


def test_a_cube_with_every_edge_sharp_is_the_cube():
    mesh = read_mesh(SAMPLES / "cube.obj")  # side 2, centred on the origin
    surface = exact_surface(mesh, sharp_everywhere(mesh))
    points = np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)])
    # every coefficient lies on a face plane of the cube and inside it: every surface point is on the cube
    assert np.min(np.abs(np.abs(points) - 1.0), axis=1).max() <= 1e-12
    assert np.abs(points).max() <= 1.0 + 1e-12
    # the eight corners are patch corners
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    patch_corners = np.concatenate([surface.biquadratic[:, ::2, ::2].reshape(-1, 3), surface.bicubic[:, ::3, ::3].reshape(-1, 3)])
    assert max(np.linalg.norm(patch_corners - c, axis=1).min() for c in corners) <= 1e-12
    # each face of the cube is a planar sheet: 16 patches, all on its plane
    assert surface.n_patches == 96 and len(surface.topology.crease_sheets.cut_edges) == 12
    crease_gap, smooth_gap, smooth_jump, crease_pairs, unmatched = crease_and_smooth(surface)
    assert crease_pairs == 48 and unmatched == 0
    assert crease_gap <= 1e-12 and smooth_gap <= 1e-12 and smooth_jump <= 1e-12


def test_opensubdiv_cube_creases2_meets_along_its_creases_and_interpolates_its_corners():
    mesh = read_mesh(shared_mesh("opensubdiv/catmark_cube_creases2.obj"))  # 11 sharp edges: corners 1|1|1, creases 1|2
    tags = mesh.tags
    surface = exact_surface(mesh, SharpFeatures(tags.crease_edges, tags.crease_sharpness))
    sheets = surface.topology.crease_sheets
    assert len(sheets.cut_edges) == 11 and len(sheets.kept_edges) == 0
    crease_gap, smooth_gap, smooth_jump, crease_pairs, unmatched = crease_and_smooth(surface)
    assert crease_pairs > 0 and unmatched == 0
    assert crease_gap <= 1e-12 and smooth_gap <= 1e-12 and smooth_jump <= 1e-10
    # the corners (three sharp edges) are reached
    halfedges = build_halfedges(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices)
    sharp = np.isin(np.sort(np.stack([halfedges.origin, halfedges.dest], 1), 1).view([("", np.int64)] * 2),
                    np.sort(tags.crease_edges[tags.crease_sharpness >= SHARP], 1).astype(np.int64).view([("", np.int64)] * 2)).ravel()
    _, exact, corner = exact_crease_vertices(halfedges, sharp, np.zeros(mesh.n_vertices, bool))
    assert exact[corner].all() and corner.sum() == 6
    patch_corners = np.concatenate([surface.biquadratic[:, ::2, ::2].reshape(-1, 3), surface.bicubic[:, ::3, ::3].reshape(-1, 3)])
    for vertex in mesh.points[corner]:
        assert np.linalg.norm(patch_corners - vertex, axis=1).min() <= 1e-12


@pytest.mark.parametrize("hexagon", [False, True])
def test_a_creased_torus_is_exact_along_its_crease_and_g1_elsewhere(hexagon):
    points, sizes, corners, features = creased_torus(hexagon=hexagon)
    surface = Surface(sizes, corners, points, SurfaceOptions(exact_creases=True), features=features)
    crease_gap, smooth_gap, smooth_jump, crease_pairs, unmatched = crease_and_smooth(surface)
    assert unmatched == 0 and crease_pairs == 40  # 10 crease edges, 4 patch sides along each
    assert crease_gap <= 1e-12 and smooth_gap <= 1e-12 and smooth_jump <= 1e-10
    assert len(surface.bicubic) > 0  # the triangles (and the hexagon) are A3 holes


def test_c0_creases_are_linear_in_the_points():
    points, sizes, corners, features = creased_torus(hexagon=True)
    surface = Surface(sizes, corners, points, SurfaceOptions(exact_creases=True), features=features)
    moved = points + 0.05 * np.random.default_rng(3).standard_normal(points.shape)
    fresh = Surface(sizes, corners, moved, SurfaceOptions(exact_creases=True), features=features)
    surface.update_points(moved)
    assert np.abs(surface.biquadratic - fresh.biquadratic).max() <= 1e-13
    assert np.abs(surface.bicubic - fresh.bicubic).max() <= 1e-13
    stacked = np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)])
    assert np.abs(surface.stencil() @ moved - stacked).max() <= 1e-13


def test_a_line_between_two_darts_is_cut_up_to_both_ends():
    # catmark_cubes_infsharp: the chain 9 - 8 - 10 ends inside the surface at both ends (darts): cut like the
    # rest, each end a dart's hole (construction.stencils.holes.dart)
    mesh = read_mesh(shared_mesh("opensubdiv/catmark_cubes_infsharp.obj"))
    tags = mesh.tags
    features = SharpFeatures(tags.crease_edges, tags.crease_sharpness, tags.corner_vertices, tags.corner_sharpness)
    surface = exact_surface(mesh, features)
    sheets = surface.topology.crease_sheets
    assert len(sheets.kept_edges) == 0 and len(sheets.dart_edges) == 0 and len(sheets.cut_edges) == 17
    assert sorted(sheets.vertex_name[sheets.dart_vertex].tolist()) == [9, 10]
    assert sheets.inexact_vertices.size == 0
    crease_gap, smooth_gap, smooth_jump, crease_pairs, unmatched = crease_and_smooth(surface)
    assert unmatched == 0 and crease_pairs == len(surface.crease_sides)
    assert crease_gap <= 1e-12 and smooth_jump <= 1e-10


def test_without_the_option_nothing_is_cut():
    mesh = read_mesh(SAMPLES / "cube.obj")
    features = sharp_everywhere(mesh)
    plain = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, features=features)
    assert plain.topology.crease_sheets is None
    crease_gap, smooth_gap, smooth_jump, crease_pairs, unmatched = crease_and_smooth(plain)
    assert crease_pairs == 0 and smooth_jump <= 1e-10  # the sharpest G1 crease


def test_exact_creases_refuse_vertex_interpolation():
    with pytest.raises(ValueError, match="exact creases"):
        SurfaceOptions(exact_creases=True, interpolate_vertices=True).check()


def _infinitely_sharp(path) -> bool:
    mesh = read_mesh(path)
    return bool(np.any(mesh.tags.crease_sharpness >= SHARP) or np.any(mesh.tags.corner_sharpness >= SHARP))


SHARP_CORPUS = ["catmark_cube_corner4", "catmark_cube_creases2", "catmark_cubes_infsharp", "catmark_edgenone",
                "catmark_edgeonly", "catmark_fvar_project0", "catmark_inf_crease0", "catmark_inf_crease1",
                "catmark_single_crease", "catmark_val2_interior"]


@pytest.mark.parametrize("name", SHARP_CORPUS)
def test_opensubdiv_files_with_infinitely_sharp_tags_meet_exactly_where_cut_and_stay_g1(name):
    from c1surf.api import check_surface, surface_from_file

    path = shared_mesh(f"opensubdiv/{name}.obj")
    assert _infinitely_sharp(path)
    surface, _ = surface_from_file(path, exact_creases=True)
    report = check_surface(surface)
    sheets = surface.topology.crease_sheets
    assert report.unpaired_crease_sides == 0 and report.crease_edges == len(surface.crease_sides)
    assert report.relative_crease_gap <= 1e-12 and report.relative_gap <= 1e-12
    assert report.max_normal_jump <= 1e-10
    cut = 0 if sheets is None else len(sheets.cut_edges)
    # cut: closed crease components, and those reaching the boundary, once too large sectors are merged
    # (fvar_project0: 1 | 3 sectors, inf_crease1: 2 | 4 and corner sectors of 2 and 3 faces); darts are cut
    # up to their end (the dart's hole): the chain 0 - 4 of inf_crease1, the edge 16 - 17 of inf_crease0, the
    # line 9 - 8 - 10 of cubes_infsharp (darts at both ends)
    assert cut == {"catmark_cube_creases2": 11, "catmark_cubes_infsharp": 17, "catmark_edgenone": 18,
                   "catmark_single_crease": 4, "catmark_val2_interior": 3, "catmark_fvar_project0": 4,
                   "catmark_inf_crease1": 8, "catmark_inf_crease0": 11}.get(name, 0)
    darts = 0 if sheets is None else sheets.dart_vertex.size
    assert darts == {"catmark_inf_crease1": 1, "catmark_inf_crease0": 1, "catmark_cubes_infsharp": 2}.get(name, 0)


def test_a_crease_reaching_the_boundary_ends_at_a_corner_of_the_boundary_curve():
    # catmark_edgenone: crease tags along boundaries and a tagged corner (vertex 48) on one
    from c1surf.api import surface_from_file

    surface, mesh = surface_from_file(shared_mesh("opensubdiv/catmark_edgenone.obj"), exact_creases=True)
    assert 48 in mesh.tags.corner_vertices
    patch_corners = np.concatenate([surface.biquadratic[:, ::2, ::2].reshape(-1, 3), surface.bicubic[:, ::3, ::3].reshape(-1, 3)])
    assert np.linalg.norm(patch_corners - mesh.points[48], axis=1).min() <= 1e-12
    # a boundary loop that no crease reaches keeps the ghost layer's rule: the one grid of the four
    # without tags (a quarter of the patches) is the untagged surface's (to round-off)
    from scipy.spatial import cKDTree

    plain, _ = surface_from_file(shared_mesh("opensubdiv/catmark_edgenone.obj"), ignore_tags=True)
    flat = lambda s: s.biquadratic.reshape(len(s.biquadratic), -1)
    distance, _ = cKDTree(flat(surface)).query(flat(plain))
    assert (distance <= 1e-12).sum() >= len(plain.biquadratic) // 4


def random_rings(seed, nu=8, nv=6):
    """(points, sizes, corners, rings (k, 2), rng): two rings each way around ``creased_torus``; even seeds
    keep them off the triangles' and the hexagon's vertices (exact), odd seeds anywhere."""
    rng = np.random.default_rng(100 + seed)
    points, sizes, corners, _ = creased_torus(nu=nu, nv=nv, noise=0.05, hexagon=bool(seed % 2), seed=seed)
    at = lambda a, b: (a % nu) * nv + (b % nv)
    around_u, around_v = (np.arange(nv), np.arange(nu)) if seed % 2 else ([2, 3], [0, 1, 2])
    rings = [[at(a, b), at(a + 1, b)] for b in rng.choice(around_u, 2, replace=False) for a in range(nu)]
    rings += [[at(a, b), at(a, b + 1)] for a in rng.choice(around_v, 2, replace=False) for b in range(nv)]
    return points, sizes, corners, np.unique(np.sort(np.array(rings), axis=1), axis=0), rng


@pytest.mark.parametrize("seed", range(8))
def test_random_crease_rings_on_a_noisy_quad_torus_meet_exactly_or_stay_g1(seed):
    """Random rings of edges around a noisy quad torus made infinitely sharp, plus a few random edges:
    crossings are corners of four one-face sectors, rings through the triangles or the hexagon have
    vertices that are not exact, stray edges make darts. Every component the sheets cut meets exactly,
    everything else stays G1, nothing is left unpaired, and it stays linear in the points."""
    from c1surf.api import check_surface

    points, sizes, corners, rings, rng = random_rings(seed)
    edges = all_edges(sizes, corners)
    stray = edges[rng.random(len(edges)) < (0.03 if seed % 4 == 3 else 0.0)]
    chosen = np.unique(np.sort(np.concatenate([np.array(rings), stray]), axis=1), axis=0)
    features = SharpFeatures(chosen, np.full(len(chosen), SHARP))
    surface = Surface(sizes, corners, points, SurfaceOptions(exact_creases=True), features=features)
    report = check_surface(surface)
    assert report.unpaired_crease_sides == 0 and report.overshared_edges == 0 and report.boundary_edges == 0
    assert report.relative_crease_gap <= 1e-12 and report.relative_gap <= 1e-12
    assert report.max_normal_jump <= 1e-10
    assert report.crease_edges == len(surface.crease_sides)
    moved = points + 0.02 * rng.standard_normal(points.shape)
    fresh = Surface(sizes, corners, moved, SurfaceOptions(exact_creases=True), features=features)
    surface.update_points(moved)
    assert np.abs(surface.biquadratic - fresh.biquadratic).max() <= 1e-12
    assert np.abs(surface.bicubic - fresh.bicubic).max() <= 1e-12


def test_some_random_rings_are_cut():
    """The random rings above do exercise the sheets: the even seeds' rings are all cut."""
    cut = 0
    for seed in range(0, 8, 2):
        points, sizes, corners, rings, _ = random_rings(seed)
        surface = Surface(sizes, corners, points, SurfaceOptions(exact_creases=True),
                          features=SharpFeatures(rings, np.full(len(rings), SHARP)))
        cut += surface.topology.crease_sheets is not None
    assert cut == 4
