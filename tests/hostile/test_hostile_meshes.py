"""Hostile mesh files for every reader (OBJ, PLY ASCII and binary, OFF, STL ASCII and binary): truncations at
random offsets, random bytes under each suffix, huge declared counts, NaN/Inf/huge/tiny coordinates,
degenerate geometry. Each: one ``c1surf: error:`` line and no output, or a finite output (issue 30)."""
from __future__ import annotations

import io
import struct

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, given, settings, strategies as st

from hostile_cases import assert_outcome, cube_text, run, scaled_cube_obj

pytestmark = pytest.mark.filterwarnings("error")  # a warning would be a second stderr line
FAST = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
CUBE = trimesh.Trimesh(*(lambda m: (m.vertices, m.faces))(trimesh.creation.box()), process=False)


def _ply_ascii() -> bytes:
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    head = ("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 6\nproperty list uchar int vertex_indices\nend_header\n")
    return (head + "".join(f"{a:g} {b:g} {c:g}\n" for a, b, c in v)
            + "".join("4 " + " ".join(map(str, f)) + "\n" for f in faces)).encode()


def _off() -> bytes:
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return ("OFF\n8 6 0\n" + "".join(f"{a:g} {b:g} {c:g}\n" for a, b, c in v)
            + "".join("4 " + " ".join(map(str, f)) + "\n" for f in faces)).encode()


SOURCES = {
    "obj": (".obj", cube_text().encode()),
    "ply-ascii": (".ply", _ply_ascii()),
    "ply-binary": (".ply", CUBE.export(file_type="ply", encoding="binary")),
    "off": (".off", _off()),
    "stl-ascii": (".stl", CUBE.export(file_type="stl_ascii").encode()),
    "stl-binary": (".stl", CUBE.export(file_type="stl")),
}


def convert_bytes(folder, data: bytes, suffix: str, *more):
    """Write ``data`` as input.SUFFIX in ``folder``, convert it at -r 2, assert the promise; the result."""
    source, out = folder / f"input{suffix}", folder / "out.ply"
    source.write_bytes(data)
    out.unlink(missing_ok=True)
    result = run("convert", source, "-o", out, "-r", "2", "-q", *more)
    assert_outcome(result, folder, [out])
    return result


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_each_reader_reads_its_sample(tmp_path, name):
    suffix, data = SOURCES[name]
    assert convert_bytes(tmp_path, data, suffix).exit_code == 0


@pytest.mark.parametrize("name", sorted(SOURCES))
@FAST
@given(fraction=st.floats(0.0, 1.0, exclude_max=True))
def test_truncated_at_any_offset(tmp_path, name, fraction):
    suffix, data = SOURCES[name]
    convert_bytes(tmp_path, data[: int(fraction * len(data))], suffix)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".off", ".stl"])
@FAST
@given(data=st.binary(max_size=600))
def test_random_bytes(tmp_path, suffix, data):
    convert_bytes(tmp_path, data, suffix)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".off", ".stl"])
@FAST
@given(data=st.binary(max_size=300), at=st.floats(0.0, 1.0))
def test_random_bytes_inside_a_valid_file(tmp_path, suffix, data, at):
    name = {".obj": "obj", ".ply": "ply-ascii", ".off": "off", ".stl": "stl-ascii"}[suffix]
    valid = SOURCES[name][1]
    k = int(at * len(valid))
    convert_bytes(tmp_path, valid[:k] + data + valid[k:], suffix)


