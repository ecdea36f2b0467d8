"""Lenient readers (issue 13): what OBJ and PLY exporters write where the intent is clear.

OBJ: dangling ``vt``/``vn`` indices are ignored with one note; ``l``, ``p``, ``mtllib``, ``usemtl`` and ``s``
records are accepted (the geometry ones named in a note); ``\\`` continues a line. PLY: ``tristrips``
elements are read as triangles (degenerate ones dropped with a note); face lists of any integer type.
What stays refused keeps its one-line ``FILE:LINE:`` error.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from plyfile import PlyData, PlyElement

from c1surf.cli.main import main
from c1surf.construction.surface import Surface
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.io.errors import MeshInputError
from c1surf.io.meshes.obj import read_obj
from c1surf.io.meshes.ply import read_ply, strip_triangles
from c1surf.io.meshes.read import read_mesh

CUBE_POINTS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_FACES = [[1, 4, 3, 2], [5, 6, 7, 8], [1, 2, 6, 5], [2, 3, 7, 6], [3, 4, 8, 7], [4, 1, 5, 8]]  # 1-based, outward
CUBE_V = "".join(f"v {x} {y} {z}\n" for x, y, z in CUBE_POINTS)

# An octahedron as two strip rows: a -1 restart in the second, and a turn (5, 5) that gives two degenerate triangles.
OCTA_POINTS = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
OCTA_STRIPS = [[0, 2, 4, 1, 3, 5, 0, 2], [3, 0, 4, -1, 1, 2, 5, 5, 2]]
# triangle k of a strip is (v_k, v_k+1, v_k+2), flipped to (v_k+1, v_k, v_k+2) for odd k
OCTA_TRIANGLES = [[0, 2, 4], [4, 2, 1], [4, 1, 3], [3, 1, 5], [3, 5, 0], [0, 5, 2], [3, 0, 4], [1, 2, 5]]


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def notes(result) -> list[str]:
    return [line for line in result.stderr.splitlines() if line.startswith("c1surf: note:")]


def write(tmp_path, name, text: str):
    path = tmp_path / name
    path.write_text(text)
    return path


def refused_at(path, line, *fragments):
    with pytest.raises(MeshInputError) as info:
        read_mesh(path)
    text = str(info.value)
    assert info.value.line == line and text.startswith(f"{path}:{line}: " if line else f"{path}: "), text
    assert "\n" not in text and all(f in text for f in fragments), text


def assert_g1_conversion(tmp_path, path):
    """`c1surf convert` writes a mesh and patches; `c1surf check` finds the patches G1; returns convert's notes."""
    patches = tmp_path / "patches.json"
    result = run("convert", path, "-o", tmp_path / "out.ply", "--patches", patches, "-r", 2)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "out.ply").stat().st_size > 0
    check = run("check", patches)
    assert check.exit_code == 0 and "G1: yes" in check.output, check.output
    data = read_mesh(path)
    report = measure_smoothness([(s := Surface(data.face_sizes, data.face_vertices, data.points)).biquadratic,
                                 s.bicubic])
    assert report.overshared_edges == 0 and report.boundary_edges == 0 and report.max_normal_jump < 1e-9
    return notes(result)


# ----------------------------------------------------------------------
# OBJ: dangling vt / vn


def cube_obj(corner: str) -> str:
    """The cube, each face corner written as ``corner.format(v=...)``."""
    return CUBE_V + "".join("f " + " ".join(corner.format(v=v) for v in f) + "\n" for f in CUBE_FACES)


def test_obj_normals_without_vn_lines_convert_with_one_note(tmp_path):
    path = write(tmp_path, "n.obj", cube_obj("{v}//{v}"))
    m = read_obj(path)
    assert m.vertex_normals is None and m.vertex_uvs is None
    np.testing.assert_array_equal(m.face_vertices, np.array(CUBE_FACES).reshape(-1) - 1)
    assert m.reader_notes == [f"{path}: ignored 24 normal indices that name no `vn` line (the file has none): "
                              "the faces are read without them"]
    assert assert_g1_conversion(tmp_path, path) == [f"c1surf: note: {m.reader_notes[0]}"]


