"""Sharp-feature tags: every command that builds a surface says once what it honours and what it does not."""
from __future__ import annotations

import pytest
from click.testing import CliRunner

from c1surf.cli.main import main

CUBE = "".join(f"v {x} {y} {z}\n" for x, y, z in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                                                  (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]) + """f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
"""
TAGS = "t crease 5/1/0 0 1 2 3 0 10\nt corner 1/1/0 6 2\nt hole 1/0/0 1\nt interpolateboundary 1/0/0 1\n" \
       "t creasemethod 0/0/1 chaikin\n"
NOTE = ("sharp-feature tags honoured: crease (4 edges), corner (1 vertex), hole (1 face); not honoured: "
        "interpolateboundary 1 (c1surf's boundary rule, a ghost layer, always ends the surface on a curve along the "
        "boundary polygon); creasemethod (1 tag: c1surf's own crease rule is used (stencils.creases))")
SHARP = "C0 creases: 4 of 4 infinitely sharp crease edges are C0 seams"  # the default (--exact-creases)
G1_SHARP = ("infinitely sharp creases (sharpness >= 10) are built as the sharpest G1 crease (sharpness 10: a narrow G1 "
            "fillet), not as a C0 edge (--g1-creases, or vertex interpolation, which C0 seams do not take yet)")
IGNORED = ("sharp-feature tags ignored (--ignore-tags), the surface is smooth: crease (4 edges), corner (1 vertex), "
           "hole (1 face), interpolateboundary 1, creasemethod (1 tag)")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture
def tagged(tmp_path):
    path = tmp_path / "tagged.obj"
    path.write_text(CUBE + TAGS)
    return path


def notes(result) -> list[str]:
    return [line for line in result.stderr.splitlines() if "sharp" in line]


def expected(path) -> list[str]:
    return [f"c1surf: note: {path}: {NOTE}", f"c1surf: note: {SHARP}"]


def test_convert_notes_the_tags_once(tmp_path, tagged):
    result = run("convert", tagged, "-o", tmp_path / "out.obj", "-r", 2)
    assert result.exit_code == 0, result.output
    assert notes(result) == expected(tagged)
    assert "sharp-feature" not in result.stdout


def test_g1_creases_say_so(tmp_path, tagged):
    result = run("convert", tagged, "-o", tmp_path / "out.obj", "-r", 2, "--g1-creases")
    assert result.exit_code == 0, result.output
    assert notes(result) == [f"c1surf: note: {tagged}: {NOTE}", f"c1surf: note: {G1_SHARP}"]


def test_convert_is_silent_with_quiet_and_honours_the_tags(tmp_path, tagged):
    plain = tmp_path / "plain.obj"
    plain.write_text(CUBE)
    result = run("convert", tagged, "-o", tmp_path / "tagged_out.obj", "-r", 2, "-q")
    assert result.exit_code == 0 and result.stderr == ""
    assert run("convert", plain, "-o", tmp_path / "plain_out.obj", "-r", 2, "-q").stderr == ""
    assert (tmp_path / "tagged_out.obj").read_bytes() != (tmp_path / "plain_out.obj").read_bytes()


def test_ignore_tags_builds_the_smooth_surface_and_says_so(tmp_path, tagged):
    plain = tmp_path / "plain.obj"
    plain.write_text(CUBE)
    result = run("convert", tagged, "-o", tmp_path / "ignored.obj", "-r", 2, "--ignore-tags")
    assert result.exit_code == 0, result.output
    assert notes(result) == [f"c1surf: note: {tagged}: {IGNORED}"]
    run("convert", plain, "-o", tmp_path / "plain_out.obj", "-r", 2, "-q")
    assert (tmp_path / "ignored.obj").read_bytes() == (tmp_path / "plain_out.obj").read_bytes()


def test_an_untagged_mesh_gets_no_note(tmp_path):
    plain = tmp_path / "plain.obj"
    plain.write_text(CUBE)
    assert notes(run("convert", plain, "-o", tmp_path / "out.obj", "-r", 2)) == []


