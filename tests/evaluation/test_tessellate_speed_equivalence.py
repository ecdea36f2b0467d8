"""The fast welded tessellation and adjacency against plain reference code.

The references are the straightforward versions: every sample of every patch
by a Bernstein einsum, written in patch order (the last patch wins), on the
welded numbering written out as in its definition, and the adjacency by
per-column gathers with a cumsum ranking. Ids and triangles must be equal;
points agree to 1e-13 of the bounding-box diagonal, and normals to 4 machine
epsilons times the condition number of the normal,
(A_u |x_v| + |x_u| A_v) / |x_u x x_v| with A = sum |B'| |B| |P| bounding the
rounding of the derivatives: 1e-14 to 1e-13 at ordinary points, more only where
the normal is ill-conditioned (the valence-12 apex of high_valence, where the
corner normal from first differences and the einsum one differ by 1e-12).
"""
from __future__ import annotations

import numpy as np
import pytest

import c1surf.evaluation.tessellate as tessellate_module
import c1surf.evaluation.adjacency as adjacency_module
from c1surf.evaluation.adjacency import PatchAdjacency, _first_appearance, _first_appearances, _renumber, patch_adjacency
from c1surf.evaluation.bezier import bernstein_basis
from c1surf.evaluation.rational import evaluate_rational, homogeneous
from c1surf.construction.surface import Surface
from c1surf.evaluation.tessellate import Tessellation, tessellate, tessellate_patches, welded_grid_from_ids
from c1surf.io.meshes.obj import read_obj

from conftest import SAMPLES, fan, grid, open_cylinder, surface_of

RESOLUTIONS = [2, 3, 8]
MIXED = ["twisted", "high_valence", "hexagon_all_six_valent", "double_torus", "triangular_prism"]


# -- open meshes -----------------------------------------------------------------------


OPEN = {"grid": lambda: grid(4, lambda x, y: 0.3 * np.sin(x) * np.cos(y)), "fan": lambda: fan(5), "cylinder": lambda: open_cylinder(7, 2)}
_SURFACES: dict = {}


def surface(name: str) -> Surface:
    if name not in _SURFACES:
        _SURFACES[name] = Surface(*OPEN[name]()) if name in OPEN else surface_of(SAMPLES / f"{name}.obj")
    return _SURFACES[name]


# -- references ------------------------------------------------------------------------


def reference_grid(adjacency: PatchAdjacency, n: int) -> np.ndarray:
    """(P, n, n) int64: corners by id, then n-2 samples per edge in edge direction, then n-2 squared per patch,
    with unused ids skipped (written out as defined, side by side)."""
    corners, edges, back = (np.asarray(a) for a in (adjacency.corners, adjacency.edges, adjacency.reversed))
    p, inner = corners.shape[0], n - 2
    n_corners = int(corners.max()) + 1 if corners.size else 0
    n_edges = int(edges.max()) + 1 if edges.size else 0
    grid = np.empty((p, n, n), dtype=np.int64)
    grid[:, 0, 0], grid[:, -1, 0], grid[:, -1, -1], grid[:, 0, -1] = corners.T
    if inner > 0:
        k = np.arange(inner)
        side = [n_corners + edges[:, s, None] * inner + np.where(back[:, s, None], inner - 1 - k, k) for s in range(4)]
        grid[:, 1:-1, 0], grid[:, -1, 1:-1], grid[:, 1:-1, -1], grid[:, 0, 1:-1] = side
        grid[:, 1:-1, 1:-1] = n_corners + n_edges * inner + np.arange(p * inner * inner).reshape(p, inner, inner)
    used = np.zeros(n_corners + n_edges * max(inner, 0) + p * max(inner, 0) ** 2, dtype=bool)
    used[grid] = True
    return (np.cumsum(used) - 1)[grid]


def reference_triangles(grid: np.ndarray) -> np.ndarray:
    """(2 (n-1)^2 P, 3): cells (i, j) of each patch row-major, (i,j) (i+1,j) (i+1,j+1) and (i,j) (i+1,j+1) (i,j+1)."""
    n = grid.shape[1]
    out = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = grid[:, i, j], grid[:, i + 1, j], grid[:, i + 1, j + 1], grid[:, i, j + 1]
            out += [np.stack([a, b, c], 1), np.stack([a, c, d], 1)]
    return np.stack(out, axis=1).reshape(-1, 3)


