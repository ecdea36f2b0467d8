"""``--tolerance T`` on the command line: watertight outputs within T, convert = tessellate, one-line refusals."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.io.meshes.obj import read_obj

from conftest import SAMPLES


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_convert_and_tessellate_write_the_same_watertight_mesh(tmp_path):
    out, json_file, npz_file = tmp_path / "a.ply", tmp_path / "a.json", tmp_path / "a.npz"
    result = invoke("convert", SAMPLES / "twisted.obj", "-o", out, "--tolerance", "0.002", "--patches", json_file,
                    "--patches", npz_file)
    assert result.exit_code == 0, result.output
    [note] = [line for line in result.stderr.splitlines() if "--tolerance" in line]
    error = float(note.split("measured chordal error ")[1].split()[0])
    assert note.startswith("c1surf: note: --tolerance 0.002:") and 0 < error <= 0.002
    mesh = trimesh.load(out, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert f"{len(mesh.faces)} triangles" in note
    for source in (json_file, npz_file):
        again = tmp_path / f"again_{source.suffix[1:]}.ply"
        result = invoke("tessellate", source, "-o", again, "--tolerance", "0.002", "-q")
        assert result.exit_code == 0 and result.stderr == ""
        assert again.read_bytes() == out.read_bytes()
    # a larger tolerance: fewer triangles
    coarse = tmp_path / "coarse.ply"
    assert invoke("convert", SAMPLES / "twisted.obj", "-o", coarse, "--tolerance", "0.02", "-q").exit_code == 0
    assert len(trimesh.load(coarse, process=False).faces) < len(mesh.faces)


@pytest.mark.parametrize("value", ["0", "-0.01", "nan", "inf", "-inf"])
@pytest.mark.parametrize("command", ["convert", "tessellate"])
def test_bad_tolerances_are_one_line_errors(tmp_path, value, command):
    source = SAMPLES / "cube.obj"
    if command == "tessellate":
        source = tmp_path / "cube.json"
        assert invoke("convert", SAMPLES / "cube.obj", "-o", tmp_path / "c.ply", "--patches", source, "-q").exit_code == 0
    out = tmp_path / "x.ply"
    result = invoke(command, source, "-o", out, f"--tolerance={value}")
    assert result.exit_code == 2
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("c1surf: error: --tolerance must be a positive number") and not out.exists()


def test_tolerance_and_an_explicit_resolution_contradict(tmp_path):
    out = tmp_path / "x.ply"
    for resolution in ("8", "4"):  # even the default value, given explicitly
        result = invoke("convert", SAMPLES / "cube.obj", "-o", out, "--tolerance", "0.01", "-r", resolution)
        assert result.exit_code == 2
        [line] = result.stderr.strip().splitlines()
        assert line == "c1surf: error: --tolerance and --resolution both set the tessellation's resolution: give one of them"
    assert not out.exists()


def test_curvature_and_attributes_follow_the_tolerance_mesh(tmp_path):
    from plyfile import PlyData

    out = tmp_path / "k.ply"
    assert invoke("convert", SAMPLES / "torus.obj", "-o", out, "--tolerance", "0.001", "--curvature", "-q").exit_code == 0
    vertex = PlyData.read(str(out))["vertex"]
    kmax = np.asarray(vertex["kmax"], dtype=np.float64)
    assert np.all(np.isfinite(kmax)) and kmax.min() > 0  # a torus bends everywhere
    # texture coordinates: a cube whose u is its x coordinate (linear in the points) stays so on every vertex
    mesh = read_obj(SAMPLES / "cube.obj")
    offsets = mesh.face_offsets()
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.points.tolist()]
    lines += [f"vt {x!r} {y!r}" for x, y, _ in mesh.points.tolist()]
    lines += ["f " + " ".join(f"{v + 1}/{v + 1}" for v in mesh.face_vertices[a:b]) for a, b in zip(offsets[:-1], offsets[1:])]
    source, textured = tmp_path / "uv.obj", tmp_path / "uv.ply"
    source.write_text("\n".join(lines) + "\n")
    result = invoke("convert", source, "-o", textured, "--tolerance", "0.002", "--attributes", "-q")
    assert result.exit_code == 0, result.output
    data = PlyData.read(str(textured))["vertex"]
    names = data.data.dtype.names
    u_name = next(n for n in ("s", "u", "texture_u") if n in names)
    np.testing.assert_allclose(np.asarray(data[u_name], dtype=np.float64), np.asarray(data["x"], dtype=np.float64),
                               atol=1e-6)
    assert trimesh.load(textured, process=False).is_watertight


def test_the_memory_guard_counts_the_tolerance_mesh(tmp_path, monkeypatch):
    from c1surf import resources

    monkeypatch.setattr(resources, "available_memory", lambda: 1 << 20)
    out = tmp_path / "x.ply"
    result = invoke("convert", SAMPLES / "twisted.obj", "-o", out, "--tolerance", "0.0001", "-q")
    assert result.exit_code == 1 and not out.exists()
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("c1surf: error: the tessellation would need about") and "--tolerance 0.0001" in line
    assert "raise --tolerance, or pass --force" in line
    assert invoke("convert", SAMPLES / "twisted.obj", "-o", out, "--tolerance", "0.0001", "-q", "--force").exit_code == 0


def test_a_tolerance_beyond_the_segment_limit_is_refused(tmp_path):
    out = tmp_path / "x.ply"
    result = invoke("convert", SAMPLES / "cube.obj", "-o", out, "--tolerance", "1e-12", "--force")
    assert result.exit_code == 1 and not out.exists()
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("c1surf: error: --tolerance 1e-12: a chordal error of 1e-12 of the diagonal needs more than")


def test_the_memory_guard_refuses_a_tiny_tolerance_before_planning_it(tmp_path, monkeypatch):
    """At 1e-8 the plan's side counts and templates would take seconds and GBs: the guard refuses first, on the
    cells of each patch's fewest segments (a lower bound of the vertices), and never reaches them."""
    from c1surf import resources
    from c1surf.evaluation.tolerance import tessellation

    def never(*args, **kwargs):
        raise AssertionError("the plan went on past the guard")

    monkeypatch.setattr(resources, "available_memory", lambda: 1 << 30)
    monkeypatch.setattr(tessellation, "least_triangles", never)
    out = tmp_path / "x.ply"
    result = invoke("convert", SAMPLES / "twisted.obj", "-o", out, "--tolerance", "1e-8", "-q")
    assert result.exit_code == 1 and not out.exists()
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("c1surf: error: the tessellation would need about") and "(at least " in line
    assert "vertices at --tolerance 1e-08" in line and "raise --tolerance, or pass --force" in line
