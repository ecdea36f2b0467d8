"""Mesh readers (OBJ, PLY), read_mesh dispatch and atomic_output."""
from __future__ import annotations

import os
import re
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from plyfile import PlyData, PlyElement

from c1surf.io.atomic import atomic_output
from c1surf.io.errors import MeshInputError, OutputError
from c1surf.io.meshes.mesh_file import MeshFile, find_repeated_vertex
from c1surf.io.meshes.obj import parse_obj, read_obj
from c1surf.io.meshes.ply import read_ply
from c1surf.io.meshes.read import read_mesh

SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "meshes"

# A cube-ish point set and faces of sizes 3, 4, 5 and 8.
PTS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],
                [0.5, -1, 0.25], [2.5, 0.5, -0.125]], dtype=float)
FACES = [[0, 1, 2], [0, 1, 2, 3], [4, 5, 6, 7, 8], [0, 1, 2, 3, 4, 5, 6, 9]]
SIZES = np.array([3, 4, 5, 8])
FLAT = np.concatenate([np.array(f) for f in FACES])


def write(tmp_path, name, content) -> Path:
    p = tmp_path / name
    p.write_bytes(content.encode() if isinstance(content, str) else content)
    return p


def obj_text(points=PTS, faces=FACES, fmt="{}", nl="\n") -> str:
    lines = ["# test mesh"]
    lines += ["v " + " ".join(repr(float(c)) for c in p) for p in points]
    lines += ["f " + " ".join(fmt.format(i + 1) for i in f) for f in faces]
    return nl.join(lines) + nl


def assert_mesh(m: MeshFile, points=PTS, faces=FACES):
    np.testing.assert_array_equal(m.points, points)
    assert m.points.dtype == np.float64 and m.points.shape == (len(points), 3)
    sizes = np.array([len(f) for f in faces])
    np.testing.assert_array_equal(m.face_sizes, sizes)
    np.testing.assert_array_equal(m.face_vertices, np.concatenate(faces))
    assert m.face_sizes.dtype == np.int64 and m.face_vertices.dtype == np.int64
    np.testing.assert_array_equal(m.face_offsets(), np.r_[0, np.cumsum(sizes)])


def raises_at(fn, line, *fragments):
    with pytest.raises(MeshInputError) as info:
        fn()
    err = info.value
    assert err.line == line, str(err)
    text = str(err)
    assert "\n" not in text
    for frag in fragments:
        assert frag in text, text
    return err


# ----------------------------------------------------------------------
# OBJ


def test_obj_mixed_sizes_exact(tmp_path):
    m = read_obj(write(tmp_path, "m.obj", obj_text()))
    assert_mesh(m)
    # Line 1 is the comment, then 10 v lines.
    np.testing.assert_array_equal(m.face_lines, [12, 13, 14, 15])
    assert m.vertex_weights is None and m.vertex_uvs is None
    assert m.vertex_normals is None and m.face_groups is None
    assert m.group_names == [] and m.path.endswith("m.obj")


@pytest.mark.parametrize("nl", ["\r\n", "\r"])
def test_obj_crlf_and_cr(tmp_path, nl):
    m = read_obj(write(tmp_path, "m.obj", obj_text(nl=nl)))
    assert_mesh(m)
    np.testing.assert_array_equal(m.face_lines, [12, 13, 14, 15])


def test_obj_negative_indices(tmp_path):
    text = ("v 0 0 0\nv 1 0 0\nv 1 1 0\n"
            "f -3 -2 -1\n"          # relative to the 3 vertices above
            "v 0 1 0\n"
            "f 1 -3 -2 -1\n"        # -1 is now vertex 4
            "f -4 2 3\n")
    m = read_obj(write(tmp_path, "m.obj", text))
    np.testing.assert_array_equal(m.face_vertices, [0, 1, 2, 0, 1, 2, 3, 0, 1, 2])
    np.testing.assert_array_equal(m.face_lines, [4, 6, 7])


def test_obj_vt_vn_forms(tmp_path):
    text = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\n"
            "vt 0.1 0.2\nvt 0.3 0.4 0.9\nvt 0.5\n"
            "vn 0 0 1\nvn 0 1 0\n"
            "f 1/1/1 2/2/1 3/3/2\n"     # v/vt/vn
            "f 1/3 3/1 4/2\n"           # v/vt: vertex 1 and 3 keep first uv
            "f 4//2 2//2 3//1\n"        # v//vn
            "f -5/-3/-2 -3/-1/-1 -2/-2/-1\n")
    m = read_obj(write(tmp_path, "m.obj", text))
    np.testing.assert_array_equal(
        m.face_vertices, [0, 1, 2, 0, 2, 3, 3, 1, 2, 0, 2, 3])
    uv = m.vertex_uvs
    np.testing.assert_array_equal(uv[:4], [[0.1, 0.2], [0.3, 0.4],
                                           [0.5, 0.0], [0.3, 0.4]])
    assert np.isnan(uv[4]).all()  # never referenced with a vt
    n = m.vertex_normals
    np.testing.assert_array_equal(n[:4], [[0, 0, 1], [0, 0, 1], [0, 1, 0],
                                          [0, 1, 0]])
    assert np.isnan(n[4]).all()