HUGE_COUNTS = [
    (".ply", _ply_ascii().replace(b"element vertex 8", b"element vertex 99999999999999")),
    (".ply", _ply_ascii().replace(b"element face 6", b"element face 4000000000")),
    (".ply", _ply_ascii().replace(b"element vertex 8", b"element vertex -8")),
    (".ply", CUBE.export(file_type="ply", encoding="binary").replace(b"element vertex 8", b"element vertex 900000000")),
    (".off", _off().replace(b"8 6 0", b"8 99999999999999 0")),
    (".off", _off().replace(b"8 6 0", b"-8 6 0")),
    (".stl", CUBE.export(file_type="stl")[:80] + struct.pack("<I", 4_000_000_000) + CUBE.export(file_type="stl")[84:]),
    (".obj", cube_text().replace("f 1 ", "f 999999999999999999999 ", 1).encode()),
    (".obj", cube_text().replace("f 1 ", "f -99999999999 ", 1).encode()),
    (".obj", cube_text().replace("f 1 ", "f 0 ", 1).encode()),
    (".ply", _ply_ascii().replace(b"4 0 1 3 2", b"255 0 1 3 2")),
    (".ply", _ply_ascii().replace(b"4 0 1 3 2", b"300 0 1 3 2")),
]


# the line each PLY case names (ASCII: the header's element line or the face's line; binary: the header's)
PLY_LINES = {0: 3, 1: 7, 2: 3, 3: 4, 11: 18}


@pytest.mark.parametrize("case", range(len(HUGE_COUNTS)))
def test_huge_declared_counts_and_indices(tmp_path, case):
    suffix, data = HUGE_COUNTS[case]
    result = convert_bytes(tmp_path, data, suffix)
    assert result.exit_code == 1
    if case in PLY_LINES:
        assert f"input.ply:{PLY_LINES[case]}: " in result.stderr, result.stderr


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e308", "1e309", "-1e400", "1e-320"])
@pytest.mark.parametrize("suffix", [".obj", ".ply", ".off"])
def test_non_finite_and_extreme_coordinates(tmp_path, suffix, value):
    text = {".obj": cube_text().encode(), ".ply": _ply_ascii(), ".off": _off()}[suffix]
    old = b"v 1.0 1.0 1.0" if suffix == ".obj" else b"1 1 1"
    assert old in text
    new = (b"v " if suffix == ".obj" else b"") + f"{value} 1 1".encode()
    result = convert_bytes(tmp_path, text.replace(old, new, 1), suffix)
    if value != "1e-320":
        assert result.exit_code == 1


@pytest.mark.parametrize("scale,offset,refused", [
    (1e308 / 2, 0.0, True), (1e300, 0.0, True), (1e80, 0.0, True), (1e49, 0.0, False),
    (1e-300, 0.0, True), (1e-80, 0.0, True), (1e-49, 0.0, False), (1.0, 1e200, True),
    (1e-30, 1.0, True),  # at 1 +- 1e-30 every vertex rounds to one point
])
def test_coordinates_the_construction_cannot_take(tmp_path, scale, offset, refused):
    """The issue's cube at +-1e308 (NaN) and scaled by 1e-300 or 1e300 (zero normals): refused, saying what
    scale works; within the range: converted, normals of unit length."""
    result = convert_bytes(tmp_path, scaled_cube_obj(scale, offset).encode(), ".obj")
    assert (result.exit_code == 1) == refused, result.stderr
    if refused:
        assert "scale" in result.stderr or "one point" in result.stderr
    else:
        from plyfile import PlyData

        vertex = PlyData.read(str(tmp_path / "out.ply"))["vertex"].data
        normals = np.stack([vertex["nx"], vertex["ny"], vertex["nz"]], axis=1)
        assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)


DEGENERATE = {
    "line": "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 3 3 3\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n",
    "point": "v 1 1 1\nv 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n",
    "repeated corners": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 1\n",
    "no faces": "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
    "empty": "",
    "one triangle": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "two-sided card": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n",
    "bowtie": "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 3 2 4\n",
}


