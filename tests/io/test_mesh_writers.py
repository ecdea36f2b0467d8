"""The vectorized OBJ and PLY writers: what they write reads back exactly (to the stated precision)."""
from __future__ import annotations

import numpy as np
import pytest
from plyfile import PlyData

from c1surf.io.meshes.number_text import format_fixed
from c1surf.io.meshes.obj import read_obj
from c1surf.io.meshes.obj_out import write_obj
from c1surf.io.meshes.ply_out import write_ply
from c1surf.io.meshes.write import TriangleMesh, write_triangle_mesh


def _mesh(scale=1.0, v=500):
    rng = np.random.default_rng(3)
    points = rng.standard_normal((v, 3)) * scale
    normals = rng.standard_normal((v, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    a = rng.integers(0, v - 2, 2 * v)
    return points, np.stack([a, a + 1, a + 2], axis=1), normals


def test_fixed_point_text():
    values = np.array([[0.0, -0.0, 1.0, -1.5], [123.25, 1e-17, 0.1, -0.0001], [99.999, np.nan, -2.0, 10.0]])
    chars, keep = format_fixed(values, 4)
    text = [bytes(chars[i, j][keep[i, j]]).decode() for i in range(3) for j in range(4)]
    assert text == ["0", "0", "1", "-1.5", "123.25", "0", "0.1", "-0.0001", "99.999", "0", "-2", "10"]


@pytest.mark.parametrize("scale", [1e-6, 1.0, 3.7e5])
@pytest.mark.parametrize("float32", [False, True])
def test_obj_round_trip(tmp_path, scale, float32):
    points, triangles, normals = _mesh(scale)
    path = tmp_path / "m.obj"
    write_obj(path, TriangleMesh(points, triangles, normals), float32=float32)
    mesh = read_obj(path)
    relative = np.abs(mesh.points - points).max() / np.abs(points).max()
    assert relative < (1e-7 if float32 else 1e-14)
    assert np.array_equal(mesh.face_vertices.reshape(-1, 3), triangles)
    assert np.abs(mesh.vertex_normals - normals).max() < (1e-7 if float32 else 1e-14)


@pytest.mark.parametrize("float32", [False, True])
def test_ply_round_trip(tmp_path, float32):
    points, triangles, normals = _mesh()
    path = tmp_path / "m.ply"
    write_ply(path, TriangleMesh(points, triangles, normals), float32=float32)
    ply = PlyData.read(str(path))
    vertex = ply["vertex"]
    assert vertex["x"].dtype == (np.float32 if float32 else np.float64)
    got = np.stack([vertex[a] for a in "xyz"], axis=1)
    assert np.abs(got - points).max() <= (1e-6 if float32 else 0.0)
    assert np.array_equal(np.stack(ply["face"]["vertex_indices"]), triangles)


def test_mesh_out_uses_the_fast_writers(tmp_path):
    points, triangles, normals = _mesh()
    write_triangle_mesh(tmp_path / "a.ply", points, triangles, normals)
    write_triangle_mesh(tmp_path / "b.ply", points, triangles, normals, float32=True)
    assert b"property double x" in (tmp_path / "a.ply").read_bytes()[:400]
    assert b"property float x" in (tmp_path / "b.ply").read_bytes()[:400]
    write_triangle_mesh(tmp_path / "c.obj", points, triangles, normals)
    assert (tmp_path / "c.obj").read_text().startswith("# c1surf\n")
