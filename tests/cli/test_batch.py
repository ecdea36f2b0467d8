"""`c1surf batch`: many inputs, skipping up-to-date outputs, failures summarized, shards."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _batch(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "c1surf.cli.main", "batch", *args], capture_output=True, text=True,
                          timeout=300, cwd=cwd)


def _inputs(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    for name in ("cube", "tetrahedron"):
        shutil.copy(ROOT / "sample_meshes" / f"{name}.obj", src / f"{name}.obj")
    (src / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
    (src / "notes.txt").write_text("not a mesh\n")
    return src


def test_batch_converts_skips_and_reports(tmp_path):
    src, out = _inputs(tmp_path), tmp_path / "out"
    r = _batch(str(src / "*.obj"), "-o", str(out), "-j", "2", "-r", "3", "--patches", ".npz")
    assert r.returncode == 1, r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["cube.npz", "cube.ply", "tetrahedron.npz", "tetrahedron.ply"]
    assert "2 converted, 0 up to date, 1 failed (of 3 inputs)" in r.stderr
    failure = [line for line in r.stderr.splitlines() if "broken.obj" in line]
    assert len(failure) == 1 and "vertex 4" in failure[0]
    assert not any(p.name.startswith(".tmp-c1surf-") for p in out.iterdir())

    # a second run skips what is newer than its input
    r = _batch(str(src / "*.obj"), "-o", str(out), "-r", "3", "--patches", ".npz")
    assert "0 converted, 2 up to date, 1 failed" in r.stderr
    # touching an input makes it convert again
    later = (out / "cube.ply").stat().st_mtime + 10
    os.utime(src / "cube.obj", (later, later))
    r = _batch(str(src / "*.obj"), "-o", str(out), "-r", "3", "--patches", ".npz")
    assert "1 converted, 1 up to date, 1 failed" in r.stderr


def test_batch_shards_and_formats(tmp_path):
    src, out = _inputs(tmp_path), tmp_path / "out"
    (src / "broken.obj").unlink()
    names = set()
    for shard in ("0/2", "1/2"):
        r = _batch(str(src / "*.obj"), "-o", str(out), "--shard", shard, "-f", ".obj", "--float32", "-r", "2")
        assert r.returncode == 0, r.stderr
        names |= {p.name for p in out.iterdir()}
    assert names == {"cube.obj", "tetrahedron.obj"}
    assert (out / "cube.obj").read_text().startswith("# c1surf\nv ")


def test_batch_usage_errors(tmp_path):
    r = _batch(str(tmp_path / "*.obj"), "-o", str(tmp_path / "out"))
    assert r.returncode == 2 and "no mesh file (.obj, .off, .ply, .stl, .usd, .usda, .usdc, .usdz) matches" in r.stderr
    src = _inputs(tmp_path)
    r = _batch(str(src / "*.obj"), "-o", str(tmp_path / "out"), "--shard", "2/2")
    assert r.returncode == 2 and "--shard" in r.stderr
