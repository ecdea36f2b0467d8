"""The command line as users run it: help, outputs, check's verdict, one-line errors."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys

import click
import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.io.patches.json_patches import read_patches_json

from conftest import SAMPLES, shared_mesh


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def test_help_describes_every_option():
    ctx = click.Context(main)
    commands = {"": main, **{name: main.get_command(ctx, name) for name in main.list_commands(ctx)}}
    assert {"convert", "check"} <= set(commands)
    for name, command in commands.items():
        result = run(*([name] if name else []), "--help")
        assert result.exit_code == 0
        text = " ".join(result.output.split())
        for param in command.params:
            if isinstance(param, click.Option):
                assert any(opt in text for opt in param.opts), (name, param.opts)
                assert param.help, f"{name} {param.opts} has no help text"


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl", ".glb", ".off"])
def test_convert_writes_every_mesh_format(tmp_path, suffix):
    out = tmp_path / f"cube{suffix}"
    result = run("convert", SAMPLES / "cube.obj", "-o", out, "--resolution", 4, "--quiet")
    assert result.exit_code == 0, result.output
    mesh = trimesh.load(out, force="mesh", process=True)
    # 96 patches of 4 x 4 samples, welded: V = F_R + 2 E_R + 4 P (corners, edge interiors, interiors)
    assert mesh.is_watertight
    assert len(mesh.faces) == 96 * 2 * 9


def test_convert_then_check_round_trip(tmp_path):
    patches = tmp_path / "twisted.json"
    result = run("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "twisted.ply", "--patches", patches)
    assert result.exit_code == 0, result.output
    doc = json.loads(patches.read_text())
    assert doc["format"] == "c1surf-patches" and doc["version"] == 1
    kinds = {p["kind"] for p in doc["patches"]}
    assert kinds == {"biquadratic", "bicubic"}
    for p in doc["patches"][:5] + doc["patches"][-5:]:
        du, dv = p["degree"]
        assert np.asarray(p["points"]).shape == (du + 1, dv + 1, 3)
        assert len(p["source"]) == 1
    check = run("check", patches)
    assert check.exit_code == 0 and "G1: yes" in check.output


def test_check_fails_on_a_broken_surface(tmp_path):
    patches = tmp_path / "cube.json"
    assert run("convert", SAMPLES / "cube.obj", "-o", tmp_path / "cube.obj", "--patches", patches).exit_code == 0
    doc = json.loads(patches.read_text())
    bicubic = next(p for p in doc["patches"] if p["kind"] == "bicubic")
    bicubic["points"][1][2][0] += 0.01  # a coefficient next to a shared edge
    patches.write_text(json.dumps(doc))
    result = run("check", patches)
    assert result.exit_code == 1 and "G1: NO" in result.output


def test_check_converts_a_mesh_first():
    result = run("check", SAMPLES / "dodecahedron.obj", "--alpha", "0.6")
    assert result.exit_code == 0 and "G1: yes" in result.output


def test_patch_file_floats_round_trip_exactly(tmp_path):
    from c1surf.construction.surface import Surface
    from c1surf.io.meshes.obj import read_obj

    patches = tmp_path / "p.json"
    assert run("convert", SAMPLES / "icosahedron.obj", "-o", tmp_path / "x.obj", "--patches", patches).exit_code == 0
    mesh = read_obj(SAMPLES / "icosahedron.obj")
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points)
    quad, cubic = read_patches_json(patches)
    assert np.array_equal(quad, surface.biquadratic) and np.array_equal(cubic, surface.bicubic)


def one_line_error(tmp_path, *args):
    """Run the real executable; return (exit code, stderr lines)."""
    proc = subprocess.run([sys.executable, "-m", "c1surf.cli.main", *map(str, args)], capture_output=True, text=True, cwd=tmp_path)
    return proc.returncode, proc.stderr.strip().splitlines()


@pytest.mark.parametrize("option", ["--non-manifold=refuse", "--g1-creases"])
def test_non_manifold_edge_is_refused_with_lines(tmp_path, option):
    # by default such edges are cut into sheets (tests/construction/test_non_manifold_sheets.py)
    fan = shared_mesh("opensubdiv/catmark_fan.obj")
    out = tmp_path / "fan.obj"
    code, lines = one_line_error(tmp_path, "convert", fan, "-o", out, option)
    assert code == 1 and len(lines) == 1
    line = lines[0]
    assert line.startswith(f"c1surf: error: {fan}:")
    assert "shared by 3 faces" in line and "faces on lines" in line and "Traceback" not in line
    assert not out.exists() and not list(tmp_path.glob("*.tmp*"))


def test_bad_usage_exits_2(tmp_path):
    code, lines = one_line_error(tmp_path, "convert", SAMPLES / "cube.obj", "-o", tmp_path / "cube.xyz")
    assert code == 2
    assert not (tmp_path / "cube.xyz").exists()


def test_never_overwrites_the_input(tmp_path):
    mesh = tmp_path / "cube.obj"
    shutil.copy(SAMPLES / "cube.obj", mesh)
    before = mesh.read_bytes()
    code, lines = one_line_error(tmp_path, "convert", mesh, "-o", mesh)
    assert code == 1 and len(lines) == 1 and lines[0].startswith("c1surf: error:")
    assert mesh.read_bytes() == before


def test_missing_input_is_one_line(tmp_path):
    code, lines = one_line_error(tmp_path, "convert", tmp_path / "nope.obj", "-o", tmp_path / "x.obj")
    assert code == 1 and len(lines) == 1 and "nope.obj" in lines[0]


def test_too_large_output_is_refused_with_an_estimate(tmp_path):
    out = tmp_path / "big.ply"
    code, lines = one_line_error(tmp_path, "convert", SAMPLES / "cube.obj", "-o", out, "--resolution", 200000)
    assert code == 1 and len(lines) == 1
    assert "GiB" in lines[0] and "--force" in lines[0] and "--resolution" in lines[0]
    assert not out.exists()


def test_curvature_of_a_rational_surface_is_the_rational_one(tmp_path):
    """``convert --curvature`` on weighted input: every PLY vertex carries the curvature of the
    rational patch at that sample (interior samples, evaluated here patch by patch, not through the tessellation)."""
    from plyfile import PlyData

    from c1surf.construction.surface import Surface
    from c1surf.evaluation.curvature import patch_curvature
    from c1surf.evaluation.tessellate import patch_adjacency, tessellate_patches
    from c1surf.io.meshes.obj import read_obj

    mesh = read_obj(SAMPLES / "twisted.obj")
    weights = np.random.default_rng(8).uniform(0.5, 2.0, mesh.n_vertices)
    offsets = mesh.face_offsets()
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r} {float(w)!r}" for (x, y, z), w in zip(mesh.points, weights)]
    lines += ["f " + " ".join(str(v + 1) for v in mesh.face_vertices[offsets[f]: offsets[f + 1]]) for f in range(mesh.n_faces)]
    src, out, n = tmp_path / "w.obj", tmp_path / "w.ply", 4
    src.write_text("\n".join(lines) + "\n")
    result = CliRunner().invoke(main, ["convert", str(src), "-o", str(out), "--curvature", "-r", str(n)])
    assert result.exit_code == 0, result.output
    kmax = np.asarray(PlyData.read(str(out))["vertex"]["kmax"], dtype=np.float64)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, weights=weights)
    groups = [surface.biquadratic, surface.bicubic]
    tess = tessellate_patches(groups, patch_adjacency(surface.refined, surface.frames), n, surface.patch_weights)
    t = np.linspace(0.0, 1.0, n)[1:-1]  # interior samples: a vertex on a patch side takes one side's curvature
    u, v = np.repeat(t, n - 2), np.tile(t, n - 2)
    for k, (group, w) in enumerate(zip(groups, surface.patch_weights)):
        first = 0 if k == 0 else len(groups[0])
        for p in (0, len(group) - 1):
            exact = patch_curvature(group, u, v, w, index=np.full(u.size, p)).kmax
            np.testing.assert_allclose(kmax[tess.grid[first + p, 1:-1, 1:-1].ravel()], exact, rtol=1e-5, atol=1e-6)  # float32 in PLY


def test_outputs_that_do_not_fit_on_the_disk_are_refused_before_writing(tmp_path, monkeypatch):
    from c1surf.api import surface_from_file, tessellate_surface
    from c1surf import resources
    from c1surf.cli import convert as convert_module

    out, patches = tmp_path / "out.ply", tmp_path / "p.json"
    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(resources.shutil, "disk_usage", lambda folder: usage._replace(free=100_000))
    args = ["convert", str(SAMPLES / "twisted.obj"), "-o", str(out), "--patches", str(patches), "-r", "8", "-q"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 1
    [line] = result.stderr.strip().splitlines()
    assert line.startswith("c1surf: error: the output files would take about 1.") and "0.1 MiB is free" in line
    assert not out.exists() and not patches.exists() and not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp")]
    assert CliRunner().invoke(main, args + ["--force"]).exit_code == 0  # --force writes anyway (it fits here)
    # the estimate is close to what is written: within 10 % for the mesh and the patch file
    surface, _ = surface_from_file(SAMPLES / "twisted.obj")
    tess = tessellate_surface(surface, 8)
    sizes = dict(convert_module.output_bytes(".ply", tess, False, False, [".json"], surface))
    assert abs(sizes[".ply"] - out.stat().st_size) < 0.1 * out.stat().st_size
    assert abs(sizes[".json"] - patches.stat().st_size) < 0.1 * patches.stat().st_size