def reference_samples(groups, grid: np.ndarray, n: int):
    """points (V, dim), normals (V, 3) and the normals' conditioning (V,): every patch's samples, in order."""
    count = int(grid.max()) + 1
    points, normals, condition = np.full((count, groups[0].shape[-1]), np.nan), np.full((count, 3), np.nan), np.ones(count)
    t = np.linspace(0.0, 1.0, n)
    start = 0
    for g in groups:
        if len(g) == 0:
            continue
        d = g.shape[1] - 1
        b, db = bernstein_basis(d, t), bernstein_basis(d, t, 1)
        ids = grid[start : start + len(g)]
        points[ids] = np.einsum("ai,bj,pijd->pabd", b, b, g)
        xu = np.einsum("ai,bj,pijd->pabd", db, b, g[..., :3])
        xv = np.einsum("ai,bj,pijd->pabd", b, db, g[..., :3])
        cross = np.cross(xu, xv)
        length = np.linalg.norm(cross, axis=-1)
        normals[ids] = cross / length[..., None]
        bound_u = np.linalg.norm(np.einsum("ai,bj,pijd->pabd", abs(db), abs(b), abs(g[..., :3])), axis=-1)
        bound_v = np.linalg.norm(np.einsum("ai,bj,pijd->pabd", abs(b), abs(db), abs(g[..., :3])), axis=-1)
        condition[ids] = (bound_u * np.linalg.norm(xv, axis=-1) + np.linalg.norm(xu, axis=-1) * bound_v) / length
        start += len(g)
    return points, normals, condition


def assert_matches_reference(tess: Tessellation, groups, adjacency: PatchAdjacency, n: int, normals_and_condition=None):
    grid = reference_grid(adjacency, n)
    assert tess.grid.shape == grid.shape and np.array_equal(tess.grid, grid)
    assert np.array_equal(tess.triangles, reference_triangles(grid))
    assert np.array_equal(tess.triangle_patch, np.repeat(np.arange(grid.shape[0]), 2 * (n - 1) ** 2))
    points, normals, condition = reference_samples(groups, grid, n)
    if normals_and_condition is not None:
        points = points[:, :-1] / points[:, -1:]  # homogeneous
        normals, condition = normals_and_condition
    assert tess.points.shape == points.shape and tess.normals.shape == normals.shape
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) or 1.0
    np.testing.assert_allclose(tess.points, points, rtol=0, atol=1e-13 * diagonal)
    assert np.all(np.abs(tess.normals - normals).max(axis=1) <= 4 * np.finfo(float).eps * condition)


# -- the tessellation ------------------------------------------------------------------


@pytest.mark.parametrize("n", RESOLUTIONS)
@pytest.mark.parametrize("name", MIXED + list(OPEN))
def test_matches_reference(name, n):
    s = surface(name)
    groups = [s.biquadratic, s.bicubic]
    adjacency = patch_adjacency(s.refined, s.frames)
    tess = tessellate_patches(groups, adjacency, n)
    assert tess.grid.dtype == np.int32 and tess.triangles.dtype == np.int32  # ids fit
    assert tess.points.dtype == np.float64 and tess.normals.dtype == np.float64
    assert_matches_reference(tess, groups, adjacency, n)
    assert np.array_equal(welded_grid_from_ids(adjacency, n), tess.grid)


@pytest.mark.parametrize("n", RESOLUTIONS)
def test_rational_matches_reference(n):
    mesh = read_obj(SAMPLES / "twisted.obj")
    weights = np.random.default_rng(3).uniform(0.5, 2.0, mesh.n_vertices)
    s = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, weights=weights)
    groups, patch_weights = [s.biquadratic, s.bicubic], s.patch_weights
    adjacency = patch_adjacency(s.refined, s.frames)
    tess = tessellate_patches(groups, adjacency, n, patch_weights)
    grid = reference_grid(adjacency, n)
    # the rational tessellation recomputes the normals with evaluate_rational: those agree to rounding (~1e-15)
    normals, condition = np.full((tess.points.shape[0], 3), np.nan), np.full(tess.points.shape[0], 10.0)
    t, start = np.linspace(0.0, 1.0, n), 0
    for g, w in zip(groups, patch_weights):
        if len(g):
            normals[grid[start : start + len(g)]] = evaluate_rational(g, w, t, t)[1]
            start += len(g)
    homogeneous_groups = [homogeneous(g, w) for g, w in zip(groups, patch_weights)]
    assert_matches_reference(tess, homogeneous_groups, adjacency, n, (normals, condition))


