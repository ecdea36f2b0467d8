"""The vectorized OBJ and PLY writers: what they write reads back exactly (to the stated precision)."""
from __future__ import annotations

import threading

import numpy as np
import pytest
from plyfile import PlyData

from c1surf.io.meshes.number_text import format_fixed
from c1surf.io.meshes.obj import read_obj
from c1surf.io.meshes.obj_out import write_obj
from c1surf.io.meshes.ply_out import write_ply, write_ply_blocks
from c1surf.io.meshes.write import TriangleMesh, write_attribute_mesh, write_triangle_mesh


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


def test_ply_blocks_of_one_records_array_write_its_bytes(tmp_path):
    """Blocks whose points and normals are the halves of one (c, 6) array are written as that array's bytes
    (no copy): the same file as separate arrays, as the faces written first, and as ``write_ply``."""
    rng = np.random.default_rng(3)
    records, triangles = rng.standard_normal((50, 6)), rng.integers(0, 50, (30, 3)).astype(np.int32)
    halves = [(records[a : a + 7, :3], records[a : a + 7, 3:]) for a in range(0, 50, 7)]
    copies = [(p.copy(), n.copy()) for p, n in halves]
    for name, blocks in (("halves", halves), ("copies", copies)):
        write_ply_blocks(tmp_path / f"{name}.ply", 50, 30, blocks, [triangles[:11], triangles[11:]])
    write_ply_blocks(tmp_path / "first.ply", 50, 30, halves, [triangles[:11], triangles[11:]], triangles_first=True)
    write_ply(tmp_path / "whole.ply", TriangleMesh(records[:, :3], triangles, records[:, 3:]))
    whole = (tmp_path / "whole.ply").read_bytes()
    assert (tmp_path / "halves.ply").read_bytes() == (tmp_path / "copies.ply").read_bytes() == whole
    assert (tmp_path / "first.ply").read_bytes() == whole  # the faces written first, after the vertices' room


def test_ply_faces_first_without_pwrite(tmp_path, monkeypatch):
    """Where there is no ``os.pwrite`` (Windows) the faces are written before the vertices: the same bytes."""
    rng = np.random.default_rng(5)
    records, triangles = rng.standard_normal((50, 6)), rng.integers(0, 50, (30, 3)).astype(np.int32)
    monkeypatch.delattr("os.pwrite", raising=False)
    blocks = [(records[a : a + 7, :3], records[a : a + 7, 3:]) for a in range(0, 50, 7)]
    write_ply_blocks(tmp_path / "first.ply", 50, 30, blocks, [triangles[:11], triangles[11:]], triangles_first=True)
    write_ply(tmp_path / "whole.ply", TriangleMesh(records[:, :3], triangles, records[:, 3:]))
    assert (tmp_path / "first.ply").read_bytes() == (tmp_path / "whole.ply").read_bytes()
    assert not _face_threads()


def _face_threads() -> list:
    return [t for t in threading.enumerate() if t.name == "ply faces"]


def test_ply_faces_first_stop_with_an_error_of_either_side(tmp_path):
    """The faces written first run on a thread beside the vertex blocks: an error in the vertex blocks stops
    them (no thread outlives the file) and is the error raised; an error in the triangle blocks is raised
    once the vertices are written. Many blocks, so that the faces are still being written."""
    rng = np.random.default_rng(4)
    records, triangles = rng.standard_normal((50, 6)), rng.integers(0, 50, (30, 3)).astype(np.int32)
    started = threading.Event()

    def triangle_blocks(fail_at=None):
        for k in range(3000):
            started.set()
            if k == fail_at:
                raise MemoryError("no room for the faces")
            yield triangles[:1]

    def vertex_blocks(fail):
        started.wait(5)  # the face thread has begun
        yield records[:25, :3], records[:25, 3:]
        if fail:
            raise KeyboardInterrupt
        yield records[25:, :3], records[25:, 3:]

    with pytest.raises(KeyboardInterrupt):
        write_ply_blocks(tmp_path / "a.ply", 50, 3000, vertex_blocks(True), triangle_blocks(), triangles_first=True)
    assert not _face_threads()
    started.clear()
    with pytest.raises(MemoryError, match="no room for the faces"):
        write_ply_blocks(tmp_path / "b.ply", 50, 3000, vertex_blocks(False), triangle_blocks(2000), triangles_first=True)
    assert not _face_threads()
    started.clear()
    write_ply_blocks(tmp_path / "c.ply", 50, 3000, vertex_blocks(False), triangle_blocks(), triangles_first=True)
    write_ply(tmp_path / "d.ply", TriangleMesh(records[:, :3], np.repeat(triangles[:1], 3000, axis=0), records[:, 3:]))
    assert (tmp_path / "c.ply").read_bytes() == (tmp_path / "d.ply").read_bytes()


def test_mesh_out_uses_the_fast_writers(tmp_path):
    points, triangles, normals = _mesh()
    write_triangle_mesh(tmp_path / "a.ply", points, triangles, normals)
    write_triangle_mesh(tmp_path / "b.ply", points, triangles, normals, float32=True)
    assert b"property double x" in (tmp_path / "a.ply").read_bytes()[:400]
    assert b"property float x" in (tmp_path / "b.ply").read_bytes()[:400]
    write_triangle_mesh(tmp_path / "c.obj", points, triangles, normals)
    assert (tmp_path / "c.obj").read_text().startswith("# c1surf\n")


def _attributes(v):
    rng = np.random.default_rng(4)
    return np.c_[rng.uniform(0, 1, (v, 2)), rng.uniform(0, 255, (v, 4))], ["u", "v", "red", "green", "blue", "alpha"]


