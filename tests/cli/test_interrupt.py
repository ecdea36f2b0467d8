"""A conversion stopped midway leaves no partial output, and earlier outputs stay intact."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
import trimesh
from click.testing import CliRunner

from c1surf.cli.main import main

from conftest import SAMPLES, shared_mesh


def temp_files(directory):
    return [p for p in directory.iterdir() if p.name.startswith(".tmp-c1surf")]


def _interruptible():
    """In the child: SIGINT at its default, as from a terminal. A test run started in the
    background (``cmd &``, some CI runners) hands its children SIGINT ignored, and Python keeps
    an ignored SIGINT ignored: Ctrl-C would not reach the conversion at all."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def convert_until_writing(mesh, out):
    """Start a conversion and return it once its temporary output exists (it is writing)."""
    resolution = "8" if out.suffix == ".obj" else "12"
    proc = subprocess.Popen([sys.executable, "-m", "c1surf.cli.main", "convert", str(mesh), "-o", str(out), "-r", resolution, "-q"],
                            stderr=subprocess.PIPE, text=True, preexec_fn=_interruptible)
    deadline = time.time() + 120
    while not temp_files(out.parent) and proc.poll() is None and time.time() < deadline:
        time.sleep(0.002)
    return proc


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_while_writing_leaves_nothing_partial(tmp_path, sig):
    mesh = shared_mesh("spot/spot_quadrangulated.obj")
    # a text OBJ of 2.3 M vertices takes seconds to write: the signal lands while it is written
    # (a binary PLY is written so fast now that the signal often came after the rename)
    out = tmp_path / "spot.obj"
    # On a loaded machine the write can finish between seeing the temporary
    # file and the signal; then try again (the property is about interruptions).
    for attempt in range(5):
        out.write_bytes(b"earlier output")
        proc = convert_until_writing(mesh, out)
        if proc.poll() is None:
            proc.send_signal(sig)  # the temporary output is being written right now
        _, stderr = proc.communicate(timeout=120)
        if proc.returncode == 0:
            continue
        assert proc.returncode == 1
        assert stderr.strip().splitlines() == ["c1surf: error: interrupted; no partial output was left behind"]
        assert temp_files(tmp_path) == []
        if out.read_bytes() != b"earlier output":
            # the signal landed after the atomic rename: the new output is then complete
            assert len(trimesh.load(out, force="mesh", process=False).faces) > 0
            continue
        return
    pytest.fail("the conversion always finished before it could be interrupted")


def test_sigkill_never_damages_the_target(tmp_path):
    """SIGKILL cannot be caught: a hidden temporary file may remain, the named output never half-written."""
    mesh = shared_mesh("spot/spot_quadrangulated.obj")
    out = tmp_path / "spot.ply"
    out.write_bytes(b"earlier output")
    proc = subprocess.Popen([sys.executable, "-m", "c1surf.cli.main", "convert", str(mesh), "-o", str(out), "-r", "12", "-q"])
    deadline = time.time() + 120
    while not temp_files(tmp_path) and proc.poll() is None and time.time() < deadline:
        time.sleep(0.002)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=60)
    assert out.read_bytes() == b"earlier output"


@pytest.mark.parametrize("stream, writer", [("0", "write_triangle_mesh"), ("1", "write_streamed_mesh"),
                                            ("1", "write_patch_stream")])
def test_write_failure_leaves_no_output(tmp_path, monkeypatch, stream, writer):
    """In memory, and streamed (the mesh, or the patch file after the mesh was written)."""
    import c1surf.cli.convert as convert_module

    def failing_writer(path, *args, **kwargs):
        with open(path, "wb") as f:
            f.write(b"half a mesh")
        raise OSError(28, "No space left on device")

    monkeypatch.setenv("C1SURF_STREAM", stream)
    monkeypatch.setattr(convert_module, writer, failing_writer)
    out = tmp_path / "cube.ply"
    patches = tmp_path / "cube.json"
    result = CliRunner().invoke(main, ["convert", str(SAMPLES / "cube.obj"), "-o", str(out), "--patches", str(patches)])
    assert result.exit_code == 1
    assert "No space left on device" in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not out.exists() and not patches.exists() and temp_files(tmp_path) == []


def processes_naming(text: str) -> list[int]:
    """Ids of the live processes whose command line contains ``text`` (Linux /proc)."""
    found = []
    for entry in os.listdir("/proc"):
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                if entry.isdigit() and text.encode() in f.read():
                    found.append(int(entry))
        except OSError:  # not a process, or it ended meanwhile
            pass
    return found


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="lists processes through /proc")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_interrupted_batch_ends_its_children_and_leaves_nothing_partial(tmp_path, sig):
    """The signal reaches the batch alone (a scheduler's SIGTERM): it must end the conversions it started."""
    mesh = shared_mesh("spot/spot_quadrangulated.obj")
    src, out = tmp_path / "in", tmp_path / "out"
    src.mkdir()
    for name in "abcd":
        os.symlink(mesh, src / f"{name}.obj")
    proc = subprocess.Popen([sys.executable, "-m", "c1surf.cli.main", "batch", str(src / "*.obj"), "-o", str(out), "-j", "2",
                             "-f", ".obj", "-r", "8"], stderr=subprocess.PIPE, text=True, preexec_fn=_interruptible)
    deadline = time.time() + 180
    while not (out.is_dir() and temp_files(out)) and proc.poll() is None and time.time() < deadline:
        time.sleep(0.002)
    conversions = f"{out}{os.sep}"  # in the children's command lines (-o OUTDIR/a.obj), not in the batch's
    assert processes_naming(conversions), "no conversion was running"
    proc.send_signal(sig)
    _, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 1
    assert stderr.strip().splitlines() == ["c1surf: error: interrupted; no partial output was left behind"]
    assert temp_files(out) == []
    assert processes_naming(conversions) == []
    # ended, not waited for: the two conversions running at the signal did not both finish
    assert len(list(out.glob("*.obj"))) < 2
