"""What every hostile case asserts (issue 30): one refusal line or a valid, finite output; never a traceback,
never a file left behind."""
from __future__ import annotations

import json
import re
import zipfile
from pathlib import Path

import numpy as np
from click.testing import CliRunner
from plyfile import PlyData

from c1surf.cli.main import main

SAMPLES = Path(__file__).resolve().parents[2] / "sample_meshes"
_NOT_CHILD_LINE = re.compile(r"\w+(Error|Exception|Warning)\b|the conversion was killed|exit status")
_NOT_FINITE_TEXT = re.compile(rb"(?i)(?<![a-z])(nan|inf|infinity)(?![a-z])")


def run(*args):
    """``c1surf ARGS`` in this process (click's CliRunner): the result with stdout and stderr apart."""
    return CliRunner().invoke(main, [str(a) for a in args])


def assert_outcome(result, folder: Path, outputs=(), refused_status=(1, 2), must_refuse: bool = False,
                   verdict: bool = False) -> bool:
    """The promise for one command: exit 0 with finite outputs, or exactly one ``c1surf: error:`` line on stderr
    (notes aside) with an exit status of ``refused_status`` and no output; no traceback either way; nothing but
    the inputs left in ``folder`` (``outputs`` when it succeeded). ``verdict``: exit 1 with a report and no error
    line is an answer too (``check``: not G1, ``diff``: they differ). True when it was refused."""
    shown = f"exit {result.exit_code}\nstdout: {result.stdout[-2000:]}\nstderr: {result.stderr[-2000:]}"
    assert result.exception is None or isinstance(result.exception, SystemExit), f"{result.exception!r}\n{shown}"
    assert "Traceback" not in result.stdout + result.stderr, shown
    lines = [line for line in result.stderr.splitlines()  # notes and batch's summary aside
             if line.strip() and not line.startswith(("c1surf: note:", "c1surf batch: "))]
    outputs = [Path(o) for o in outputs]
    answered = verdict and result.exit_code == 1 and not lines and result.stdout.strip()
    if must_refuse or (result.exit_code != 0 and not answered):
        assert result.exit_code in refused_status, shown
        assert len(lines) == 1 and lines[0].startswith("c1surf: error: "), shown
        assert not any(o.exists() for o in outputs), shown
    else:
        assert not lines, shown
        assert not _NOT_FINITE_TEXT.search(result.stdout.encode()), shown
        for output in outputs:
            assert_finite_file(output)
    left = [p.name for p in folder.iterdir() if p.name.startswith(".tmp-c1surf")]
    assert not left, f"temporary files left: {left}\n{shown}"
    return result.exit_code != 0


def assert_batch_outcome(result, path: Path, output: Path) -> None:
    """``batch`` on one file: its summary line, then (exit 1, no output) one line of the child's refusal naming
    the file, or (exit 0) the finite output; no traceback, nothing else on stderr. A usage error (exit 2) is
    one line, as for every command."""
    if result.exit_code == 2:
        assert_outcome(result, Path(path).parent, [output], refused_status=(2,), must_refuse=True)
        return
    shown = f"exit {result.exit_code}\nstderr: {result.stderr[-2000:]}"
    lines = [line for line in result.stderr.splitlines() if line.strip() and not line.startswith("c1surf: note:")]
    assert result.exit_code in (0, 1) and "Traceback" not in result.stderr + result.stdout, shown
    assert lines and lines[0].startswith("c1surf batch: "), shown
    if result.exit_code == 0:
        assert len(lines) == 1, shown
        assert_finite_file(output)
    else:
        assert len(lines) == 2 and lines[1].startswith(f"  {path}:"), shown  # the path once, then its line
        message = re.sub(r"^:(\d+:)? ", "", lines[1][len(f"  {path}"):])
        assert not lines[1].startswith(f"  {path}: {path}"), shown
        assert not _NOT_CHILD_LINE.match(message), shown  # the child's one line, no crash
        assert not output.exists(), shown


def assert_finite_file(path: Path) -> None:
    """Every number of the output file ``path`` is finite (PLY properties, JSON and NPZ arrays, text numbers)."""
    path = Path(path)
    assert path.is_file(), path
    suffix = path.suffix.lower()
    if suffix == ".ply":
        ply = PlyData.read(str(path))
        for element in ply.elements:
            for prop in element.properties:
                values = element.data[prop.name]
                if values.dtype.kind == "f":
                    assert np.isfinite(values).all(), f"{path}: {element.name}.{prop.name} not finite"
    elif suffix == ".json":
        def refuse(constant):
            raise AssertionError(f"{path}: {constant} in a JSON output")
        json.loads(path.read_text(), parse_constant=refuse)
    elif suffix == ".npz":
        with np.load(path) as data:
            for name in data.files:
                if data[name].dtype.kind == "f":
                    assert np.isfinite(data[name]).all(), f"{path}: {name} not finite"
    elif suffix in (".obj", ".off", ".igs", ".iges", ".step", ".stp"):
        assert not _NOT_FINITE_TEXT.search(path.read_bytes()), f"{path}: NaN or infinity written as text"
    elif suffix in (".stl", ".glb"):
        import trimesh

        mesh = trimesh.load(path, process=False, force="mesh")
        assert np.isfinite(mesh.vertices).all(), path


def cube_text() -> str:
    return (SAMPLES / "cube.obj").read_text()


def scaled_cube_obj(scale: float, offset: float = 0.0) -> str:
    """cube.obj with every coordinate times ``scale`` plus ``offset``."""
    out = []
    for line in cube_text().splitlines():
        if line.startswith("v "):
            out.append("v " + " ".join(repr(float(t) * scale + offset) for t in line.split()[1:4]))
        else:
            out.append(line)
    return "\n".join(out) + "\n"


def zip_bomb(path: Path, member: str, size: int) -> None:
    """An NPZ whose ``member`` (a valid .npy header of zeros) expands ``size`` bytes from a few KB."""
    header = np.lib.format.header_data_from_array_1_0(np.zeros((size // 216, 3, 3, 3)))
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        with zf.open(member + ".npy", "w", force_zip64=True) as f:
            np.lib.format.write_array_header_1_0(f, header)
            chunk = bytes(1 << 20)
            for _ in range(size >> 20):
                f.write(chunk)
