"""Crease sectors merged for exact C0 creases (mesh.creases.sectors): triangle meshes with creases of
any face counts become exact, planar regions stay planar, and nothing else about the mesh changes."""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.features import SharpFeatures
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.mesh.creases.sectors import merge_crease_sectors
from c1surf.mesh.creases.sheets import corner_sectors, exact_crease_vertices
from c1surf.mesh.feature_edges import feature_edges
from c1surf.mesh.halfedges import build_halfedges, undirected_edges, vertex_valences

from cad_meshes import _Builder

SIDES = np.array([2.0, 1.5, 1.0])


def triangulated_box(n: int, seed: int):
    """The box [0, 2] x [0, 1.5] x [0, 1], each face an n x n grid of quads split by random diagonals."""
    rng = np.random.default_rng(seed)
    b = _Builder()
    for axis in range(3):
        u, w = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, 1):
            rows = []
            for i in range(n + 1):
                row = []
                for j in range(n + 1):
                    p = np.zeros(3)
                    p[axis], p[u], p[w] = side * SIDES[axis], i / n * SIDES[u], j / n * SIDES[w]
                    row.append(tuple(p))
                rows.append(row)
            b.grid(rows, flip=side == 0, rng=rng)
    return b.mesh()


def sector_sizes(sizes, corners, n_vertices, edges):
    """(mesh, sharp, largest sector at each vertex) of a mesh and its sharp edges."""
    mesh = build_halfedges(sizes, corners, n_vertices)
    key = np.minimum(mesh.origin, mesh.dest) * n_vertices + np.maximum(mesh.origin, mesh.dest)
    sharp = np.isin(key, edges.min(axis=1) * n_vertices + edges.max(axis=1))
    sector = corner_sectors(mesh, sharp | (mesh.twin < 0))
    size = np.bincount(sector, minlength=mesh.n_halfedges)[sector]
    largest = np.zeros(n_vertices, dtype=np.int64)
    np.maximum.at(largest, mesh.origin, size)
    return mesh, sharp, largest


@pytest.mark.parametrize("n, seed", [(2, 0), (3, 1), (4, 0), (4, 3), (6, 1), (8, 2)])
def test_a_triangulated_box_becomes_an_exact_box(n, seed):
    sizes, corners, points = triangulated_box(n, seed)
    edges = feature_edges(sizes, corners, points, 40.0)
    assert len(edges) == 12 * n  # the box's edges, found by the angle alone
    before = sector_sizes(sizes, corners, len(points), edges)[2]
    assert before.max() >= 3  # sectors of three or more triangles: not exact as they are
    merge = merge_crease_sectors(sizes, corners, len(points), edges, np.zeros(0, dtype=np.int64))
    assert merge is not None and merge.polygons > 0 and merge.kept.sum() == merge.face_sizes.size
    # the merged mesh: simple polygons, the same vertices, still a sphere, every sector one or two faces
    faces = np.split(merge.face_vertices, np.cumsum(merge.face_sizes)[:-1])
    assert all(len(set(f.tolist())) == len(f) for f in faces)
    mesh, sharp, largest = sector_sizes(merge.face_sizes, merge.face_vertices, len(points), edges)
    n_edges = len(undirected_edges(mesh)[0])
    assert len(points) - n_edges + mesh.n_faces == 2 and np.all(mesh.twin >= 0)
    assert vertex_valences(mesh).min() >= 3
    on_seam, exact, corner = exact_crease_vertices(mesh, sharp, np.zeros(len(points), dtype=bool))
    assert np.all(exact[on_seam]) and corner.sum() == 8
    # the surface: C0 along all 12 edges, G1 elsewhere, and every coefficient on a face of the box
    from construction.test_c0_creases import crease_and_smooth

    surface = Surface(merge.face_sizes, merge.face_vertices, points, SurfaceOptions(exact_creases=True),
                      features=SharpFeatures(edges, np.full(len(edges), 10.0)))
    assert len(surface.topology.crease_sheets.kept_edges) == 0
    crease_gap, smooth_gap, smooth_jump, crease_pairs, unmatched = crease_and_smooth(surface)
    assert unmatched == 0 and crease_pairs == 4 * 12 * n
    assert crease_gap <= 1e-12 and smooth_jump <= 1e-10
    for group in (g for g in (surface.biquadratic, surface.bicubic) if len(g)):
        c = group.reshape(len(group), -1, 3)
        off_plane = np.minimum(np.abs(c), np.abs(c - SIDES)).max(axis=1).min(axis=1)  # the nearest face plane
        assert off_plane.max(initial=0.0) <= 1e-12


def test_faces_with_other_data_and_tagged_edges_are_never_merged():
    sizes, corners, points = triangulated_box(4, 0)
    edges = feature_edges(sizes, corners, points, 40.0)
    merge = merge_crease_sectors(sizes, corners, len(points), edges, np.zeros(0, dtype=np.int64))
    merged = np.flatnonzero(~merge.kept)
    # a face of another key (a hole, another blend ratio) keeps every one of its edges
    keys = np.zeros(sizes.size, dtype=np.int64)
    keys[merged[0]] = 1
    other = merge_crease_sectors(sizes, corners, len(points), edges, np.zeros(0, dtype=np.int64), keys)
    assert other is None or other.kept[merged[0]]
    # an edge tagged with some sharpness (a semi-sharp crease) stays an edge of the mesh
    face = np.split(corners, np.cumsum(sizes)[:-1])[merged[0]]
    tagged = np.array([[face[0], face[1]], [face[1], face[2]], [face[2], face[0]]])
    kept = merge_crease_sectors(sizes, corners, len(points), edges, np.zeros(0, dtype=np.int64), None, tagged)
    assert kept is None or kept.kept[merged[0]]


def test_nothing_to_merge():
    # the sample cube: every sector one face already; and a mesh without creases
    from conftest import SAMPLES
    from c1surf.io.meshes.read import read_mesh

    cube = read_mesh(SAMPLES / "cube.obj")
    edges = feature_edges(cube.face_sizes, cube.face_vertices, cube.points, 40.0)
    assert merge_crease_sectors(cube.face_sizes, cube.face_vertices, cube.n_vertices, edges, []) is None
    assert merge_crease_sectors(cube.face_sizes, cube.face_vertices, cube.n_vertices, np.zeros((0, 2)), []) is None
