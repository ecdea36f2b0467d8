"""evaluation.compare on plain arrays: structure before coefficients, weights, merged pieces, sources, meshes."""
from __future__ import annotations

import dataclasses

import numpy as np

from c1surf.evaluation.compare import compare_meshes, compare_patch_sets, largest_moves
from c1surf.evaluation.merge import merge_biquadratic
from c1surf.evaluation.patch_set import surface_patch_set

from conftest import SAMPLES, surface_of


def twisted():
    surface = surface_of(SAMPLES / "twisted.obj")
    return dataclasses.replace(surface_patch_set(surface), merged=merge_biquadratic(surface))


def copy(ps, **changes):
    fields = {"groups": [g.copy() for g in ps.groups], "merged": list(ps.merged)}
    fields.update(changes)
    return dataclasses.replace(ps, **fields)


def test_largest_moves_sorts_and_counts():
    a = np.zeros((3, 2, 3))
    b = a.copy()
    b[2, 1, 0], b[0, 0, 2] = 3.0, -1.0
    worst, count, top = largest_moves(a, b, 10.0, 0.05, show=1)
    assert count == 2 and top == 0.3 and worst == [(0.3, (2, 1))]


def test_equal_copy_and_a_moved_coefficient():
    ps = twisted()
    assert compare_patch_sets(ps, copy(ps)).equal
    moved = copy(ps)
    moved.groups[1][4, 2, 3, 1] += 1e-9
    result = compare_patch_sets(ps, moved)
    assert not result.equal and result.n_moved == 1 and not result.structural
    assert result.moved[0].startswith(f"patch {len(ps.groups[0]) + 4} (bicubic, source ") and "points[2][3]" in result.moved[0]
    assert compare_patch_sets(ps, moved, tolerance=1e-9).equal


def test_structure_weights_merged_and_sources():
    ps = twisted()
    fewer = copy(ps, groups=[ps.groups[0][:-1], ps.groups[1]])
    assert compare_patch_sets(ps, fewer).structural[0].startswith("patches: 212 biquadratic, 108 bicubic -> 211")
    rational = copy(ps, weights=[np.ones(g.shape[:3]) for g in ps.groups])
    assert "weights: polynomial -> rational patches" in compare_patch_sets(ps, rational).structural
    heavier = copy(rational, weights=[w.copy() for w in rational.weights])
    heavier.weights[0][7, 1, 1] = 1.5
    result = compare_patch_sets(rational, heavier)
    assert result.n_moved == 1 and "patch 7 " in result.moved[0] and "weights[1][1] 1.0 -> 1.5" in result.moved[0]
    unmerged = copy(ps, merged=[])  # the same surface, its patches not packed into pieces
    assert compare_patch_sets(ps, unmerged).equal and compare_patch_sets(unmerged, ps).equal
    piece = ps.merged[0]
    shifted = copy(ps, merged=[dataclasses.replace(piece, points=piece.points + 1e-6)] + ps.merged[1:])
    result = compare_patch_sets(ps, shifted)  # a piece that is not its patches: each of its 9 m n coefficients
    assert result.n_moved == 9 * piece.patches.size and result.moved[0].startswith("B: merged piece 0 (span ")
    other_source = copy(ps, source=ps.source.copy())
    other_source.source[3, 0] += 1
    assert compare_patch_sets(ps, other_source).structural[0].startswith("patch 3 (biquadratic, source ")
    assert compare_patch_sets(ps, copy(ps, source_kind=None, source=None)).equal  # a file without sources


def test_meshes_compare_counts_sizes_vertices_and_positions():
    points = np.random.default_rng(1).random((5, 3))
    sizes, vertices = np.array([3, 4]), np.array([0, 1, 2, 1, 2, 3, 4])
    assert compare_meshes(points, sizes, vertices, points, sizes, vertices).equal
    assert compare_meshes(points, sizes, vertices, points[:4], sizes, vertices).structural == ["vertices: 5 -> 4"]
    assert compare_meshes(points, sizes, vertices, points, np.array([4, 3]), vertices).structural[0] == "face 0: 3 -> 4 sides"
    swapped = vertices.copy()
    swapped[[3, 4]] = swapped[[4, 3]]
    assert compare_meshes(points, sizes, vertices, points, sizes, swapped).structural[0].startswith("face 1: vertices")
    moved = points.copy()
    moved[2, 1] += 1e-3
    result = compare_meshes(points, sizes, vertices, moved, sizes, vertices, tolerance=1e-6)
    assert result.n_moved == 1 and result.moved[0].startswith("vertex 2: position ")


def test_surfaces_compare_equal_whatever_the_packing_order_and_turns():
    """A file of other packing (IGES/STEP: pieces' patches first, in the pieces' (u, v)) is paired by centres and
    turned to match: equal; with the same packing and order a turned patch is a move; a moved one stays one."""
    ps = twisted()
    rng = np.random.default_rng(3)
    order = [rng.permutation(len(g)) for g in ps.groups]
    turns = [rng.integers(0, 4, len(g)) for g in ps.groups]
    shuffled = [np.stack([np.rot90(p, k, axes=(0, 1)) for p, k in zip(g[o], t[o])])
                for g, o, t in zip(ps.groups, order, turns)]
    repacked = copy(ps, groups=shuffled, merged=[], source_kind=None, source=None)
    assert compare_patch_sets(ps, repacked).equal and compare_patch_sets(repacked, ps).equal
    moved = copy(repacked, groups=[g.copy() for g in shuffled])
    moved.groups[1][5, 1, 2, 0] += 1e-6
    result = compare_patch_sets(ps, moved)
    assert not result.equal and result.n_moved == 1 and not result.structural
    plain = copy(ps, merged=[])
    turned = copy(plain)
    turned.groups[0][3] = np.rot90(turned.groups[0][3], 1, axes=(0, 1))
    assert compare_patch_sets(plain, turned).n_moved > 0  # same packing, same order: compared as written