def test_obj_dangling_vt_and_vn_together_give_one_note(tmp_path):
    # 24 corners: vt 1..24 against 2 `vt` lines, vn 1..24 against 3 `vn` lines (negative ones too)
    faces = "".join("f " + " ".join(f"{v}/{4 * i + j + 1}/{-(4 * i + j + 1)}" for j, v in enumerate(f)) + "\n"
                    for i, f in enumerate(CUBE_FACES))
    path = write(tmp_path, "tn.obj", CUBE_V + "vt 0.5 0.25\nvt 0.75 1\nvn 0 0 1\nvn 0 1 0\nvn 1 0 0\n" + faces)
    m = read_obj(path)
    assert m.reader_notes == [f"{path}: ignored 22 texture coordinate indices that name no `vt` line (the file has 2) "
                              "and 21 normal indices that name no `vn` line (the file has 3): the faces are read "
                              "without them"]
    # the valid references are kept: corner 1 (vertex 1) has vt 1 and vn -1 (the last `vn`), corner 2 (vertex 4) vt 2
    np.testing.assert_array_equal(m.vertex_uvs[0], [0.5, 0.25])
    np.testing.assert_array_equal(m.vertex_uvs[3], [0.75, 1])
    np.testing.assert_array_equal(m.vertex_normals[0], [1, 0, 0])
    assert np.isnan(m.vertex_uvs[[1, 2, 4, 5, 6, 7]]).all()
    result = run("convert", path, "-o", tmp_path / "out.obj", "-r", 2)
    assert result.exit_code == 0, result.output
    assert notes(result) == [f"c1surf: note: {m.reader_notes[0]}"]


@pytest.mark.parametrize("text,note", [
    # the cases test_io_read.OBJ_ERRORS refused before issue 13
    ("v 0 0 0\nv 1 0 0\nvt 0 0\nv 0 1 0\nf 1/1 2/2 3/1\n", "1 texture coordinate index that names no `vt` line "
     "(the file has 1)"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", "1 normal index that names no `vn` line (the file has 1)"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", "3 texture coordinate indices that name no `vt` line "
     "(the file has none)"),
])
def test_obj_dangling_indices_that_were_refused(tmp_path, text, note):
    m = read_obj(write(tmp_path, "d.obj", text))
    np.testing.assert_array_equal(m.face_vertices, [0, 1, 2])
    assert len(m.reader_notes) == 1 and note in m.reader_notes[0]


def test_obj_index_zero_and_bad_positions_are_still_refused(tmp_path):
    refused_at(write(tmp_path, "z.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//0 2//1 3//1\n"), 5, "normal index 0")
    refused_at(write(tmp_path, "p.obj", cube_obj("{v}//{v}").replace("f 1//1", "f 9//1")),
               9, "vertex 9", "only 8 `v` lines")
    refused_at(write(tmp_path, "nan.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1//4 2//4 3//4\n"), 2, "NaN")


# ----------------------------------------------------------------------
# OBJ: ignored records and line continuations


def test_obj_ignored_records_and_continuations_convert(tmp_path):
    text = ("mtllib cube.mtl\n"
            "o cube\n"
            + CUBE_V.replace("v 1 1 1\n", "v 1 \\\n  1 \\\n 1\n")  # lines 9-11
            + "usemtl red\ns 1\nl 1 2 3\nl 5 6\np 7\n"
            + "g body\n"  # line 18
            + "f 1 4 \\\n 3 2\n"  # lines 19-20
            + "".join("f " + " ".join(map(str, f)) + "\n" for f in CUBE_FACES[1:4])
            + "s off\ng lid\nf 3 4 8 7\nf 4 1 \\\r\n 5 8\n")
    path = write(tmp_path, "r.obj", text)
    m = read_obj(path)
    np.testing.assert_array_equal(m.points, CUBE_POINTS)
    np.testing.assert_array_equal(m.face_vertices, np.array(CUBE_FACES).reshape(-1) - 1)
    np.testing.assert_array_equal(m.face_lines, [19, 21, 22, 23, 26, 27])  # a joined face keeps its first line
    assert m.group_names == ["body", "lid"]
    np.testing.assert_array_equal(m.face_groups, [0, 0, 0, 0, 1, 1])
    note = f"{path}: ignored 2 line (`l`) records, 1 point (`p`) record: c1surf builds the surface from the `f` faces only"
    assert m.reader_notes == [note]
    assert assert_g1_conversion(tmp_path, path) == [f"c1surf: note: {note}"]
    # groups still name faces for a blend file
    blend = tmp_path / "blend.json"
    blend.write_text(json.dumps({"default": 0.5, "faces": {"lid": 0.25}}))
    result = run("convert", path, "-o", tmp_path / "b.obj", "-r", 2, "--blend-file", blend, "--quiet")
    assert result.exit_code == 0 and result.stderr == "", result.output


