"""The patch writers by blocks (``PATCH_WRITERS.streamed()``): a ``PatchStream`` gives the ``PatchSet`` bytes.

The surface is built twice, eagerly and with ``lazy_patches`` (whose patch
arrays must stay unmade), and each streamed file is compared byte for byte
with the whole-surface file, at several block sizes of the writers.
"""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.patch_set import surface_patch_set, surface_patch_stream
from c1surf.io.meshes.read import read_mesh
from c1surf.io.patches import json_patches, npz
from c1surf.io.patches.formats import write_patch_set, write_patch_stream
from c1surf.io.registry import PATCH_WRITERS

from conftest import SAMPLES, shared_mesh

MESHES = ["twisted", "torus", "high_valence", "cube"]  # torus: no bicubic patch


def _surfaces(path, **options):
    m = read_mesh(path)
    eager = Surface(m.face_sizes, m.face_vertices, m.points, SurfaceOptions(**options))
    lazy = Surface(m.face_sizes, m.face_vertices, m.points, SurfaceOptions(**options), lazy_patches=True)
    return eager, lazy


def _compare(tmp_path, eager, lazy, suffix):
    whole, streamed = tmp_path / f"whole{suffix}", tmp_path / f"streamed{suffix}"
    write_patch_set(whole, surface_patch_set(eager, "in.obj"))
    write_patch_stream(streamed, surface_patch_stream(lazy, "in.obj"))
    assert lazy._patches is None  # never made
    return whole.read_bytes(), streamed.read_bytes()


def test_every_streamed_patch_format_is_tested_here():
    assert set(PATCH_WRITERS.streamed()) == {".json", ".npz"}


@pytest.mark.parametrize("suffix", PATCH_WRITERS.streamed())
@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("block", [1, 3, 1 << 12])
def test_a_patch_stream_writes_the_patch_set_bytes(monkeypatch, tmp_path, suffix, name, block):
    monkeypatch.setattr(json_patches, "_STREAM_BLOCK", block)
    monkeypatch.setattr(npz, "_STREAM_BLOCK", block)
    whole, streamed = _compare(tmp_path, *_surfaces(SAMPLES / f"{name}.obj", blend=0.4), suffix)
    assert whole == streamed


@pytest.mark.parametrize("suffix", PATCH_WRITERS.streamed())
def test_an_open_mesh_with_holes_streams_its_kept_patches(tmp_path, suffix):
    eager, lazy = _surfaces(shared_mesh("pmp-library/hole_capsule.obj"))
    whole, streamed = _compare(tmp_path, eager, lazy, suffix)
    assert whole == streamed


def test_the_stream_header_counts_are_the_arrays():
    eager, lazy = _surfaces(SAMPLES / "twisted.obj")
    stream = surface_patch_stream(lazy)
    assert stream.counts == (len(eager.biquadratic), len(eager.bicubic))
    counts = stream.header["counts"]
    assert (counts["biquadratic"], counts["bicubic"]) == stream.counts and lazy._patches is None
    for kind, whole in enumerate((eager.biquadratic, eager.bicubic)):
        blocks = list(stream.blocks(kind, 5))
        assert [a for a, _ in blocks] == list(range(0, len(whole), 5))
        assert np.array_equal(np.concatenate([c for _, c in blocks]), whole[..., :3])


def test_rational_surfaces_and_other_formats_are_written_whole(tmp_path):
    m = read_mesh(SAMPLES / "cube.obj")
    weights = np.ones(len(m.points))
    weights[0] = 2.0
    rational = Surface(m.face_sizes, m.face_vertices, m.points, weights=weights, lazy_patches=True)
    with pytest.raises(ValueError, match="rational"):
        surface_patch_stream(rational)
    _, lazy = _surfaces(SAMPLES / "cube.obj")
    with pytest.raises(ValueError, match="written whole"):
        write_patch_stream(tmp_path / "p.igs", surface_patch_stream(lazy))


def test_the_integer_rows_by_blocks_are_the_patch_set_arrays():
    eager, lazy = _surfaces(shared_mesh("pmp-library/hole_capsule.obj"))
    whole, stream = surface_patch_set(eager), surface_patch_stream(lazy)
    arrays = {"source_kind": whole.source_kind, "source": whole.source, "corners": whole.adjacency.corners,
              "edges": whole.adjacency.edges, "reversed": whole.adjacency.reversed,
              "neighbours": whole.adjacency.neighbours()}
    p = stream.n_patches
    for name, row, dtype in stream.INTEGERS:
        blocks = [stream.integers(name, a, min(a + 7, p)) for a in range(0, p, 7)]
        joined = np.concatenate(blocks)
        assert joined.dtype == np.dtype(dtype) and joined.shape == (p, *row)
        assert np.array_equal(joined, arrays[name]), name


def test_neighbours_pair_the_two_sides_of_each_edge():
    """``PatchAdjacency.neighbours`` (from ``partners``) against pairing by hand: edges of one or of more than two
    sides have none."""
    from c1surf.evaluation.adjacency import PatchAdjacency

    rng = np.random.default_rng(5)
    for _ in range(200):
        p = int(rng.integers(0, 40))
        edges = rng.integers(0, max(1, 2 * p), (p, 4))
        adjacency = PatchAdjacency(np.zeros((p, 4), dtype=np.int64), edges.astype(np.int32), np.zeros((p, 4), bool))
        expected = np.full((p, 4, 2), -1)
        for e in np.unique(edges):
            sides = np.argwhere(edges == e)
            if len(sides) == 2:
                expected[tuple(sides[0])], expected[tuple(sides[1])] = sides[1], sides[0]
        assert np.array_equal(adjacency.neighbours(), expected)