def test_obj_mixed_corner_forms():
    # Slash counts differ per corner but sum to a multiple of the corner
    # count: must not be mistaken for one uniform form.
    text = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0.5 0.5\nvn 0 0 1\n"
            "f 1/1/1 2 3/1\nf 2//1 3/1/1 4/1\n")
    m = parse_obj(text.encode())
    np.testing.assert_array_equal(m.face_vertices, [0, 1, 2, 1, 2, 3])
    np.testing.assert_array_equal(m.vertex_uvs[[0, 2, 3]], np.full((3, 2), 0.5))
    assert np.isnan(m.vertex_uvs[1]).all()
    np.testing.assert_array_equal(m.vertex_normals[[0, 1, 2]], [[0, 0, 1]] * 3)
    assert np.isnan(m.vertex_normals[3]).all()


def test_obj_slow_path_spellings_match_fast(tmp_path):
    # "1/" and "1//" are odd but legal: handled by the corner-by-corner path.
    odd = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/ 2/ 3/ 4/\nf 1// 2// 3//\n"
    plain = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 1 2 3\n"
    a = parse_obj(odd.encode())
    b = parse_obj(plain.encode())
    np.testing.assert_array_equal(a.face_vertices, b.face_vertices)
    np.testing.assert_array_equal(a.face_sizes, b.face_sizes)
    assert a.vertex_uvs is None and a.vertex_normals is None


def test_obj_chunked_fallback_large(tmp_path):
    # > 4096 faces, one odd corner: only its chunk goes line by line.
    n = 5000
    pts = np.column_stack([np.arange(n + 2), np.zeros(n + 2), np.zeros(n + 2)])
    faces = [[i, i + 1, i + 2] for i in range(n)]
    lines = ["v %d 0 0" % i for i in range(n + 2)]
    lines += ["f %d/%d %d %d" % (i + 1, 1, i + 2, i + 3) if i == 4500 else
              "f %d %d %d" % (i + 1, i + 2, i + 3) for i in range(n)]
    lines.insert(0, "vt 0.25 0.75")
    m = parse_obj(("\n".join(lines) + "\n").replace(
        "f 4501/1 ", "f 4501/1/ ").encode())
    assert_mesh(m, pts, faces)
    assert m.vertex_uvs[4500].tolist() == [0.25, 0.75]
    assert np.isnan(m.vertex_uvs[0]).all()


def test_obj_comments_blank_tabs_bom_and_ignored_records(tmp_path):
    text = ("\ufeff# header\n"
            "mtllib m.mtl\n"
            "o thing\n"
            "\n"
            "  v\t0 0 0   # inline comment\n"
            "v 1 0 0\n"
            "v 1 1 0\n"
            "v 0 1 0\n"
            "vp 0.5\n"
            "s off\n"
            "usemtl red\n"
            "l 1 2\n"
            "p 3\n"
            "f 1 2 3 4 # a quad\n"
            "t crease 2/1/0 0 1 2.0\n"
            "t interpolateboundary 1/0/0 1\n"
            "#f 1 2 3\n")
    m = read_obj(write(tmp_path, "m.obj", text))
    assert_mesh(m, PTS[:4], [[0, 1, 2, 3]])
    np.testing.assert_array_equal(m.face_lines, [14])
    assert m.group_names == ["thing"]
    np.testing.assert_array_equal(m.face_groups, [0])


def test_obj_weights_and_colors(tmp_path):
    m = read_obj(write(tmp_path, "w.obj",
                       "v 0 0 0 2\nv 1 0 0\nv 0 1 0 0.5\nf 1 2 3\n"))
    np.testing.assert_array_equal(m.vertex_weights, [2.0, 1.0, 0.5])
    np.testing.assert_array_equal(m.points, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    m = read_obj(write(tmp_path, "c.obj",
                       "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"))
    assert m.vertex_weights is None
    np.testing.assert_array_equal(m.vertex_attributes["green"], [0, 1, 0])


def test_obj_groups(tmp_path):
    text = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
            "f 1 2 3\n"             # before any group: "default"
            "g body\nf 1 3 4\n"
            "g  arm  left \nf 2 3 4\n"
            "o body\nf 1 2 4\n")
    m = read_obj(write(tmp_path, "m.obj", text))
    assert m.group_names == ["default", "body", "arm left"]
    np.testing.assert_array_equal(m.face_groups, [0, 1, 2, 1])


