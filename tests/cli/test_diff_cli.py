"""``c1surf diff``: exit 0 when equal within --tolerance, 1 with the first differences, one-line errors."""
from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from c1surf.cli.main import main

from conftest import SAMPLES


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """twisted's patches as JSON, NPZ and IGES, and cube's as JSON (one face per patch in IGES: --no-merge)."""
    folder = tmp_path_factory.mktemp("diff")
    out = {}
    for name in ("twisted", "cube"):
        paths = {s: folder / f"{name}{s}" for s in (".json", ".npz", ".igs")}
        result = run("convert", SAMPLES / f"{name}.obj", "-o", folder / f"{name}.ply", "-r", "2", "-q", "--no-merge",
                     *[a for p in paths.values() for a in ("--patches", p)])
        assert result.exit_code == 0, result.output
        out[name] = paths
    return out


def moved_copy(source, target, k, i, j, axis, by):
    doc = json.loads(source.read_text())
    doc["patches"][k]["points"][i][j][axis] += by
    target.write_text(json.dumps(doc))
    return doc["patches"][k]


def test_identical_files_and_formats_of_one_surface_are_equal(files):
    twisted = files["twisted"]
    for a, b in ((".json", ".json"), (".json", ".npz"), (".npz", ".json"), (".json", ".igs")):
        result = run("diff", twisted[a], twisted[b])
        assert result.exit_code == 0, result.output
        assert result.stdout.startswith("equal within 1e-12")


def test_one_moved_coefficient_is_named(files, tmp_path):
    patch = moved_copy(files["twisted"][".json"], tmp_path / "moved.json", 123, 1, 2, 0, 1e-6)
    result = run("diff", files["twisted"][".json"], tmp_path / "moved.json")
    assert result.exit_code == 1
    lines = result.stdout.splitlines()
    source = ", ".join(f"{key} {value}" for key, value in patch["source"].items())
    assert lines[0].startswith(f"patch 123 ({patch['kind']}, source {source}): points[1][2] ")
    assert "moved 1.000e-06" in lines[0] and "of the bounding-box diagonal > 1e-12" in lines[0]
    assert lines[-1].startswith("1 coefficients moved by more than 1e-12")
    # also against the NPZ of the unmoved surface, and honouring --tolerance
    assert run("diff", files["twisted"][".npz"], tmp_path / "moved.json").exit_code == 1
    assert run("diff", files["twisted"][".json"], tmp_path / "moved.json", "--tolerance", "1e-6").exit_code == 0
    assert run("diff", files["twisted"][".json"], tmp_path / "moved.json", "--tolerance", "1e-8").exit_code == 1


def test_different_counts_are_a_structural_difference(files):
    result = run("diff", files["twisted"][".json"], files["cube"][".npz"])
    assert result.exit_code == 1
    assert result.stdout.splitlines()[0] == "patches: 212 biquadratic, 108 bicubic -> 72 biquadratic, 24 bicubic"
    assert "differ in structure" in result.stdout


def test_meshes(tmp_path):
    assert run("diff", SAMPLES / "cube.obj", SAMPLES / "cube.obj").exit_code == 0
    result = run("diff", SAMPLES / "cube.obj", SAMPLES / "twisted.obj")
    assert result.exit_code == 1 and "vertices: 8 -> " in result.stdout and "faces: 6 -> " in result.stdout
    text = (SAMPLES / "cube.obj").read_text().splitlines()
    first_v = next(n for n, line in enumerate(text) if line.startswith("v "))
    x, y, z = map(float, text[first_v].split()[1:4])
    text[first_v] = f"v {x + 1e-6!r} {y!r} {z!r}"
    (tmp_path / "moved.obj").write_text("\n".join(text) + "\n")
    result = run("diff", SAMPLES / "cube.obj", tmp_path / "moved.obj")
    assert result.exit_code == 1 and result.stdout.startswith("vertex 0: position ")
    assert run("diff", SAMPLES / "cube.obj", tmp_path / "moved.obj", "--tolerance", "1e-5").exit_code == 0


@pytest.mark.parametrize("second", ["missing.json", "mesh.obj", "x.stl", "bad.json"])
def test_unreadable_or_mixed_inputs_are_one_line_errors(files, tmp_path, second):
    (tmp_path / "bad.json").write_text("{")
    target = SAMPLES / "cube.obj" if second == "mesh.obj" else tmp_path / second
    result = run("diff", files["cube"][".json"], target)
    assert result.exit_code == 1
    assert result.stderr.startswith("c1surf: error: ") and result.stderr.count("\n") == 1


def test_packed_and_unpacked_files_of_one_surface_compare_equal(tmp_path):
    """diff compares surfaces: the JSON (one entry per patch) and the packed STEP and IGES (strips of merged
    pieces, their patches in the pieces' (u, v) and in another order) of one conversion are equal, both ways;
    a surface made with another blend ratio is not (its coefficients moved, the structure is the same)."""
    pytest.importorskip("OCP")
    files = {s: tmp_path / f"t{s}" for s in (".json", ".step", ".igs")}
    result = run("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "t.ply", "-r", "2", "-q",
                 *[a for p in files.values() for a in ("--patches", p)])
    assert result.exit_code == 0, result.output
    for a, b in ((".json", ".step"), (".step", ".json"), (".json", ".igs"), (".igs", ".step")):
        result = run("diff", files[a], files[b])
        assert result.exit_code == 0, (a, b, result.output)
        assert result.stdout.startswith("equal within 1e-12")
    other = tmp_path / "other.step"
    result = run("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "o.ply", "-r", "2", "-q", "--blend", "0.4",
                 "--patches", other)
    assert result.exit_code == 0, result.output
    result = run("diff", files[".json"], other)
    assert result.exit_code == 1 and "differ in structure" not in result.stdout
    assert "coefficients moved by more than 1e-12" in result.stdout.splitlines()[-1]
