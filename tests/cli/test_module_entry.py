"""``python -m c1surf`` runs the command line as the ``c1surf`` console script does (``c1surf/__main__.py``)."""
from __future__ import annotations

import os
import subprocess
import sys

from conftest import ROOT, SAMPLES


def module(*args, cwd):
    """``python -m c1surf ARGS`` in a fresh process, this checkout first on the path: (status, stdout, stderr)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run([sys.executable, "-m", "c1surf", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, env=env, timeout=120)
    return proc.returncode, proc.stdout, proc.stderr


def test_help_lists_the_commands(tmp_path):
    status, out, err = module("--help", cwd=tmp_path)
    assert status == 0 and err == ""
    assert out.startswith("Usage: c1surf [OPTIONS] COMMAND [ARGS]...")
    for command in ("convert", "check", "measure", "diff", "tessellate", "fit"):
        assert f"\n  {command} " in out


def test_convert_writes_what_the_console_script_writes(tmp_path):
    """The same command through ``-m c1surf`` and through ``c1surf.cli.main``: the same bytes; a bad option is one
    ``c1surf: error:`` line with status 2, as from the console script."""
    status, _, err = module("convert", SAMPLES / "cube.obj", "-o", tmp_path / "a.ply", "-r", "2", "-q", cwd=tmp_path)
    assert status == 0, err
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    subprocess.run([sys.executable, "-m", "c1surf.cli.main", "convert", str(SAMPLES / "cube.obj"), "-o",
                    str(tmp_path / "b.ply"), "-r", "2", "-q"], check=True, cwd=tmp_path, env=env, timeout=120)
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()
    status, out, err = module("convert", SAMPLES / "cube.obj", "-o", tmp_path / "c.ply", "-r", "0", cwd=tmp_path)
    assert status == 2 and out == "" and len(err.strip().splitlines()) == 1 and err.startswith("c1surf: error:"), err