OBJ_ERRORS = [
    # (content, line, fragments)
    ("", None, ["empty"]),
    ("  \n\n", None, ["empty"]),
    ("# only a comment\nmtllib x.mtl\n", None, ["no `v`"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", None,
     ["has vertices but no faces: c1surf needs polygon faces"]),
    ("f 1 2 3\n", None, ["no vertices"]),
    ("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", 2, ["2 numbers", "x y z"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 abc\nf 1 2 3\n", 3, ["'abc'", "number"]),
    ("v 0 0 0\nv 1 0 1.5.2\nv 0 1 0\nf 1 2 3\n", 2, ["'1.5.2'"]),
    ("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", 2, ["NaN or infinite"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n", 3, ["NaN or infinite"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, ["vertex 4", "only 3"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 0 2\n", 4, ["index 0", "start at 1"]),
    ("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", 3, ["-3", "only 2"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2\n", 5, ["2 vertices", "at least 3"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1\n", 4, ["1 vertex", "at least 3"]),
    # a non-consecutive repeat (a figure-eight polygon) is refused ...
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4\nf 1 2 -4 3\n", 6,
     ["vertex 1 twice", "corners 1 and 3"]),
    # ... a consecutive one ("f a b c c") is a zero-length edge and is dropped,
    # unless fewer than 3 distinct vertices remain
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2 -3\n", 4, ["fewer than 3 distinct vertices"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", 4, ["'x'", "whole number"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.0\n", 4, ["'3.0'"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", 4, ["too many '/'"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf /1 2 3\n", 4, ["no vertex index"]),
    # vt/vn indices that name no record are ignored with a note (test_lenient_input.py); index 0 is refused
    ("v 0 0 0\nv 1 0 0\nvt 0 0\nv 0 1 0\nf 1/0 2/1 3/1\n", 5, ["index 0"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1/0/1 2//1 3//1\n", 5,
     ["texture coordinate index 0"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0\nf 1//1 2//1 3//1\n", 4,
     ["`vn` line has 2 numbers"]),
    ("v 0 0 0\x00\x01\x02", 1, ["not an OBJ text file"]),  # the NUL byte's line (issue 30)
    ("ply\nformat ascii 1.0\nend_header\n", None, [".ply suffix"]),
]


@pytest.mark.parametrize("content,line,fragments", OBJ_ERRORS)
def test_obj_errors(tmp_path, content, line, fragments):
    p = write(tmp_path, "bad.obj", content)
    err = raises_at(lambda: read_obj(p), line, *fragments)
    assert err.path == str(p)
    prefix = f"{p}:{line}: " if line else f"{p}: "
    assert str(err).startswith(prefix)


def test_obj_not_text(tmp_path):
    rng = np.random.default_rng(0)
    junk = rng.integers(1, 256, 4000, dtype=np.uint8).tobytes()  # no NUL
    raises_at(lambda: read_obj(write(tmp_path, "j.obj", junk)), None,
              "not an OBJ text file")
    # A few Latin-1 bytes in a comment or a group name are fine.
    text = "# Cr\xe9\xe9 par moi\ng caf\xe9\n".encode("latin-1") + \
        obj_text().encode()
    m = read_obj(write(tmp_path, "l.obj", text))
    assert_mesh(m)
    assert m.group_names[0].startswith("caf")


def test_obj_error_deep_in_large_file():
    n = 20000
    lines = ["v %d %d 0" % (i, i % 7) for i in range(n)]
    lines += ["f %d %d %d" % (i + 1, i + 2, i + 3) for i in range(n - 2)]
    bad = list(lines)
    bad[15000] = "v 1 2 3e"
    raises_at(lambda: parse_obj("\n".join(bad).encode(), "big.obj"), 15001,
              "'3e'")
    bad = list(lines)
    bad[n + 9000] = "f 9001 9002 9003x"
    raises_at(lambda: parse_obj("\n".join(bad).encode(), "big.obj"),
              n + 9001, "'9003x'")
    bad = list(lines)
    bad[n + 12000] = "f 1 2 %d" % (n + 1)
    raises_at(lambda: parse_obj("\n".join(bad).encode(), "big.obj"),
              n + 12001, f"vertex {n + 1}", f"only {n}")


# ----------------------------------------------------------------------
# PLY


def ply_elements(points=PTS, faces=FACES, index_name="vertex_indices",
                 extra=True, float_type="f8"):
    v = np.empty(len(points), dtype=[("x", float_type), ("y", float_type),
                                     ("z", float_type)]
                 + ([("nx", "f4"), ("ny", "f4"), ("nz", "f4"), ("s", "f4"),
                     ("t", "f4"), ("weight", "f8"), ("red", "u1"),
                     ("green", "u1"), ("blue", "u1")] if extra else []))
    v["x"], v["y"], v["z"] = np.asarray(points).T
    if extra:
        v["nx"], v["ny"], v["nz"] = 0, 0, 1
        v["s"] = np.arange(len(points)) / 16
        v["t"] = 0.5
        v["weight"] = np.arange(len(points)) + 1
        v["red"] = np.arange(len(points))
        v["green"], v["blue"] = 7, 255
    f = np.empty(len(faces), dtype=[(index_name, "O")]
                 + ([("blend", "f4")] if extra else []))
    f[index_name] = [np.asarray(x, dtype=np.int32) for x in faces]
    if extra:
        f["blend"] = np.linspace(0, 1, len(faces))
    return [PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]


def write_ply(path, elements, text=False, byte_order="<", comments=()):
    PlyData(elements, text=text, byte_order=byte_order,
            comments=list(comments)).write(str(path))
    return path


def handmade_binary_ply(path, order):
    """Same mesh as ply_elements(), written without plyfile's writer.

    plyfile 1.1.5 writes scalar properties of an element that also has a
    list property in native order even for big-endian files, so the
    big-endian case is built here byte by byte.
    """
    (v, f) = ply_elements()
    vdata = v.data.astype(v.data.dtype.newbyteorder(order))
    head = ["ply", f"format binary_{'little' if order == '<' else 'big'}"
            "_endian 1.0", "comment made by hand", f"element vertex {len(vdata)}"]
    head += [f"property {t} {n}" for n, t in [
        ("x", "double"), ("y", "double"), ("z", "double"), ("nx", "float"),
        ("ny", "float"), ("nz", "float"), ("s", "float"), ("t", "float"),
        ("weight", "double"), ("red", "uchar"), ("green", "uchar"),
        ("blue", "uchar")]]
    head += [f"element face {len(f.data)}",
             "property list uchar int vertex_indices", "property float blend",
             "end_header"]
    body = [vdata.tobytes()]
    for idx, blend in zip(f.data["vertex_indices"], f.data["blend"]):
        body += [bytes([len(idx)]), np.asarray(idx, order + "i4").tobytes(),
                 np.asarray(blend, order + "f4").tobytes()]
    path.write_bytes(("\n".join(head) + "\n").encode() + b"".join(body))
    return path


@pytest.mark.parametrize("text,order", [(True, "="), (False, "<"), (False, ">")])
def test_ply_mixed_sizes_and_attributes(tmp_path, text, order):
    if text:
        p = write_ply(tmp_path / "m.ply", ply_elements(), text=True,
                      comments=["made by the test"])
    else:
        p = handmade_binary_ply(tmp_path / "m.ply", order)
    m = read_ply(p)
    assert_mesh(m)
    np.testing.assert_array_equal(m.vertex_normals, np.tile([0, 0, 1.0], (10, 1)))
    np.testing.assert_array_equal(m.vertex_uvs[:, 0], np.arange(10) / 16)
    np.testing.assert_array_equal(m.vertex_uvs[:, 1], 0.5)
    np.testing.assert_array_equal(m.vertex_weights, np.arange(10) + 1)
    assert set(m.vertex_attributes) == {"red", "green", "blue"}
    np.testing.assert_array_equal(m.vertex_attributes["red"], np.arange(10))
    assert m.vertex_attributes["red"].dtype.isnative
    np.testing.assert_allclose(m.face_attributes["blend"], [0, 1 / 3, 2 / 3, 1],
                               rtol=1e-6)
    assert set(m.face_attributes) == {"blend"}
    if text:
        # ply, format, comment, element+7 props... count the header lines.
        header = p.read_bytes().split(b"end_header")[0].count(b"\n") + 1
        np.testing.assert_array_equal(
            m.face_lines, header + 10 + np.arange(1, 5))
        lines = p.read_text().splitlines()
        assert lines[m.face_lines[3] - 1].startswith("8 0 1 2 3 4 5 6 9")
    else:
        assert m.face_lines is None


@pytest.mark.parametrize("k", [3, 4])
@pytest.mark.parametrize("order", ["<", ">"])
def test_ply_uniform_faces_fast_path(tmp_path, k, order):
    rng = np.random.default_rng(k)
    pts = rng.random((50, 3))
    faces = [list(rng.choice(50, k, replace=False)) for _ in range(200)]
    p = write_ply(tmp_path / "u.ply", ply_elements(pts, faces, "vertex_index",
                                                   extra=False),
                  byte_order=order)
    m = read_ply(p)
    assert_mesh(m, pts, faces)
    # Fast path memory-maps: results must be plain, writable arrays.
    assert type(m.face_vertices) is np.ndarray and m.face_vertices.flags.writeable
    assert type(m.points) is np.ndarray


def test_ply_extra_element_after_faces(tmp_path):
    # An element after 'face' must not confuse the fixed-size fast path.
    els = ply_elements(PTS, [[0, 1, 2, 3], [4, 5, 6]], extra=False)
    e = np.zeros(3, dtype=[("vertex1", "i4"), ("vertex2", "i4")])
    els.append(PlyElement.describe(e, "edge"))
    m = read_ply(write_ply(tmp_path / "e.ply", els))
    assert_mesh(m, PTS, [[0, 1, 2, 3], [4, 5, 6]])


def ascii_ply(body_vertices, body_faces, vertex_props="xyz",
              face_prop="property list uchar int vertex_indices", nv=None,
              nf=None):
    nv = len(body_vertices) if nv is None else nv
    nf = len(body_faces) if nf is None else nf
    head = ["ply", "format ascii 1.0", f"element vertex {nv}"]
    head += [f"property float {c}" for c in vertex_props]
    head += [f"element face {nf}", face_prop, "end_header"]
    return "\n".join(head + body_vertices + body_faces) + "\n"


V3 = ["0 0 0", "1 0 0", "0 1 0", "1 1 0"]


PLY_ERRORS = [
    # 9 header lines: vertices on lines 10-13, faces from line 14.
    (ascii_ply(V3, ["3 0 1 4"]), 14, ["face 0 refers to vertex 4", "4 vertices"]),
    (ascii_ply(V3, ["3 0 1 2", "3 0 -1 2"]), 15, ["vertex -1"]),
    (ascii_ply(V3, ["3 0 1 2", "2 0 1"]), 15, ["face 1 has 2 vertices"]),
    (ascii_ply(V3, ["4 0 1 2 1"]), 14, ["face 0 visits vertex 1 twice"]),
    (ascii_ply(["0 0 0", "1 nan 0", "0 1 0"], ["3 0 1 2"]), 11,
     ["vertex 1 has a NaN"]),
    (ascii_ply(["0 0", "1 0", "0 1"], ["3 0 1 2"], vertex_props="xy"),
     None, ["no z property"]),
    (ascii_ply(V3, ["3"], face_prop="property int vertex_indices"),
     None, ["no 'vertex_indices' list"]),
    (ascii_ply(V3, ["3 0 1 2"], face_prop="property list uchar int verts"),
     None, ["no 'vertex_indices' list"]),
    (ascii_ply(V3, ["3 0 1 2"], nv=0, nf=0).replace(
        "0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n", ""), None, ["no vertices"]),
    (ascii_ply(V3, [], nf=0), None, ["has vertices but no faces"]),
    (ascii_ply(V3, ["3 0 1 2"], nf=2), 15, ["ends early", "face 1 of 2"]),
    (ascii_ply(["0 0 0", "1 0", "0 1 0", "1 1 0"], ["3 0 1 2"]), 11,
     ["vertex 1 has too few values"]),
    (ascii_ply(V3, ["3 0 1 x"]), 14, ["cannot read face 0"]),
    (ascii_ply(V3, ["3 0 1 2 7"]), 14, ["more values"]),
    ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty "
     "flaot y\nend_header\n", 5, ["bad PLY header"]),
    ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty "
     "float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n", None,
     ["has vertices but no faces"]),
    ("ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int "
     "vertex_indices\nend_header\n3 0 1 2\n", None, ["no 'vertex' element"]),
    ("v 0 0 0\nf 1 2 3\n", None, ["not a PLY file"]),
    ("", None, ["empty"]),
    # impossible header counts name their element line (3: vertex, 7: face), before anything is allocated
    (ascii_ply(V3, ["3 0 1 2"], nv=99999999999), 3, ["99,999,999,999 'vertex' elements", "count is wrong"]),
    (ascii_ply(V3, ["3 0 1 2"], nf=10**23), 7, ["'face' elements", "count is wrong"]),
    (ascii_ply(V3, ["3 0 1 2"], nv=-3), 3, ["negative element count"]),
    # a value outside its declared integer type names its line
    (ascii_ply(V3, ["3 0 1 2", "300 0 1 2"]), 15,
     ["face 1: the list length 300 of property 'vertex_indices'", "0..255", "'uchar'"]),
    (ascii_ply(V3, ["-1 0 1 2"]), 14, ["face 0: the list length -1", "0..255"]),
    (ascii_ply(V3, ["3 0 1 2"], face_prop="property list ushort int vertex_indices").replace("3 0 1 2", "70000 0"),
     14, ["list length 70000", "0..65535", "'ushort'"]),
    (ascii_ply(["0 0 0 1", "1 0 0 256", "0 1 0 3"], ["3 0 1 2"], vertex_props=["x", "y", "z"]).replace(
        "property float z\n", "property float z\nproperty uchar red\n"), 12,
     ["vertex 1: the value 256 of property 'red'", "0..255"]),
]


@pytest.mark.parametrize("content,line,fragments", PLY_ERRORS)
def test_ply_errors(tmp_path, content, line, fragments):
    p = write(tmp_path, "bad.ply", content)
    raises_at(lambda: read_ply(p), line, *fragments)


@pytest.mark.parametrize("faces", [FACES, [[0, 1, 2, 3]] * 3, [[0, 1, 2]] * 3])
def test_ply_truncated_binary(tmp_path, faces):
    p = write_ply(tmp_path / "t.ply", ply_elements(PTS, faces))
    data = p.read_bytes()
    for cut in (len(data) - 3, len(data) - 40, data.index(b"end_header") + 60):
        q = write(tmp_path, "cut.ply", data[:cut])
        raises_at(lambda: read_ply(q), None, "ends early", "truncated")


def test_ply_binary_errors_name_face(tmp_path):
    p = write_ply(tmp_path / "b.ply",
                  ply_elements(PTS, [[0, 1, 2], [0, 1, 12]], extra=False))
    raises_at(lambda: read_ply(p), None, "face 1 refers to vertex 12")
    p = write_ply(tmp_path / "r.ply",
                  ply_elements(PTS, [[0, 1, 2, 3], [4, 5, 4, 6]], extra=False))
    raises_at(lambda: read_ply(p), None, "face 1 visits vertex 4 twice")


def test_ply_junk_after_header(tmp_path):
    rng = np.random.default_rng(3)
    head = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\n" \
        b"property float x\nproperty float y\nproperty float z\n" \
        b"element face 1000\nproperty list uchar int vertex_indices\n" \
        b"end_header\n"
    p = write(tmp_path, "j.ply", head + rng.bytes(12000 + 500))
    with pytest.raises(MeshInputError) as info:
        read_ply(p)
    assert str(info.value).startswith(f"{p}: ")


# ----------------------------------------------------------------------
# read_mesh


def test_read_mesh_dispatch(tmp_path):
    a = read_mesh(write(tmp_path, "A.OBJ", obj_text()))
    b = read_mesh(write_ply(tmp_path / "B.Ply", ply_elements()))
    assert_mesh(a)
    assert_mesh(b)


def test_read_mesh_errors(tmp_path):
    raises_at(lambda: read_mesh(tmp_path / "nope.obj"), None, "no such file")
    raises_at(lambda: read_mesh(tmp_path / "no" / "nope.obj"), None,
              "does not exist either")
    raises_at(lambda: read_mesh(tmp_path), None, "is a directory")
    err = raises_at(lambda: read_mesh(write(tmp_path, "m.glb", "glTF")), None,
                    "unsupported mesh format", ".obj, .off, .ply, .stl")
    assert "'.glb'" in str(err)
    raises_at(lambda: read_mesh(write(tmp_path, "noext", "x")), None,
              "no suffix")


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="root can read anything")
def test_read_mesh_unreadable(tmp_path):
    p = write(tmp_path, "m.obj", obj_text())
    p.chmod(0)
    raises_at(lambda: read_mesh(p), None, "permission denied")


def test_read_mesh_unreadable_simulated(tmp_path, monkeypatch):
    # Same check as above, also when the tests run as root.
    p = write(tmp_path, "m.obj", obj_text())
    monkeypatch.setattr(os, "access", lambda *a, **k: False)
    raises_at(lambda: read_mesh(p), None, "permission denied")


# ----------------------------------------------------------------------
# shared real meshes against MANIFEST.md


def manifest_rows():
    manifest = SHARED / "MANIFEST.md"
    if not manifest.exists():
        return []
    rows = []
    for line in manifest.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 9 and cells[0].endswith(".obj"):
            rows.append(pytest.param(cells[0], int(cells[4]), int(cells[5]),
                                     cells[6], cells[8], id=cells[0]))
    return rows


@pytest.mark.skipif(not SHARED.exists(), reason="../shared/meshes absent")
def test_manifest_lists_every_obj():
    listed = {r.values[0] for r in manifest_rows()}
    on_disk = {str(p.relative_to(SHARED)) for p in SHARED.rglob("*.obj")}
    assert on_disk <= listed


@pytest.mark.parametrize("name,n_vert,n_face,hist,notes", manifest_rows())
def test_shared_meshes_match_manifest(name, n_vert, n_face, hist, notes):
    if "degenerate faces" in notes and "nonman_edges" in name:
        # a face "f a b b" has only two distinct vertices: refused with its line
        with pytest.raises(MeshInputError, match=r":\d+: face has fewer than 3 distinct vertices"):
            read_mesh(SHARED / name)
        return
    m = read_mesh(SHARED / name)
    if "degenerate faces" in notes:
        # OpenSubdiv's quad poles write triangles as quads "f a b c c": the
        # repeated corner is dropped, so the histogram moves quads to triangles.
        assert m.collapsed_corners > 0
        counts = Counter(m.face_sizes.tolist())
        assert m.n_faces == n_face and counts[4] + counts[3] == n_face
        assert find_repeated_vertex(m.face_sizes, m.face_vertices) is None
        return
    assert m.n_vertices == n_vert  # unused vertices included
    assert m.n_faces == n_face
    counts = Counter(m.face_sizes.tolist())
    assert " ".join(f"{k}:{counts[k]}" for k in sorted(counts)) == hist
    assert m.face_vertices.min() >= 0 and m.face_vertices.max() < n_vert
    assert np.isfinite(m.points).all()
    assert find_repeated_vertex(m.face_sizes, m.face_vertices) is None
    text = (SHARED / name).read_text(errors="replace").splitlines()
    assert all(text[i - 1].lstrip().startswith("f") for i in m.face_lines)


# ----------------------------------------------------------------------
# random meshes: OBJ text and binary PLY read back identically


@st.composite
def polygon_meshes(draw):
    n_vert = draw(st.integers(3, 24))
    coords = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False,
                       width=64)
    points = np.array(draw(st.lists(st.tuples(coords, coords, coords),
                                    min_size=n_vert, max_size=n_vert)))
    faces = []
    for _ in range(draw(st.integers(1, 12))):
        k = draw(st.integers(3, min(9, n_vert)))
        faces.append(draw(st.permutations(range(n_vert)))[:k])
    return points, faces


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mesh=polygon_meshes(), style=st.integers(0, 3), relative=st.booleans(),
       crlf=st.booleans(), order=st.sampled_from("<>"))
def test_random_meshes_roundtrip(tmp_path, mesh, style, relative, crlf, order):
    points, faces = mesh
    n = len(points)
    nl = "\r\n" if crlf else "\n"
    lines = ["v " + " ".join(repr(float(c)) for c in p) for p in points]
    lines += ["vt 0.5 0.5", "vn 0 0 1"]
    form = ["{v}", "{v}/1", "{v}//1", "{v}/1/1"][style]
    for f in faces:
        idx = [i - n if relative else i + 1 for i in f]
        lines.append("f " + " ".join(form.format(v=v) for v in idx))
    obj = write(tmp_path, "r.obj", nl.join(lines) + nl)
    ply = write_ply(tmp_path / "r.ply", ply_elements(points, faces, extra=False),
                    byte_order=order)
    a, b = read_obj(obj), read_ply(ply)
    for m in (a, b):
        assert_mesh(m, points, faces)
    np.testing.assert_array_equal(a.face_lines, n + 3 + np.arange(len(faces)))
    assert (a.vertex_uvs is not None) == (style in (1, 3))
    assert (a.vertex_normals is not None) == (style in (2, 3))


@settings(max_examples=40, deadline=None)
@given(mesh=polygon_meshes(), forms=st.lists(st.integers(0, 3), min_size=12,
                                             max_size=12))
def test_random_obj_slow_path_agrees(mesh, forms):
    """The corner-by-corner fallback gives what the bulk parse gives."""
    import c1surf.io.meshes.obj_text as obj_module
    points, faces = mesh
    lines = ["v " + " ".join(repr(float(c)) for c in p) for p in points]
    lines += ["vt 0.5 0.25", "vn 0 0 1"]
    for f, style in zip(faces, forms):  # mixed corner forms across faces
        form = ["{v}", "{v}/1", "{v}//1", "{v}/1/1"][style]
        lines.append("f " + " ".join(form.format(v=i + 1) for i in f))
    data = ("\n".join(lines) + "\n").encode()
    fast = parse_obj(data)
    real = obj_module._fast_corners
    obj_module._fast_corners = lambda *a: None  # force the fallback
    try:
        slow = parse_obj(data)
    finally:
        obj_module._fast_corners = real
    for name in ("face_sizes", "face_vertices", "face_lines", "vertex_uvs",
                 "vertex_normals"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(slow, name))


# ----------------------------------------------------------------------
# atomic_output


def test_atomic_success_replaces(tmp_path):
    target = tmp_path / "out.ply"
    target.write_text("old")
    target.chmod(0o640)
    with atomic_output(target) as tmp:
        tmp = Path(tmp)
        assert tmp.parent == tmp_path and tmp.name.endswith(".out.ply")
        assert tmp.name.startswith(".tmp-c1surf-") and tmp.suffix == ".ply"
        assert target.read_text() == "old"  # untouched until the end
        tmp.write_text("new")
    assert target.read_text() == "new"
    assert oct(target.stat().st_mode & 0o777) == oct(0o640)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.ply"]


def test_atomic_new_file_and_default_mode(tmp_path):
    target = tmp_path / "new.json"
    with atomic_output(str(target), inputs=[tmp_path / "in.obj"]) as tmp:
        Path(tmp).write_text("{}")
    assert target.read_text() == "{}"
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask


@pytest.mark.parametrize("exc", [RuntimeError, KeyboardInterrupt])
@pytest.mark.parametrize("existing", [False, True])
def test_atomic_failure_leaves_nothing(tmp_path, exc, existing):
    target = tmp_path / "out.obj"
    if existing:
        target.write_text("keep me")
    with pytest.raises(exc):
        with atomic_output(target) as tmp:
            Path(tmp).write_text("half written")
            raise exc("boom")
    if existing:
        assert target.read_text() == "keep me"
        assert [p.name for p in tmp_path.iterdir()] == ["out.obj"]
    else:
        assert list(tmp_path.iterdir()) == []


def test_atomic_refuses_input(tmp_path):
    src = write(tmp_path, "m.obj", obj_text())
    link = tmp_path / "link.obj"
    link.symlink_to(src)
    hard = tmp_path / "hard.obj"
    os.link(src, hard)
    for out, inputs in [(src, [src]), (str(src), ["./x.obj", str(src)]),
                        (link, [src]), (src, [link]), (hard, [src]),
                        (tmp_path / "sub" / ".." / "m.obj", [src])]:
        if "sub" in str(out):
            (tmp_path / "sub").mkdir(exist_ok=True)
        with pytest.raises(OutputError, match="overwrite the input"):
            with atomic_output(out, inputs=inputs):
                pytest.fail("must not get here")
    assert src.read_text() == obj_text()
    assert not any(p.name.startswith(".tmp-c1surf-") for p in tmp_path.iterdir())


def test_atomic_bad_targets(tmp_path):
    with pytest.raises(OutputError, match="does not exist") as info:
        with atomic_output(tmp_path / "missing" / "o.ply"):
            pass
    assert str(info.value).startswith(str(tmp_path / "missing" / "o.ply") + ": ")
    with pytest.raises(OutputError, match="is a directory"):
        with atomic_output(tmp_path):
            pass
    f = write(tmp_path, "file", "x")
    with pytest.raises(OutputError, match="not a folder"):
        with atomic_output(f / "o.ply"):
            pass


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="root can write anywhere")
def test_atomic_unwritable_dir(tmp_path):
    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(0o500)
    try:
        with pytest.raises(OutputError, match="not writable"):
            with atomic_output(d / "o.ply"):
                pass
    finally:
        d.chmod(0o700)


def test_atomic_unwritable_dir_simulated(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "access", lambda *a, **k: False)
    with pytest.raises(OutputError, match="not writable"):
        with atomic_output(tmp_path / "o.ply"):
            pass


def test_atomic_writer_removed_temp(tmp_path):
    with pytest.raises(OutputError, match="did not produce"):
        with atomic_output(tmp_path / "o.ply") as tmp:
            os.unlink(tmp)
    assert list(tmp_path.iterdir()) == []


def test_error_strings_and_pickle():
    import pickle
    e = MeshInputError("a.obj", "bad thing: do X", 7)
    assert str(e) == "a.obj:7: bad thing: do X"
    assert str(MeshInputError(Path("a.obj"), "m")) == "a.obj: m"
    e2 = pickle.loads(pickle.dumps(e))
    assert (e2.path, e2.line, e2.message) == ("a.obj", 7, "bad thing: do X")
    o = pickle.loads(pickle.dumps(OutputError("o.ply", "no")))
    assert str(o) == "o.ply: no" and o.line is None
    assert re.fullmatch(r"\S+: .+", str(o))