def test_attribute_obj_honours_float32(tmp_path):
    """--attributes --float32 to OBJ: float32 digits (it kept every double digit before, ignoring the flag)."""
    points, triangles, normals = _mesh(scale=3.7e2)
    attributes, names = _attributes(len(points))
    exact, small = tmp_path / "exact.obj", tmp_path / "small.obj"
    write_attribute_mesh(exact, points, triangles, normals, attributes, names)
    write_attribute_mesh(small, points, triangles, normals, attributes, names, float32=True)
    assert small.stat().st_size < 0.8 * exact.stat().st_size
    full, short = read_obj(exact), read_obj(small)
    assert np.array_equal(full.points, points)  # shortest round-trip text: the same doubles
    assert np.array_equal(full.vertex_uvs, attributes[:, :2])
    assert np.abs(short.points - points).max() / np.abs(points).max() < 1e-7
    assert np.abs(short.vertex_uvs - attributes[:, :2]).max() < 1e-7
    assert np.abs(short.vertex_normals - normals).max() < 1e-7
    for mesh in (full, short):  # colours 0..1 with 6 digits, alpha left out (OBJ has none)
        assert np.abs(np.c_[[mesh.vertex_attributes[c] for c in ("red", "green", "blue")]].T - attributes[:, 2:5] / 255).max() < 1e-6
    plain = tmp_path / "plain.obj"
    write_triangle_mesh(plain, points, triangles, normals, float32=True)
    v_lines = [line for line in small.read_text().splitlines() if line.startswith(("v ", "vn "))]
    plain_lines = [line for line in plain.read_text().splitlines() if line.startswith(("v ", "vn "))]
    assert [" ".join(line.split()[:4]) for line in v_lines] == plain_lines  # the same digits as without attributes


@pytest.mark.parametrize("float32", [False, True])
def test_attribute_ply_layout(tmp_path, float32):
    points, triangles, normals = _mesh()
    attributes, names = _attributes(len(points))
    path = tmp_path / "a.ply"
    write_attribute_mesh(path, points, triangles, normals, attributes, names, float32=float32)
    data = path.read_bytes()
    header = data[: data.index(b"end_header\n")].decode().splitlines()
    real = "float" if float32 else "double"
    assert header[2:] == ["element vertex 500", f"property {real} x", f"property {real} y", f"property {real} z",
                          "property float nx", "property float ny", "property float nz", "property float s",
                          "property float t", "property uchar red", "property uchar green", "property uchar blue",
                          "property uchar alpha", "element face 1000", "property list uchar int vertex_indices"]
    vertex = PlyData.read(str(path))["vertex"]
    assert np.array_equal(vertex["red"], np.rint(attributes[:, 2] / 255 * 255).astype(np.uint8))
    assert np.abs(np.c_[vertex["x"], vertex["y"], vertex["z"]] - points).max() <= (1e-6 if float32 else 0.0)


def test_curvature_ply_layout(tmp_path):
    points, triangles, normals = _mesh()
    values = {"kmax": np.arange(500.0), "K": np.ones(500), "H": -np.ones(500), "quality": np.arange(500.0)}
    colours = np.tile(np.array([[1, 2, 3]], dtype=np.uint8), (500, 1))
    write_triangle_mesh(tmp_path / "c.ply", points, triangles, normals, vertex_properties=values, vertex_colors=colours)
    data = (tmp_path / "c.ply").read_bytes()
    header = data[: data.index(b"end_header\n")].decode().splitlines()
    assert header[2:4] == ["comment c1surf", "element vertex 500"]
    assert header[4:] == [f"property double {a}" for a in ("x", "y", "z", "nx", "ny", "nz")] + [
        f"property float {a}" for a in values] + [f"property uchar {a}" for a in ("red", "green", "blue")] + [
        "element face 1000", "property list uchar int vertex_indices"]
    vertex = PlyData.read(str(tmp_path / "c.ply"))["vertex"]
    assert np.array_equal(vertex["kmax"], np.arange(500.0)) and np.array_equal(vertex["blue"], colours[:, 2])
    with pytest.raises(ValueError, match="need a .ply output"):
        write_triangle_mesh(tmp_path / "c.obj", points, triangles, normals, vertex_properties=values)


def test_convert_attributes_float32(tmp_path):
    """``convert --attributes --float32``: the flag reaches the attribute writers (OBJ and PLY)."""
    from click.testing import CliRunner

    from c1surf.cli.main import main
    from conftest import SAMPLES

    mesh = read_obj(SAMPLES / "twisted.obj")
    offsets = mesh.face_offsets()
    source = tmp_path / "uv.obj"
    source.write_text("".join(f"v {x!r} {y!r} {z!r}\nvt {x + y!r} {y - z!r}\n" for x, y, z in mesh.points.tolist())
                      + "".join("f " + " ".join(f"{v + 1}/{v + 1}" for v in mesh.face_vertices[a:b]) + "\n"
                                for a, b in zip(offsets[:-1], offsets[1:])))
    sizes = {}
    for suffix in (".obj", ".ply"):
        for flag in ([], ["--float32"]):
            out = tmp_path / f"out{len(flag)}{suffix}"
            result = CliRunner().invoke(main, ["convert", str(source), "-o", str(out), "--attributes", "-q", *flag])
            assert result.exit_code == 0, result.output
            sizes[out.name] = out.stat().st_size
    assert sizes["out1.obj"] < 0.8 * sizes["out0.obj"] and sizes["out1.ply"] < sizes["out0.ply"]
    assert b"property float x" in (tmp_path / "out1.ply").read_bytes()[:300]
    assert b"property double x" in (tmp_path / "out0.ply").read_bytes()[:300]