def test_check_notes_the_tags_on_stderr(tagged):
    result = run("check", tagged)
    assert result.exit_code == 0 and "G1: yes" in result.stdout
    assert notes(result) == expected(tagged)


def test_a_bad_tag_is_a_one_line_error(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text(CUBE + "t crease 2/1/0 0 6 1.0\n")
    result = run("convert", path, "-o", tmp_path / "out.obj")
    assert result.exit_code == 1
    assert result.stderr.strip() == (f"c1surf: error: {path}:15: crease pair 0 6 is not an edge of the mesh (no face "
                                     "has these two vertices next to each other; tags count vertices from 0): fix the tag")


def test_render_notes_the_tags_unless_quiet(tmp_path, tagged):
    result = run("render", tagged, "-o", tmp_path / "a.exr", "--size", 16)
    assert result.exit_code == 0, result.output
    assert notes(result) == expected(tagged)
    assert notes(run("render", tagged, "-o", tmp_path / "b.exr", "--size", 16, "-q")) == []


def test_a_creases_sidecar_does_what_the_same_tags_do(tmp_path):
    plain = tmp_path / "plain.obj"
    plain.write_text(CUBE)
    tagged = tmp_path / "tagged.obj"
    tagged.write_text(CUBE + "t crease 5/1/0 0 1 2 3 0 2.5\nt corner 1/1/0 6 10\nt hole 1/0/0 1\n")
    sidecar = tmp_path / "creases.json"
    sidecar.write_text('{"creases": [[0, 1, 2, 3, 0, 2.5]], "corners": [[6, 10]], "holes": [1]}')
    assert run("convert", tagged, "-o", tmp_path / "a.obj", "-r", 2, "-q").exit_code == 0
    assert run("convert", plain, "-o", tmp_path / "b.obj", "-r", 2, "-q", "--creases", sidecar).exit_code == 0
    assert (tmp_path / "a.obj").read_bytes() == (tmp_path / "b.obj").read_bytes()


@pytest.mark.parametrize("text,message", [
    ('{"creases": [[0, 1]]}', "creases[0]: expected [vertex, vertex, ..., sharpness]"),
    ('{"creases": [[0, 6, 1.0]]}', "crease pair 0 6 is not an edge of the mesh"),
    ('{"corners": [[9, 1.0]]}', "corner names vertex 9 but the file has 8 vertices"),
    ('{"holes": [6]}', "hole names face 6 but the file has 6 faces"),
    ('{"edges": []}', 'expected a JSON object with the keys "creases", "corners" and "holes" only'),
    ('{"creases": ', "not a JSON file"),
])
def test_a_bad_creases_sidecar_is_a_one_line_error(tmp_path, text, message):
    plain = tmp_path / "plain.obj"
    plain.write_text(CUBE)
    sidecar = tmp_path / "creases.json"
    sidecar.write_text(text)
    result = run("convert", plain, "-o", tmp_path / "out.obj", "--creases", sidecar)
    assert result.exit_code == 1 and not (tmp_path / "out.obj").exists()
    [line] = result.stderr.strip().splitlines()
    assert line.startswith(f"c1surf: error: {sidecar}") and message in line


def test_crease_angle_makes_the_cube_edges_creases(tmp_path):
    plain = tmp_path / "plain.obj"
    plain.write_text(CUBE)
    result = run("convert", plain, "-o", tmp_path / "sharp.obj", "-r", 2, "--crease-angle", 40)
    assert result.exit_code == 0, result.output
    assert "--crease-angle 40: 12 edges with a dihedral angle above it are creases" in result.stderr
    run("convert", plain, "-o", tmp_path / "smooth.obj", "-r", 2, "-q")
    assert (tmp_path / "sharp.obj").read_bytes() != (tmp_path / "smooth.obj").read_bytes()
    assert "G1: yes" in run("check", plain, "--crease-angle", 40).stdout
