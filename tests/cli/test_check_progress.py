"""``check`` and ``measure`` show phases and bars on a terminal only (as ``convert``), take ``-q``, and print
notes on lines of their own; streamed from a mesh, they report what the whole surface gives."""
from __future__ import annotations

import re

from click.testing import CliRunner

from c1surf.cli.main import main
from conftest import SAMPLES
from test_progress import on_terminal, piped


def _lines(shown: str) -> list[str]:
    """The terminal's lines as finally drawn (a bar redrawn in place: its last state)."""
    return [line.rstrip("\r").split("\r")[-1] for line in shown.replace("\x1b[?25l", "").replace("\x1b[?25h", "").split("\n")]


def test_check_and_measure_show_progress_on_a_terminal_only(tmp_path):
    patches = tmp_path / "t.npz"
    assert CliRunner().invoke(main, ["convert", str(SAMPLES / "torus.obj"), "-o", str(tmp_path / "t.ply"),
                                     "--patches", str(patches)]).exit_code == 0
    for source in (patches, SAMPLES / "torus.obj"):
        shown = on_terminal("check", source)
        assert re.search(rf"c1surf: reading {re.escape(str(source))}\.\.\. \d+\.\d\ds", shown)
        for bar in ("finding the shared edges", "matching the patch sides", "measuring the shared edges"):
            assert re.search(rf"c1surf: {bar} \[#{{30}}\] 100% \d+\.\d\ds", shown), bar
        measured = on_terminal("measure", source)
        for bar in ("measuring the area", "measuring the volume"):
            assert re.search(rf"c1surf: {bar} \[#{{30}}\] 100% \d+\.\d\ds", measured), bar
        for command in ("check", "measure"):
            assert piped(command, source) == ""
            assert on_terminal(command, source, "-q") == ""


def test_notes_never_break_a_progress_line(tmp_path):
    # a vertex given twice: welded, with a note, while the surface is built
    mesh = tmp_path / "tet.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 0 0\nf 1 3 2\nf 1 2 4\nf 5 4 3\nf 2 3 4\n")
    for command in ("check", "measure"):
        lines = _lines(on_terminal(command, mesh))
        notes = [line for line in lines if "c1surf: note:" in line]
        assert len(notes) == 1 and notes[0].startswith("c1surf: note: welded 1 vertices"), lines
        assert re.fullmatch(r"c1surf: building the surface of 4 faces\.\.\. \d+\.\d\ds", lines[lines.index(notes[0]) - 1])


def test_check_and_measure_of_a_mesh_equal_those_of_its_patch_file(tmp_path):
    # the mesh input is streamed (its patches made by blocks when read); the NPZ is read as written
    for name in ("twisted", "high_valence"):
        npz = tmp_path / f"{name}.npz"
        run = lambda *a: CliRunner().invoke(main, [str(x) for x in a])
        assert run("convert", SAMPLES / f"{name}.obj", "-o", tmp_path / "x.ply", "--patches", npz).exit_code == 0
        for command in ("check", "measure"):
            from_mesh, from_file = run(command, SAMPLES / f"{name}.obj"), run(command, npz)
            assert from_mesh.exit_code == from_file.exit_code == 0
            assert from_mesh.stdout == from_file.stdout


def test_diff_shows_its_phases_on_a_terminal_only(tmp_path):
    patches = tmp_path / "t.json"
    assert CliRunner().invoke(main, ["convert", str(SAMPLES / "cube.obj"), "-o", str(tmp_path / "t.ply"),
                                     "--patches", str(patches)]).exit_code == 0
    shown = on_terminal("diff", patches, patches)
    for phase in (f"reading {re.escape(str(patches))}", "comparing"):
        assert re.search(rf"c1surf: {phase}\.\.\. \d+\.\d\ds", shown), phase
    assert piped("diff", patches, patches) == "" and on_terminal("diff", patches, patches, "-q") == ""
