"""Foreign code in a child process (io.contained, issue 42): a crash, a signal or a hang there is one line about
the file, and the next read starts a fresh child."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from c1surf.io.contained import ContainedCrash, ContainedModule
from c1surf.io.errors import MeshInputError

SAMPLES = Path(__file__).resolve().parents[2] / "sample_meshes"


def test_a_crash_is_one_line_and_the_next_call_works():
    contained = ContainedModule("faulthandler", "the reader")
    try:
        with pytest.raises(ContainedCrash, match=r"^x\.step: the reader crashed reading the file \(signal SIGSEGV\)"):
            contained.call("_sigsegv", [], path="x.step", limit=60)
        with pytest.raises(ContainedCrash, match="signal SIGSEGV"):  # a fresh child, crashed again
            contained.call("_sigsegv", [], path="x.step", limit=60)
    finally:
        contained.close()


def test_a_hang_is_stopped_at_its_limit():
    contained = ContainedModule("os", "the reader")
    try:
        with pytest.raises(ContainedCrash, match=r"took more than 1 s reading the file and was stopped"):
            contained.call("system", ["sleep 30"], path="x.step", limit=1.0)
        assert contained._child is None  # killed and forgotten
    finally:
        contained.close()


def test_a_refusal_in_the_child_is_the_parents_line_and_arrays_come_back(tmp_path):
    pytest.importorskip("OCP")
    from click.testing import CliRunner

    from c1surf.cli.main import main
    from c1surf.io.patches.brep.step_faces import face_nets

    shutil.copy(SAMPLES / "cube.obj", tmp_path / "cube.obj")
    result = CliRunner().invoke(main, ["convert", str(tmp_path / "cube.obj"), "-o", str(tmp_path / "cube.ply"),
                                       "--patches", str(tmp_path / "cube.step"), "-q"])
    assert result.exit_code == 0, result.output
    contained = ContainedModule("c1surf.io.patches.brep.step_faces", "Open CASCADE")
    try:
        header, arrays = contained.call("face_arrays", [str(tmp_path / "cube.step")], path="cube.step", limit=120)
        faces = face_nets(tmp_path / "cube.step")  # the same reading in this process
        assert header["faces"] == len(faces) == arrays[0].shape[0]
        assert np.array_equal(arrays[3], np.concatenate([f[3].reshape(-1, 3) for f in faces]))
        (tmp_path / "bad.step").write_text("ISO-10303-21;\nnot a STEP file\n")
        with pytest.raises(MeshInputError, match=r"bad\.step: not a STEP file Open CASCADE can read"):
            contained.call("face_arrays", [str(tmp_path / "bad.step")], path=tmp_path / "bad.step", limit=120)
    finally:
        contained.close()


class _Interrupted(BaseException):
    pass


def test_an_interrupted_call_leaves_no_stale_answer():
    """Ctrl-C (or a caller's alarm) mid-call kills the child: the next call gets its own answer, not the old one."""
    import signal

    def interrupt(signum, frame):
        raise _Interrupted

    contained = ContainedModule("os", "the reader")
    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        with pytest.raises(_Interrupted):
            contained.call("system", ["sleep 2"], path="x", limit=60)  # answers an int: "cannot unpack"
        signal.setitimer(signal.ITIMER_REAL, 0)
        with pytest.raises(MeshInputError, match=r"ValueError: too many values to unpack"):
            contained.call("getcwd", [], path="x", limit=60)  # a path string: its own answer
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        contained.close()


def test_step_numbers_beyond_the_range_are_one_line(tmp_path):
    """A real of 1e50 or more is refused before Open CASCADE sees it (a pole at 1e100 kept it busy past a minute),
    naming its line; 1e49 is not."""
    pytest.importorskip("OCP")
    import re

    from c1surf.io.patches.step import read_patch_set_step
    from c1surf.io.patches.brep.step_faces import refuse_huge_reals

    shutil.copy(SAMPLES / "tetrahedron.obj", tmp_path / "t.obj")
    from click.testing import CliRunner

    from c1surf.cli.main import main

    result = CliRunner().invoke(main, ["convert", str(tmp_path / "t.obj"), "-o", str(tmp_path / "t.ply"),
                                       "--patches", str(tmp_path / "t.step"), "-q"])
    assert result.exit_code == 0, result.output
    text = (tmp_path / "t.step").read_text()
    pole = re.search(r"B_SPLINE_SURFACE[^#]*#(\d+)", text).group(1)  # the first pole of the first surface
    point = re.search(rf"#{pole} = CARTESIAN_POINT\('',\(([-0-9.E+]+),", text)
    line = text[:point.start(1)].count("\n") + 1
    (tmp_path / "t2.step").write_text(text[:point.start(1)] + "1.E+100" + text[point.end(1):])
    with pytest.raises(MeshInputError, match=rf"t2\.step:{line}: the number 1\.E\+100 is beyond 1e50"):
        read_patch_set_step(tmp_path / "t2.step")
    (tmp_path / "t3.step").write_text(text[:point.start(1)] + "1.E+49" + text[point.end(1):])
    refuse_huge_reals(tmp_path / "t3.step")  # within the range: read as any other number