@pytest.mark.parametrize("name", sorted(DEGENERATE))
@pytest.mark.parametrize("command", ["convert", "measure", "check", "inspect"])
def test_degenerate_geometry(tmp_path, name, command):
    source = tmp_path / "input.obj"
    source.write_text(DEGENERATE[name])
    out = tmp_path / "out.ply"
    args = ["-o", out, "-r", "2", "-q"] if command == "convert" else []
    result = run(command, source, *args)
    assert_outcome(result, tmp_path, [out] if command == "convert" else [], verdict=command == "check")
    if name in ("line", "point") and command == "inspect":  # a report: it names the refusal
        assert result.exit_code == 0 and "refused:" in result.stdout and "the mesh spans no surface" in result.stdout
    elif name in ("line", "point"):
        assert result.exit_code == 1 and "the mesh spans no surface" in result.stderr


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".off"])
def test_byte_order_mark_alike_in_every_text_format(tmp_path, suffix):
    text = {".obj": cube_text().encode(), ".ply": _ply_ascii(), ".off": _off()}[suffix]
    assert convert_bytes(tmp_path, b"\xef\xbb\xbf" + text, suffix).exit_code == 0


def test_nul_byte_in_an_obj_names_its_line(tmp_path):
    text = cube_text().replace("v 1.0 1.0 1.0", "v 1.0 1.0\x00 1.0")
    line = next(k for k, row in enumerate(text.splitlines(), 1) if "\x00" in row)
    result = convert_bytes(tmp_path, text.encode(), ".obj")
    assert result.exit_code == 1 and f"input.obj:{line}: " in result.stderr


def test_invalid_stl_is_one_line_without_charset_normalizer(tmp_path):
    result = convert_bytes(tmp_path, bytes(range(256)) * 3, ".stl")
    assert result.exit_code == 1 and "charset_normalizer" not in result.stderr and "not an STL file" in result.stderr


def test_truncated_ascii_ply_leaks_no_warning(tmp_path):
    data = _ply_ascii()
    result = convert_bytes(tmp_path, data[: data.index(b"4 0 1 3 2") + 2], ".ply")
    assert result.exit_code == 1 and "Warning" not in result.stderr


def test_malformed_ply_counts_are_our_words(tmp_path):
    result = convert_bytes(tmp_path, _ply_ascii().replace(b"4 0 1 3 2", b"300 0 1 3 2"), ".ply")
    assert "out of bounds" not in result.stderr and "uint8" not in result.stderr
    result = convert_bytes(tmp_path, _ply_ascii().replace(b"element vertex 8", b"element vertex -8"), ".ply")
    assert "input.ply:3: " in result.stderr and "negative" in result.stderr


def test_malformed_ascii_stl_names_its_line_in_our_words(tmp_path):
    text = SOURCES["stl-ascii"][1].decode()
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if line.strip().startswith("vertex"))
    bad = lines[:k] + ["vertex 1 2"] + lines[k + 1:]
    result = convert_bytes(tmp_path, ("\n".join(bad) + "\n").encode(), ".stl")
    assert result.exit_code == 1 and f"input.stl:{k + 1}: " in result.stderr and "three numbers" in result.stderr
    bad = lines[:k] + lines[k + 1:]  # a facet of two vertices
    result = convert_bytes(tmp_path, ("\n".join(bad) + "\n").encode(), ".stl")
    assert result.exit_code == 1 and "a triangle needs 3" in result.stderr and "reshape" not in result.stderr


@FAST
@given(exponent=st.integers(-330, 308), mantissa=st.floats(1.0, 9.99), offset=st.sampled_from([0.0, 1.0, -3e5, 1e30]))
def test_any_scale_is_refused_or_gives_unit_normals(tmp_path, exponent, mantissa, offset):
    """A cube at any scale and offset: refused in one line (what scale works), or converted with finite points and
    unit normals (no zero normals from underflow, no NaN from overflow)."""
    from plyfile import PlyData

    result = convert_bytes(tmp_path, scaled_cube_obj(mantissa * 10.0 ** exponent, offset).encode(), ".obj")
    if result.exit_code == 0:
        vertex = PlyData.read(str(tmp_path / "out.ply"))["vertex"].data
        normals = np.stack([vertex["nx"], vertex["ny"], vertex["nz"]], axis=1)
        assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