@pytest.mark.parametrize("name", MIXED + list(OPEN) + ["rational"])
def test_tessellate_at_resolution_2_numbers_corners_only(name):
    """``tessellate`` at N = 2 numbers the corners alone (no side labels): bit for bit the tessellation of the
    whole adjacency, rational patches too."""
    if name == "rational":
        mesh = read_obj(SAMPLES / "twisted.obj")
        s = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points,
                    weights=np.random.default_rng(3).uniform(0.5, 2.0, mesh.n_vertices))
    else:
        s = surface(name)
    groups = [s.biquadratic, s.bicubic]
    whole = tessellate_patches(groups, patch_adjacency(s.refined, s.frames), 2, s.patch_weights)
    corners_only = tessellate(groups, s.refined, s.frames, 2, s.patch_weights)
    for key in ("points", "normals", "triangles", "grid"):
        assert np.array_equal(getattr(whole, key), getattr(corners_only, key)), key


@pytest.mark.parametrize("n", RESOLUTIONS)
def test_extra_coordinates(n):
    """Points may carry attributes after x, y, z (``convert`` with attributes); normals use x, y, z."""
    s = surface("twisted")
    groups = [np.concatenate([g, g[..., :2] ** 2], axis=-1) for g in (s.biquadratic, s.bicubic)]
    adjacency = patch_adjacency(s.refined, s.frames)
    tess = tessellate_patches(groups, adjacency, n)
    assert tess.points.shape[1] == 5
    assert_matches_reference(tess, groups, adjacency, n)


@pytest.mark.parametrize("n", RESOLUTIONS)
def test_ids_with_gaps(n):
    """Adjacency ids with unused values (not from c1surf) are closed up and every sample is evaluated."""
    s = surface("triangular_prism")
    groups = [s.biquadratic, s.bicubic]
    a = patch_adjacency(s.refined, s.frames)
    gappy = PatchAdjacency(a.corners * 2 + 1, a.edges + (a.edges >= 5) * 3, a.reversed)
    tess = tessellate_patches(groups, gappy, n)
    assert_matches_reference(tess, groups, gappy, n)


@pytest.mark.parametrize("n", RESOLUTIONS)
def test_blocks_and_threads_change_nothing(monkeypatch, n):
    """Tiny blocks (many, split across groups) give the same ids and values to rounding (BLAS may pick
    other kernels for other shapes); for given blocks, any number of threads gives bit-identical output."""
    s = surface("high_valence")
    groups = [s.biquadratic, s.bicubic]
    adjacency = patch_adjacency(s.refined, s.frames)
    default = tessellate_patches(groups, adjacency, n)
    for samples, grid_samples in [(37, 64), (5, 1)]:
        monkeypatch.setattr(tessellate_module, "_BLOCK_SAMPLES", samples)
        monkeypatch.setattr(tessellate_module, "_GRID_BLOCK_SAMPLES", grid_samples)
        runs = []
        for workers in (1, 2, 3):
            monkeypatch.setenv("C1SURF_THREADS", str(workers))
            runs.append(tessellate_patches(groups, adjacency, n))
        for got in runs[1:]:
            for key in ("points", "normals", "triangles", "grid"):
                assert np.array_equal(getattr(got, key), getattr(runs[0], key)), (key, samples)
        assert np.array_equal(runs[0].grid, default.grid) and np.array_equal(runs[0].triangles, default.triangles)
        np.testing.assert_allclose(runs[0].points, default.points, rtol=0, atol=1e-15)
        np.testing.assert_allclose(runs[0].normals, default.normals, rtol=0, atol=1e-13)


def test_no_patches():
    empty = np.zeros((0, 4), dtype=np.int64)
    adjacency = PatchAdjacency(empty, empty.copy(), np.zeros((0, 4), dtype=bool))
    for n in RESOLUTIONS:
        tess = tessellate_patches([np.zeros((0, 3, 3, 3)), np.zeros((0, 4, 4, 3))], adjacency, n)
        assert tess.points.shape == (0, 3) and tess.normals.shape == (0, 3)
        assert tess.triangles.shape == (0, 3) and tess.grid.shape == (0, n, n) and tess.triangle_patch.shape == (0,)


