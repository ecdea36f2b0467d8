"""Progress (click's bars) only on a terminal: shown when stderr is a tty, silent when piped or with --quiet."""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

import pytest

from conftest import SAMPLES

pty = pytest.importorskip("pty")  # POSIX pseudo-terminals


def c1surf(*args) -> list[str]:
    return [sys.executable, "-m", "c1surf.cli.main", *map(str, args)]


def on_terminal(*args) -> str:
    """Run c1surf with stderr on a pseudo-terminal; return what the terminal showed."""
    controller, terminal = pty.openpty()
    proc = subprocess.Popen(c1surf(*args), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=terminal)
    os.close(terminal)
    shown = []
    while True:
        try:
            chunk = os.read(controller, 65536)
        except OSError:  # EIO: every writer of the terminal has ended
            break
        if not chunk:
            break
        shown.append(chunk)
    os.close(controller)
    assert proc.wait(timeout=300) == 0
    return b"".join(shown).decode()


def piped(*args) -> str:
    """Run c1surf with stderr to a pipe; return its stderr."""
    proc = subprocess.run(c1surf(*args), stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return proc.stderr


def test_convert_shows_phases_and_bars_on_a_terminal_only(tmp_path):
    args = ("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "t.ply", "--curvature", "-r", 6,
            "--patches", tmp_path / "t.json")
    shown = on_terminal(*args)
    for phase in (f"reading {SAMPLES / 'twisted.obj'}", "building the surface of 18 faces",
                  "tessellating 320 patches at 6 x 6", f"writing {tmp_path / 't.ply'}", f"writing {tmp_path / 't.json'}"):
        assert re.search(rf"c1surf: {re.escape(phase)}\.\.\. \d+\.\d\ds", shown), phase
    assert re.search(r"c1surf: evaluating curvature \[#{30}\] 100% \d+\.\d\ds", shown)
    assert "(total " in shown
    assert piped(*args) == ""
    assert on_terminal(*args, "--quiet") == ""


def test_batch_shows_one_bar_on_a_terminal_only(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    for name in ("cube", "tetrahedron"):
        shutil.copy(SAMPLES / f"{name}.obj", src / f"{name}.obj")
    args = ("batch", src / "*.obj", "-r", 2, "-j", 2, "--rebuild", "-o")
    shown = on_terminal(*args, tmp_path / "a")
    assert re.search(r"\[#{30}\] 2/2 .*0 failed  0 running", shown)
    assert "c1surf batch: 2 converted, 0 up to date, 0 failed (of 2 inputs)" in shown
    summary = piped(*args, tmp_path / "b").splitlines()
    assert len(summary) == 1 and summary[0].startswith("c1surf batch: 2 converted, 0 up to date, 0 failed (of 2 inputs)")
    quiet = on_terminal(*args, tmp_path / "c", "-q").splitlines()
    assert len(quiet) == 1 and quiet[0].startswith("c1surf batch: 2 converted, 0 up to date, 0 failed (of 2 inputs)")
