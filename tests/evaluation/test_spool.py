"""evaluation.stream.SpooledTessellation: vertex blocks evaluated once, read back with the same bits and sizes."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from c1surf.construction.surface import Surface
from c1surf.evaluation.stream import SpooledTessellation, StreamedTessellation
from c1surf.evaluation.tessellate import patch_adjacency
from c1surf.io.meshes.read import read_mesh

ROOT = Path(__file__).resolve().parents[2]


class Counting:
    """A StreamedTessellation that counts its vertex passes."""

    def __init__(self, tessellation):
        self.inner, self.passes = tessellation, 0
        self.n_vertices, self.n_triangles, self.dim = tessellation.n_vertices, tessellation.n_triangles, tessellation.dim

    def vertex_blocks(self):
        self.passes += 1
        return self.inner.vertex_blocks()

    def triangle_blocks(self):
        return self.inner.triangle_blocks()


def test_blocks_are_evaluated_once_and_read_back_bit_for_bit(tmp_path):
    m = read_mesh(ROOT / "sample_meshes" / "twisted.obj")
    surface = Surface(m.face_sizes, m.face_vertices, m.points, lazy_patches=True)
    tess = StreamedTessellation(surface.patch_source(), patch_adjacency(surface.refined, surface.frames), 4)
    expected = list(tess.vertex_blocks())
    counting = Counting(tess)
    with SpooledTessellation(counting, str(tmp_path)) as spooled:
        partial = spooled.vertex_blocks()
        next(partial)  # a pass left midway keeps nothing: the next one evaluates again
        partial.close()
        for _ in range(3):
            blocks = list(spooled.vertex_blocks())
            assert len(blocks) == len(expected)
            for (p, n), (q, o) in zip(blocks, expected):
                assert p.shape == q.shape and np.array_equal(p, q) and np.array_equal(n, o)
        assert counting.passes == 2
        triangles = np.concatenate(list(spooled.triangle_blocks()))
        assert np.array_equal(triangles, np.concatenate(list(tess.triangle_blocks())))
    assert list(tmp_path.iterdir()) == []  # the file had no name
