"""The mesh writers by blocks (``MESH_WRITERS.streamed()``) against the whole-mesh writers, on plain arrays.

A stand-in tessellation cuts whole arrays into uneven blocks, so these tests
reach what conversions rarely give: degenerate triangles (STL's zero facet
normals), GLB's one buffer view for equal position and normal bytes, normals
that are not quite unit, large and tiny coordinates, and blocks of one row.
"""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.io.meshes.write import write_streamed_mesh, write_triangle_mesh
from c1surf.io.registry import MESH_WRITERS


class BlockTessellation:
    """Whole arrays given by blocks as ``evaluation.stream.StreamedTessellation`` gives them.

    points (V, 3), normals (V, 3) float, triangles (T, 3) int; block edges drawn at random (``seed``).
    """

    def __init__(self, points, normals, triangles, seed: int = 0, largest: int = 7):
        self.points, self.normals, self.triangles = points, normals, triangles
        self.n_vertices, self.n_triangles, self.dim = len(points), len(triangles), points.shape[1]
        rng = np.random.default_rng(seed)
        self._cuts = [np.unique(np.concatenate([[0], np.cumsum(rng.integers(1, largest + 1, n)), [n]]).clip(0, n))
                      for n in (self.n_vertices, self.n_triangles)]

    def _ranges(self, k):
        cuts = self._cuts[k]
        return zip(cuts[:-1], cuts[1:])

    def vertex_blocks(self):
        for a, z in self._ranges(0):
            yield self.points[a:z], self.normals[a:z]

    def triangle_blocks(self):
        for a, z in self._ranges(1):
            yield self.triangles[a:z].astype(np.int32)

    def triangle_point_blocks(self):
        for a, z in self._ranges(1):
            yield self.points[self.triangles[a:z]]


def _mesh(v: int = 60, scale: float = 1.0, seed: int = 1):
    rng = np.random.default_rng(seed)
    points = rng.standard_normal((v, 3)) * scale
    normals = rng.standard_normal((v, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    normals[::5] *= 1 + 1e-9  # not quite unit: GLB makes them unit again
    a = rng.integers(0, v - 2, 2 * v)
    triangles = np.stack([a, a + 1, a + 2], axis=1)
    triangles[::7, 2] = triangles[::7, 1]  # degenerate: no facet normal
    triangles[::11] = triangles[::11, [0, 0, 0]]
    return points, normals, triangles


def _both(tmp_path, suffix, points, normals, triangles, float32=False, seed=0):
    whole, streamed = tmp_path / f"whole{suffix}", tmp_path / f"streamed{suffix}"
    write_triangle_mesh(whole, points, triangles, normals, float32=float32)
    write_streamed_mesh(streamed, BlockTessellation(points, normals, triangles, seed), float32=float32)
    return whole.read_bytes(), streamed.read_bytes()


def test_every_streamed_mesh_format_is_tested_here():
    assert set(MESH_WRITERS.streamed()) == {".ply", ".obj", ".stl", ".glb"}


@pytest.mark.parametrize("suffix", MESH_WRITERS.streamed())
@pytest.mark.parametrize("scale", [1e-7, 1.0, 4.2e6])
@pytest.mark.parametrize("float32", [False, True])
def test_blocks_give_the_whole_mesh_bytes(tmp_path, suffix, scale, float32):
    points, normals, triangles = _mesh(scale=scale)
    for seed in range(3):
        whole, streamed = _both(tmp_path, suffix, points, normals, triangles, float32, seed)
        assert whole == streamed, f"{suffix} scale {scale} float32 {float32} blocks {seed}"


def test_stl_pads_facets_without_normal_with_zeros(tmp_path):
    points, normals, triangles = _mesh()
    whole, streamed = _both(tmp_path, ".stl", points, normals, triangles)
    assert whole == streamed
    records = np.frombuffer(streamed[84:], dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    assert len(records) == len(triangles) and not records["n"][::7].any() and records["n"][1::7].any()


def test_glb_shares_one_view_for_normals_equal_to_the_positions(tmp_path):
    """Unit positions (an octahedron) as normals: trimesh stores their bytes once, and so do the blocks."""
    points = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    triangles = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    whole, streamed = _both(tmp_path, ".glb", points, points.copy(), triangles)
    assert whole == streamed and b'"bufferView":1,"max"' in whole
    moved = points + 1e-3
    whole, streamed = _both(tmp_path, ".glb", moved, points, triangles)
    assert whole == streamed and b'"bufferView":2' in whole