def test_obj_check_prints_the_reader_notes(tmp_path):
    path = write(tmp_path, "c.obj", cube_obj("{v}") + "l 1 7\n")
    result = run("check", path)
    assert result.exit_code == 0 and "G1: yes" in result.output
    assert notes(result) == [f"c1surf: note: {path}: ignored 1 line (`l`) record: c1surf builds the surface from "
                             "the `f` faces only"]


def test_obj_plain_file_has_no_reader_notes(tmp_path):
    assert read_obj(write(tmp_path, "plain.obj", "mtllib a.mtl\nusemtl b\ns 1\n" + cube_obj("{v}"))).reader_notes == []


@pytest.mark.parametrize("text,line,fragments", [
    # an error in a continued record points at its first physical line
    ("v 0 0 0\nv 1 \\\n 0 abc\nv 0 1 0\nf 1 2 3\n", 2, ["'abc'"]),
    ("v 0 0 0\nv 1 \\\n 0 nan\nv 0 1 0\nf 1 2 3\n", 2, ["NaN or infinite"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 \\\n 2 \\\n 4\nf 1 2 3\n", 5, ["vertex 4", "only 3"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2\n", 4, ["2 vertices", "at least 3"]),
    # l and p lines are not faces
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3 1\np 1\n", None, ["has vertices but no faces"]),
])
def test_obj_refusals_with_continuations(tmp_path, text, line, fragments):
    refused_at(write(tmp_path, "bad.obj", text), line, *fragments)


def test_obj_backslash_inside_a_line_is_not_a_continuation(tmp_path):
    m = read_obj(write(tmp_path, "w.obj", "mtllib C:\\models\\a.mtl\ng a\\b\n" + cube_obj("{v}") + "v 0 0 0 \\"))
    assert m.n_faces == 6 and m.n_vertices == 9 and m.group_names == ["a\\b"]


# ----------------------------------------------------------------------
# PLY: tristrips


def octa_ply(tmp_path, fmt: str, index_type="i4", strips=OCTA_STRIPS, extra_face=None):
    """The octahedron with ``strips`` (and ``extra_face`` rows in a 'face' element), each row with a ``part`` short.

    ASCII files are written by plyfile. Binary ones are written here: plyfile 1.1.5 writes the scalars of an
    element with a list property in the machine's byte order, also in a big-endian file.
    """
    elements = [("tristrips", strips, index_type, np.arange(len(strips)) + 7)]
    if extra_face is not None:
        elements.insert(0, ("face", extra_face, "i4", np.ones(len(extra_face), int)))
    path = tmp_path / f"octa_{fmt}.ply"
    if fmt == "ascii":
        plys = [PlyElement.describe(np.array(OCTA_POINTS, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")]), "vertex")]
        for name, rows, itype, part in elements:
            data = np.empty(len(rows), dtype=[("vertex_indices", object), ("part", "i2")])
            for i, row in enumerate(rows):
                data["vertex_indices"][i] = np.array(row, dtype=itype)
            data["part"] = part
            plys.append(PlyElement.describe(data, name, val_types={"vertex_indices": itype}))
        PlyData(plys, text=True).write(str(path))
        return path
    order = {"big": ">", "little": "<"}[fmt]
    header = [f"ply\nformat binary_{fmt}_endian 1.0\nelement vertex {len(OCTA_POINTS)}\n"
              "property double x\nproperty double y\nproperty double z\n"]
    body = [np.array(OCTA_POINTS, dtype=order + "f8").tobytes()]
    for name, rows, itype, part in elements:
        header.append(f"element {name} {len(rows)}\nproperty list uchar {_PLY_TYPE[itype]} vertex_indices\n"
                      "property short part\n")
        for row, value in zip(rows, part):
            body += [np.uint8(len(row)).tobytes(), np.array(row, dtype=order + itype).tobytes(),
                     np.array(value, dtype=order + "i2").tobytes()]
    path.write_bytes("".join(header).encode() + b"end_header\n" + b"".join(body))
    return path


def test_strip_triangles_alternate_and_restart():
    flat = np.array([0, 1, 2, 3, 4, -1, 5, 6, 7, 8, 9, 10, 11])
    row = np.array([0] * 9 + [1] * 4)
    triangles, rows = strip_triangles(flat, row)
    assert triangles.tolist() == [[0, 1, 2], [2, 1, 3], [2, 3, 4], [5, 6, 7], [8, 9, 10], [10, 9, 11]]
    assert rows.tolist() == [0, 0, 0, 0, 1, 1]  # a row starts a new strip
    assert strip_triangles(np.array([1, 2, -1, 3]), np.zeros(4, int))[0].shape == (0, 3)


@pytest.mark.parametrize("fmt", ["ascii", "little", "big"])
def test_ply_tristrips_read_as_triangles(tmp_path, fmt):
    path = octa_ply(tmp_path, fmt)
    m = read_ply(path)
    assert m.face_vertices.reshape(-1, 3).tolist() == OCTA_TRIANGLES
    np.testing.assert_array_equal(m.face_sizes, [3] * 8)
    np.testing.assert_array_equal(m.face_attributes["part"], [7] * 6 + [8] * 2)  # per strip row
    if fmt == "ascii":  # header 10 lines, 6 vertex lines: the strip rows are lines 17 and 18
        np.testing.assert_array_equal(m.face_lines, [17] * 6 + [18] * 2)
    else:
        assert m.face_lines is None
    assert m.reader_notes == [f"{path}: dropped 2 degenerate strip triangles (a repeated vertex, where a strip turns)"]
    got = assert_g1_conversion(tmp_path, path)
    assert got == [f"c1surf: note: {m.reader_notes[0]}"]  # no "flipped" note: the strip orientation is kept


@pytest.mark.parametrize("index_type", ["i1", "i2", "i4"])
def test_ply_tristrips_of_every_signed_index_type(tmp_path, index_type):
    m = read_ply(octa_ply(tmp_path, "little", index_type))
    assert m.face_vertices.reshape(-1, 3).tolist() == OCTA_TRIANGLES


@pytest.mark.parametrize("fmt", ["ascii", "little"])
def test_ply_faces_and_tristrips_together(tmp_path, fmt):
    strips = [[0, 2, 4, 1, 3, 5, 0, 2], [3, 0, 4]]
    m = read_ply(octa_ply(tmp_path, fmt, strips=strips, extra_face=[[1, 2, 5]]))
    assert m.face_vertices.reshape(-1, 3).tolist() == [[1, 2, 5]] + OCTA_TRIANGLES[:7]
    np.testing.assert_array_equal(m.face_attributes["part"], [1] + [7] * 6 + [8])
    assert m.reader_notes == []


@pytest.mark.parametrize("strips,row,fragments", [
    ([[0, 2, 4, 1, 3, 6]], 0, ["tristrips 0 refers to vertex 6", "valid: 0..5"]),
    ([[0, 2, 4], [1, 3, -2]], 1, ["vertex -2", "-1 to restart"]),
    ([[0, 2, 2, 4], [1, -1, 3, 3, 5]], None, ["no triangle with 3 distinct vertices"]),
])
def test_ply_bad_tristrips_are_refused(tmp_path, strips, row, fragments):
    path = octa_ply(tmp_path, "ascii", strips=strips)
    refused_at(path, None if row is None else 17 + row, *fragments)


# ----------------------------------------------------------------------
# PLY: face lists of any integer type


@pytest.mark.parametrize("fmt", ["ascii", "little", "big"])
@pytest.mark.parametrize("name", ["vertex_index", "vertex_indices"])
@pytest.mark.parametrize("len_type,val_type", [("u1", "u1"), ("u1", "i1"), ("u1", "u2"), ("u2", "i2"),
                                               ("i4", "i4"), ("u1", "u4"), ("u4", "i4")])
def test_ply_face_lists_of_any_integer_type(tmp_path, fmt, name, len_type, val_type):
    vertex = np.array(CUBE_POINTS, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    faces = np.empty(6, dtype=[(name, object)])
    for i, f in enumerate(CUBE_FACES):
        faces[name][i] = np.array(f, dtype=val_type) - 1
    elements = [PlyElement.describe(vertex, "vertex"),
                PlyElement.describe(faces, "face", len_types={name: len_type}, val_types={name: val_type})]
    path = tmp_path / "cube.ply"
    PlyData(elements, text=fmt == "ascii", byte_order={"big": ">", "little": "<"}.get(fmt, "=")).write(str(path))
    assert f"property list {_PLY_TYPE[len_type]} {_PLY_TYPE[val_type]} {name}".encode() in path.read_bytes()[:400]
    m = read_ply(path)
    np.testing.assert_array_equal(m.face_vertices, np.array(CUBE_FACES).reshape(-1) - 1)
    assert m.face_vertices.dtype == np.int64 and m.reader_notes == []
    if (fmt, name, val_type) == ("little", "vertex_index", "u2"):  # one full run through the CLI
        assert assert_g1_conversion(tmp_path, path) == []


_PLY_TYPE = {"u1": "uchar", "i1": "char", "u2": "ushort", "i2": "short", "u4": "uint", "i4": "int"}