def test_triangle_patch_is_made_on_demand_or_kept():
    s = surface("cube")
    tess = tessellate_patches([s.biquadratic, s.bicubic], patch_adjacency(s.refined, s.frames), 3)
    assert np.array_equal(tess.triangle_patch, np.arange(tess.triangles.shape[0]) // 8)
    given = np.arange(tess.triangles.shape[0])
    kept = Tessellation(tess.points, tess.normals, tess.triangles, given, tess.grid)  # positional, as the rational tessellation builds it
    assert kept.triangle_patch is given


# -- the adjacency ---------------------------------------------------------------------


def reference_first_appearance(labels: np.ndarray) -> np.ndarray:
    flat = labels.ravel()
    _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
    rank = np.empty(first.size, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(first.size)
    return rank[inverse.ravel()].reshape(labels.shape)


@pytest.mark.parametrize("high", [7, 1000, 10**12])  # dense labels, and sparse ones (sorted path)
def test_first_appearances(high):
    rng = np.random.default_rng(high % 1000)
    labels = rng.integers(0, high, (500, 4))
    ids, first = _first_appearances(labels)
    assert np.array_equal(ids, reference_first_appearance(labels))
    assert np.array_equal(_first_appearance(labels), ids)
    # first: where each id appears first, in increasing order
    assert np.all(np.diff(first) > 0) and np.array_equal(ids.ravel()[first], np.arange(first.size))
    assert np.array_equal(first, np.sort(np.unique(labels.ravel(), return_index=True)[1]))


def reference_patch_adjacency(refined, frames) -> PatchAdjacency:
    frames = np.asarray(frames, dtype=np.int64).reshape(-1, 4)
    face, twin = refined.face, refined.twin
    e0, e1, e2, e3 = frames.T
    corner_faces = np.stack([face[e2], face[e3], face[e0], face[e1]], axis=1)
    x = np.stack([twin[e3], twin[e0], e1, e2], axis=1)
    edges = reference_first_appearance(np.minimum(x, twin[x]))
    flat = edges.ravel()
    first = np.full(flat.max() + 1, -1)
    first[flat[::-1]] = np.arange(flat.size)[::-1]
    key = x.ravel()
    return PatchAdjacency(reference_first_appearance(corner_faces), edges, (key != key[first[flat]]).reshape(edges.shape))


@pytest.mark.parametrize("name", MIXED + list(OPEN))
def test_patch_adjacency_matches_reference(name):
    s = surface(name)
    got = patch_adjacency(s.refined, s.frames)
    assert got == reference_patch_adjacency(s.refined, s.frames)
    # ids are int32 while 4 P < 2^31 (half the memory of the largest arrays), else int64
    assert got.corners.dtype == np.int32 and got.edges.dtype == np.int32 and got.reversed.dtype == bool


@pytest.mark.parametrize("name", ["high_valence", "triangular_prism", "fan"])
def test_patch_adjacency_by_tiny_blocks_and_parts(monkeypatch, name):
    """Blocks of a few patches (cutting through both kinds) and the frames given as (quad, cubic) parts
    change nothing: the same ids, and no (P, 4) copy of the frames is needed."""
    s = surface(name)
    expected = reference_patch_adjacency(s.refined, s.frames)
    monkeypatch.setattr(adjacency_module, "_ADJACENCY_BLOCK", 3)
    assert patch_adjacency(s.refined, s.frames) == expected
    assert patch_adjacency(s.refined, (s.quad_frames, s.cubic_frames)) == expected


@pytest.mark.parametrize("high", [7, 1000, 10**12])  # dense labels, and sparse ones (sorted path)
@pytest.mark.parametrize("block", [1, 5, 1 << 16])
def test_renumber_in_place(monkeypatch, high, block):
    monkeypatch.setattr(adjacency_module, "_ADJACENCY_BLOCK", block)
    labels = np.random.default_rng(high % 1000).integers(0, high, 2001)
    ids, first = _first_appearances(labels)
    flat = labels.copy()
    assert np.array_equal(_renumber(flat), first) and np.array_equal(flat, ids)


def reference_partners(adjacency: PatchAdjacency) -> np.ndarray:
    flat = np.asarray(adjacency.edges).reshape(-1)
    out = np.full(flat.size, -1, dtype=np.int64)
    for edge in np.unique(flat):
        sides = np.flatnonzero(flat == edge)
        if sides.size == 2:
            out[sides[0]], out[sides[1]] = sides[1], sides[0]
    return out


@pytest.mark.parametrize("block", [1, 3, 1 << 16])
def test_partners_by_blocks(monkeypatch, block):
    """Pairs, boundary sides, an edge of three sides and unused ids (a patch file's), at any block size."""
    monkeypatch.setattr(adjacency_module, "_ADJACENCY_BLOCK", block)
    for name in ("high_valence", "fan", "triangular_prism"):
        a = patch_adjacency(surface(name).refined, surface(name).frames)
        got = a.partners()
        assert got.dtype == np.int32 and np.array_equal(got, reference_partners(a))
    edges = np.array([[0, 1, 2, 3], [3, 4, 5, 0], [0, 7, 9, 9]])  # edge 0 thrice, 6 and 8 unused
    odd = PatchAdjacency(edges, edges, np.zeros((3, 4), dtype=bool))
    assert np.array_equal(odd.partners(), reference_partners(odd))
