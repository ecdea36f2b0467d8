"""The numpy graph labellings of ``mesh.halfedges`` against scipy's ``connected_components`` they replace."""
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from c1surf.io.meshes.read import read_mesh
from c1surf.mesh.halfedges import build_halfedges, component_roots, orbit_labels, rotation_cycles

SAMPLES = Path(__file__).resolve().parents[2] / "sample_meshes"


def _scipy_labels(n, a, b):
    return connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)


def test_orbit_labels_are_scipys_on_random_chains_and_cycles():
    rng = np.random.default_rng(0)
    for _ in range(500):
        n = int(rng.integers(0, 80))
        order, successor, longest, i = rng.permutation(n), np.full(n, -1), 1, 0
        while i < n:
            run = order[i : i + int(rng.integers(1, 20))]
            successor[run[:-1]] = run[1:]
            if rng.random() < 0.5 and run.size > 1:
                successor[run[-1]] = run[0]  # a cycle, else a chain
            i, longest = i + run.size, max(longest, run.size)
        ok = successor >= 0
        expected = _scipy_labels(n, np.arange(n)[ok], successor[ok])[1]
        got = orbit_labels(successor, longest)
        assert got.dtype == expected.dtype and np.array_equal(got, expected)


@pytest.mark.parametrize("path", sorted(SAMPLES.glob("*.obj")), ids=lambda p: p.name)
def test_rotation_cycles_are_scipys(path):
    mesh = read_mesh(path)
    halfedges = build_halfedges(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices)
    h = np.arange(halfedges.n_halfedges)
    r = halfedges.rotate(h)
    assert np.array_equal(rotation_cycles(halfedges), _scipy_labels(h.size, h[r >= 0], r[r >= 0])[1])


def test_component_roots_count_and_group_as_scipy():
    rng = np.random.default_rng(1)
    for _ in range(1000):
        n = int(rng.integers(1, 60))
        a, b = rng.integers(0, n, (2, int(rng.integers(0, 80))))
        count, label = _scipy_labels(n, a, b)
        roots = component_roots(n, a, b)
        assert np.count_nonzero(roots == np.arange(n)) == count
        for c in range(count):  # every vertex points at the smallest vertex of its component
            members = np.flatnonzero(label == c)
            assert np.all(roots[members] == members.min())
    path = rng.permutation(100_000)
    assert np.all(component_roots(path.size, path[:-1], path[1:]) == 0)


def test_repeated_faces_skip_their_sorts_only_when_no_face_can_repeat(monkeypatch):
    """``duplicate_faces._may_repeat`` says False only when no two faces share their vertices; planted copies
    and reversed copies give what the sorts alone give."""
    from c1surf.mesh import duplicate_faces

    def always_sorted(sizes, vertices):
        with monkeypatch.context() as patch:
            patch.setattr(duplicate_faces, "_may_repeat", lambda *args: True)
            return duplicate_faces.repeated_faces(sizes, vertices)

    rng = np.random.default_rng(2)
    for _ in range(300):
        n_faces = int(rng.integers(2, 30))
        sizes = rng.integers(3, 6, n_faces)
        vertices = np.concatenate([rng.choice(40, size, replace=False) for size in sizes])
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        if rng.random() < 0.6:  # plant a copy (rotated, maybe reversed) of a face
            f = int(rng.integers(n_faces))
            cycle = np.roll(vertices[offsets[f] : offsets[f + 1]], int(rng.integers(sizes[f])))
            sizes = np.r_[sizes, sizes[f]]
            vertices = np.r_[vertices, cycle[::-1] if rng.random() < 0.5 else cycle]
            offsets = np.concatenate([[0], np.cumsum(sizes)])
        cycles = {tuple(sorted(vertices[offsets[f] : offsets[f + 1]])) for f in range(sizes.size)}
        shared = len(cycles) < sizes.size
        assert duplicate_faces._may_repeat(sizes, vertices, offsets) or not shared
        assert np.array_equal(duplicate_faces.repeated_faces(sizes, vertices), always_sorted(sizes, vertices))
