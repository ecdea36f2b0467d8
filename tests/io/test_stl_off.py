"""STL and OFF inputs (io/meshes/formats), and welding as the commands and the API do it."""
from __future__ import annotations

import struct

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from c1surf.api import check_surface, surface_from_file
from c1surf.cli.main import main
from c1surf.io.errors import MeshInputError
from c1surf.io.meshes.formats.off import parse_off
from c1surf.io.meshes.read import read_mesh
from c1surf.io.registry import MESH_READERS

MAX_JUMP = 1e-10  # radians, as in tests/construction
FUZZ = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def icosahedron():
    """(12, 3) points and (20, 3) outward triangles of a regular icosahedron."""
    t = (1 + 5 ** 0.5) / 2
    points = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
                       [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    faces = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
                      [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
                      [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    return points, faces


def cube_triangles(offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(12, 3, 3) outward triangles of the unit cube moved by ``offset``."""
    points = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) + offset
    quads = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
    return points[np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])]


def ascii_stl(path, triangles: np.ndarray):
    lines = ["solid test"]
    for tri in triangles:
        lines += ["  facet normal 0 0 0", "    outer loop"]
        lines += [f"      vertex {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in tri]
        lines += ["    endloop", "  endfacet"]
    path.write_text("\n".join(lines + ["endsolid test", ""]))
    return path


def binary_stl(path, triangles: np.ndarray):
    with open(path, "wb") as f:
        f.write(b"binary STL written by test_stl_off".ljust(80, b" ") + struct.pack("<I", len(triangles)))
        for tri in triangles.astype(np.float32):
            f.write(struct.pack("<12fH", 0.0, 0.0, 0.0, *tri.ravel(), 0))
    return path


def assert_closed_g1(surface):
    report = check_surface(surface)
    assert report.boundary_edges == 0 and report.overshared_edges == 0
    assert report.max_normal_jump < MAX_JUMP, report


def test_the_registry_reads_stl_and_off():
    assert {".stl", ".off"} <= set(MESH_READERS)
    assert MESH_READERS[".stl"].target.startswith("c1surf.io.meshes.formats.")


# -- STL ---------------------------------------------------------------------------------


@pytest.mark.parametrize("write", [ascii_stl, binary_stl])
def test_stl_is_read_as_separate_triangles(tmp_path, write):
    points, faces = icosahedron()
    mesh = read_mesh(write(tmp_path / "ico.stl", points[faces]))
    assert mesh.n_vertices == 60 and mesh.n_faces == 20 and np.all(mesh.face_sizes == 3)
    assert np.array_equal(mesh.face_vertices, np.arange(60))  # trimesh merged nothing
    np.testing.assert_allclose(mesh.points.reshape(20, 3, 3), points[faces], atol=1e-6)  # binary STL is float32
    if write is ascii_stl:
        assert np.array_equal(mesh.face_lines, 2 + 7 * np.arange(20))  # the `facet` lines
        assert np.array_equal(mesh.points.reshape(20, 3, 3), points[faces])
    else:
        assert mesh.face_lines is None


@pytest.mark.parametrize("write", [ascii_stl, binary_stl])
def test_stl_converts_closed_and_g1_after_welding(tmp_path, write):
    points, faces = icosahedron()
    path = write(tmp_path / "part.stl", points[faces])
    surface, mesh = surface_from_file(path)
    assert mesh.weld.welded_vertices == 48 and np.unique(mesh.face_vertices).size == 12
    assert surface.repairs["components"] == 1 and surface.repairs["boundary_edges"] == 0
    assert_closed_g1(surface)
    out = tmp_path / "out.ply"
    result = run("convert", path, "-o", out, "-r", 4)
    assert result.exit_code == 0, result.output
    notes = [line for line in result.stderr.splitlines() if line.startswith("c1surf: note:")]
    assert notes == ["c1surf: note: welded 48 vertices at the same position into the vertex they coincide with "
                     "(--no-weld keeps them)"]  # and no "ignored 48 vertices used by no face"
    assert trimesh.load(out, force="mesh", process=True).is_watertight
    check = run("check", path)
    assert check.exit_code == 0 and "G1: yes" in check.output and "boundary edges:   0" in check.output


def test_no_weld_keeps_an_stl_as_separate_triangles(tmp_path):
    points, faces = icosahedron()
    path = ascii_stl(tmp_path / "part.stl", points[faces])
    surface, mesh = surface_from_file(path, weld=None)
    assert mesh.weld is None and np.array_equal(mesh.face_vertices, np.arange(60))
    # 20 open triangles, each closed for the construction by its own ghost layer
    assert surface.repairs["components"] == 20 and surface.repairs["boundary_edges"] == 60
    result = run("convert", path, "-o", tmp_path / "out.ply", "-r", 3, "--no-weld")
    assert result.exit_code == 0, result.output
    assert "open mesh: 60 boundary edges" in result.stderr and "welded" not in result.stderr
    assert "boundary edges:   0" not in run("check", path, "--no-weld").output


def test_weld_tolerance_merges_vertices_1e9_apart(tmp_path):
    points, faces = icosahedron()
    corners = points[faces] + np.random.default_rng(7).uniform(-1e-9, 1e-9, (20, 3, 3))
    path = ascii_stl(tmp_path / "jitter.stl", corners)
    exact, exact_mesh = surface_from_file(path)
    assert exact_mesh.weld.welded_vertices == 0 and exact.repairs["boundary_edges"] == 60
    near, near_mesh = surface_from_file(path, weld=1e-6)
    assert near_mesh.weld.welded_vertices == 48 and near.repairs["boundary_edges"] == 0
    assert_closed_g1(near)
    result = run("convert", path, "-o", tmp_path / "out.ply", "-r", 3, "--weld", "1e-6")
    assert result.exit_code == 0, result.output
    assert "welded 48 vertices within 1e-06 of the bounding-box diagonal" in result.stderr


def test_weld_and_no_weld_together_is_a_usage_error(tmp_path):
    points, faces = icosahedron()
    path = ascii_stl(tmp_path / "part.stl", points[faces])
    result = run("convert", path, "-o", tmp_path / "out.ply", "--weld", "0.1", "--no-weld")
    assert result.exit_code == 2 and "contradict" in result.output


@pytest.mark.parametrize("offset, components, split", [((1.0, 1.0, 0.0), 2, 0), ((1.0, 1.0, 1.0), 2, 1)],
                         ids=["edge", "corner"])
def test_stl_cubes_that_touch_stay_two_cubes(tmp_path, offset, components, split):
    path = binary_stl(tmp_path / "two.stl", np.r_[cube_triangles(), cube_triangles(offset)])
    surface, mesh = surface_from_file(path)
    assert mesh.n_faces == 24
    assert surface.repairs["components"] == components and surface.repairs["split_vertices"] == split
    assert surface.repairs["boundary_edges"] == 0
    assert_closed_g1(surface)
    result = run("convert", path, "-o", tmp_path / "out.ply", "-r", 3)
    assert result.exit_code == 0, result.output
    if split:
        assert "split 1 pinched vertices" in result.stderr
    else:
        assert "kept 2 positions as several vertices" in result.stderr


def test_a_malformed_stl_is_one_line(tmp_path):
    path = tmp_path / "bad.stl"
    path.write_text("solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0\n")
    with pytest.raises(MeshInputError) as info:
        read_mesh(path)
    assert str(info.value).startswith(f"{path}: ") and "\n" not in str(info.value)
    path.write_bytes(b"\0" * 80 + struct.pack("<I", 5) + b"\0" * 10)  # claims 5 triangles, holds none
    with pytest.raises(MeshInputError, match="no triangles found|not a valid STL"):
        read_mesh(path)


# -- OFF ---------------------------------------------------------------------------------

PRISM_OFF = """OFF
# a pentagonal prism: two pentagons and five quads
10 7 15
{vertices}
5 0 1 2 3 4      # bottom, seen from below
5 9 8 7 6 5 0.5 0.5 0.5   # top, with a face colour
4 0 5 6 1
4 1 6 7 2
4 2 7 8 3
4 3 8 9 4
4 4 9 5 0
"""


def prism_vertices(extra: str = "") -> str:
    a = 2 * np.pi * np.arange(5) / 5
    rows = [(np.cos(t), -np.sin(t), z) for z in (0.0, 1.0) for t in a]  # clockwise from above: the bottom faces down
    return "\n".join(f"{float(x)!r} {float(y)!r} {float(z)!r}{extra}" for x, y, z in rows)


def test_off_keeps_its_polygons(tmp_path):
    path = tmp_path / "prism.off"
    path.write_text(PRISM_OFF.format(vertices=prism_vertices()))
    mesh = read_mesh(path)
    assert mesh.face_sizes.tolist() == [5, 5, 4, 4, 4, 4, 4] and mesh.n_vertices == 10
    assert mesh.face_lines.tolist() == [14, 15, 16, 17, 18, 19, 20]
    assert mesh.face_vertices[:10].tolist() == [0, 1, 2, 3, 4, 9, 8, 7, 6, 5]
    surface, welded = surface_from_file(path)
    assert welded.weld.welded_vertices == 0 and surface.repairs["flipped_faces"] == 0
    assert_closed_g1(surface)
    result = run("convert", path, "-o", tmp_path / "out.obj", "-r", 3)
    assert result.exit_code == 0, result.output


@pytest.mark.parametrize("header, extra", [("COFF", " 255 0 0 255"), ("NOFF", " 0 0 1"), ("CNOFF", " 0 0 1 1 1 1")])
def test_coff_and_noff_values_after_xyz_are_ignored(header, extra):
    plain = parse_off(PRISM_OFF.format(vertices=prism_vertices()).encode())
    other = parse_off(PRISM_OFF.replace("OFF\n", f"{header}\n", 1).format(vertices=prism_vertices(extra)).encode())
    assert np.array_equal(other.points, plain.points) and np.array_equal(other.face_vertices, plain.face_vertices)


def test_off_counts_may_follow_the_keyword():
    text = PRISM_OFF.replace("OFF\n# a pentagonal prism: two pentagons and five quads\n10 7 15\n", "OFF 10 7 15\n")
    mesh = parse_off(text.format(vertices=prism_vertices()).encode())
    assert mesh.face_sizes.tolist() == [5, 5, 4, 4, 4, 4, 4] and mesh.face_lines[0] == 12


def off_error(text: str):
    with pytest.raises(MeshInputError) as info:
        parse_off(text.encode(), "m.off")
    assert "\n" not in str(info.value)
    return info.value


@pytest.mark.parametrize("text, line, fragment", [
    ("PLY\n3 1 0\n", 1, "expected the header `OFF`"),
    ("OFF\n3 x 0\n", 2, "expected the counts"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n", 4, "truncated"),
    ("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", 4, "vertex has 2 numbers"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0 1\n0 1 0\n3 0 1 2\n", 4, "vertex has 4 numbers"),
    ("OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n", 4, "not a number"),
    ("OFF\n# c\n3 1 0\n0 0 0\n1 0 0\n\n0 1 0\n3 0 1 3\n", 8, "refers to vertex 3"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", 6, "announces 4 vertices but lists 3"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", 6, "at least 3 vertices"),
    ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 a\n", 6, "not a whole number"),
    ("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n4 0 1 0 3\n", 7, "visits vertex 0 twice"),
    ("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", 2, "has no faces"),
])
def test_a_malformed_off_names_its_line(text, line, fragment):
    err = off_error(text)
    assert err.line == line and fragment in err.message, str(err)
    assert str(err).startswith(f"m.off:{line}: ")


# -- seams -------------------------------------------------------------------------------

CUBE_OBJ = """v -1 -1 -1
v -1 -1 1
v -1 1 -1
v -1 1 1
v 1 -1 -1
v 1 -1 1
v 1 1 -1
v 1 1 1
"""
CUBE_FACES = ["1 2 4 3", "5 7 8 6", "1 5 6 2", "3 4 8 7", "1 3 7 5", "2 6 8 4"]


def seam_split_cube(uv: bool) -> str:
    """The cube with its top face (z = 1) cut off along the loop of its four edges: vertices 9..12 copy 2, 6, 8, 4."""
    text = CUBE_OBJ + "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
    faces = CUBE_FACES[:5] + ["9 10 11 12"]
    if not uv:
        return text + "".join(f"f {f}\n" for f in faces)
    text += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"  # the top face's own texture coordinates (1..4) and the sides' (5)
    corners = [" ".join(f"{v}/5" for v in f.split()) for f in faces[:5]] + ["9/1 10/2 11/3 12/4"]
    return text + "".join(f"f {f}\n" for f in corners)


def test_a_seam_split_obj_converts_to_the_unsplit_surface(tmp_path):
    whole = tmp_path / "cube.obj"
    whole.write_text(CUBE_OBJ + "".join(f"f {f}\n" for f in CUBE_FACES))
    split = tmp_path / "split.obj"
    split.write_text(seam_split_cube(uv=False))
    reference, _ = surface_from_file(whole)
    welded, mesh = surface_from_file(split)
    assert mesh.weld.welded_vertices == 4 and mesh.n_faces == 6
    np.testing.assert_allclose(welded.biquadratic, reference.biquadratic, rtol=0, atol=1e-12)
    np.testing.assert_allclose(welded.bicubic, reference.bicubic, rtol=0, atol=1e-12)
    assert_closed_g1(welded)
    apart, _ = surface_from_file(split, weld=None)
    assert apart.repairs["boundary_edges"] == 8 and apart.repairs["components"] == 2
    result = run("convert", split, "-o", tmp_path / "out.ply", "-r", 3)
    assert result.exit_code == 0, result.output
    assert "welded 4 vertices at the same position" in result.stderr and "used by no face" not in result.stderr


def test_texture_seams_weld_unless_the_uvs_are_carried(tmp_path):
    split = tmp_path / "split.obj"
    split.write_text(seam_split_cube(uv=True))
    geometry, mesh = surface_from_file(split)
    assert mesh.weld.welded_vertices == 4 and geometry.repairs["boundary_edges"] == 0
    # with --attributes the texture coordinates differ across the seam: its two sides stay apart, each with its own
    carried, mesh = surface_from_file(split, attributes=True)
    assert mesh.weld.welded_vertices == 0
    assert carried.repairs["boundary_edges"] == 8 and carried.repairs["components"] == 2


# -- never a crash -----------------------------------------------------------------------

OFF_LINES = st.one_of(
    st.sampled_from(["OFF", "COFF", "NOFF", "OFF 4 2 0", "4 2 0", "3 1", "# c", "", "OFF x"]),
    st.builds(lambda *c: " ".join(c), *[st.sampled_from(["0", "1", "-2.5", "1e3", "nan", "x", ""])] * 4),
    st.builds(lambda *i: " ".join(i), *[st.sampled_from(["3", "4", "0", "1", "2", "3", "9", "-1", "a", ""])] * 5),
)


def convert_never_crashes(tmp_path, data: bytes, suffix: str):
    path, out = tmp_path / f"in{suffix}", tmp_path / "out.ply"
    path.write_bytes(data)
    out.unlink(missing_ok=True)
    result = CliRunner().invoke(main, ["convert", str(path), "-o", str(out), "-r", "2", "-q"])
    assert result.exit_code in (0, 1), result.output
    if result.exit_code == 1:
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("c1surf: error: ")
    assert out.exists() == (result.exit_code == 0)


@FUZZ
@given(st.lists(OFF_LINES, max_size=20))
def test_random_off_text_never_crashes(tmp_path, lines):
    convert_never_crashes(tmp_path, "\n".join(lines).encode(), ".off")


@FUZZ
@given(st.binary(max_size=300), st.sampled_from([".off", ".stl"]))
def test_arbitrary_bytes_never_crash(tmp_path, data, suffix):
    convert_never_crashes(tmp_path, data, suffix)


@FUZZ
@given(st.lists(st.sampled_from([0.0, 1.0, 1.0 + 1e-12, -1.0]), min_size=9, max_size=9), st.integers(1, 12))
def test_random_binary_stl_soups_never_crash(tmp_path, corners, copies):
    triangles = np.resize(np.asarray(corners), (copies, 3, 3)) + np.arange(copies)[:, None, None] % 2
    convert_never_crashes(tmp_path, binary_stl(tmp_path / "soup.bin", triangles).read_bytes(), ".stl")


def test_batch_finds_stl_and_off_inputs_and_passes_the_weld_options_on(tmp_path):
    from c1surf.cli.batch import batch, expand_inputs, given_arguments

    for name in ("a.stl", "b.OFF", "c.obj", "d.glb"):
        (tmp_path / name).write_text("x")
    assert [p.name for p in expand_inputs([str(tmp_path / "*")])] == ["a.stl", "b.OFF", "c.obj"]

    def passed_on(*options):
        context = batch.make_context("batch", [str(tmp_path / "*"), "-o", str(tmp_path / "out"), *options])
        return given_arguments(context, exclude=("out_dir",))

    assert passed_on("--no-weld") == ["--no-weld"] and passed_on() == []
    assert passed_on("--weld", "1e-6") == ["--weld", "1e-06"]
