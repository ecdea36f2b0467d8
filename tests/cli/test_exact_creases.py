"""convert/check with C0 creases (the default, --exact-creases): in every output (patch files list the
crease sides, check measures their gap, tessellations split normals along them, STEP/IGES solids close over them)."""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from plyfile import PlyData

from c1surf.cli.main import main

from conftest import SAMPLES, shared_mesh

CUBE = SAMPLES / "cube.obj"  # side 2, centred on the origin


def run(*args, env=None):
    return CliRunner(env=env).invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def sharp_cube(tmp_path_factory):
    """The sample cube with every edge an infinitely sharp crease (--crease-angle 40), C0."""
    d = tmp_path_factory.mktemp("cube")
    result = run("convert", CUBE, "-o", d / "cube.ply", "-r", 5, "--crease-angle", 40, "--exact-creases",
                 "--patches", d / "cube.json", "--patches", d / "cube.npz", "--patches", d / "cube.step",
                 "--patches", d / "cube.igs")
    assert result.exit_code == 0, result.output
    return d, result


def test_the_patch_files_list_the_crease_sides_and_check_measures_them(sharp_cube):
    d, result = sharp_cube
    assert "C0 creases: 12 of 12 infinitely sharp crease edges are C0 seams" in result.stderr
    doc = json.loads((d / "cube.json").read_text())
    rows = np.array(doc["crease_sides"])
    assert rows.shape == (48, 4) and set(rows[:, [1, 3]].ravel()) <= {0, 1, 2, 3}
    for name in ("cube.json", "cube.npz"):
        check = run("check", d / name)
        assert check.exit_code == 0, check.output
        assert "crease edges:     48 of 48 listed, max gap 0.000e+00" in check.output
        assert "G1: yes" in check.output


def test_the_tessellation_is_the_cube_with_split_normals(sharp_cube):
    d, _ = sharp_cube
    vertex = PlyData.read(str(d / "cube.ply"))["vertex"]
    points = np.stack([vertex["x"], vertex["y"], vertex["z"]], axis=1)
    normals = np.stack([vertex["nx"], vertex["ny"], vertex["nz"]], axis=1)
    # every vertex on a face of the cube; every normal that face's (none averaged across an edge)
    assert np.abs(np.abs(points).max(axis=1) - 1.0).max() <= 1e-12
    assert np.abs(np.abs(normals).max(axis=1) - 1.0).max() <= 1e-12
    assert np.abs(np.sort(np.abs(normals), axis=1)[:, :2]).max() <= 1e-12
    # the corners are reached, once per face they belong to
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    hits = [(np.linalg.norm(points - c, axis=1) <= 1e-12).sum() for c in corners]
    assert hits == [3] * 8


@pytest.mark.parametrize("name", ["cube.step", "cube.igs"])
def test_cad_files_are_one_closed_valid_solid_of_the_cube(sharp_cube, name):
    pytest.importorskip("OCP")
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.IGESControl import IGESControl_Reader
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer

    d, _ = sharp_cube
    reader = STEPControl_Reader() if name.endswith(".step") else IGESControl_Reader()
    reader.ReadFile(str(d / name))
    reader.TransferRoots()
    shape = reader.OneShape()

    def count(kind):
        explorer, n = TopExp_Explorer(shape, kind), 0
        while explorer.More():
            n, _ = n + 1, explorer.Next()
        return n

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    assert count(TopAbs_SOLID) == 1 and count(TopAbs_FACE) == 24  # each side a 4 x 4 piece, in 4 strips
    assert BRepCheck_Analyzer(shape).IsValid()
    assert abs(props.Mass() - 8.0) <= 1e-12


def test_check_fails_when_a_listed_crease_does_not_meet(sharp_cube, tmp_path):
    d, _ = sharp_cube
    doc = json.loads((d / "cube.json").read_text())
    first, second = doc["crease_sides"][0], doc["crease_sides"][1]
    doc["crease_sides"][0] = [first[0], first[1], second[2], second[3]]  # two sides that are not one edge
    doc["crease_sides"][1] = [second[0], second[1], first[2], first[3]]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    check = run("check", bad)
    assert check.exit_code == 1
    assert "crease edges whose two sides do not meet: 2" in check.output and "G1: NO" in check.output


def test_malformed_crease_sides_are_one_line(sharp_cube, tmp_path):
    d, _ = sharp_cube
    doc = json.loads((d / "cube.json").read_text())
    doc["crease_sides"][0] = [0, 7, 1, 0]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    check = run("check", bad)
    assert check.exit_code != 0
    assert check.stderr.strip().splitlines()[-1].startswith("c1surf: error:") and "crease_sides" in check.stderr


def test_crease_lines_that_end_inside_are_named(tmp_path):
    result = run("check", shared_mesh("opensubdiv/catmark_cubes_infsharp.obj"), "--exact-creases")
    assert result.exit_code == 0, result.output
    assert "C0 creases: 17 of 17 infinitely sharp crease edges are C0 seams" in result.stderr
    assert "2 C0 crease lines end inside the surface (darts): C0 up to the dart" in result.stderr
    assert "1 infinitely sharp corners are not on a C0 seam" in result.stderr
    assert "crease edges:     68 of 68 listed" in result.output


def test_a_crease_line_of_one_edge_inside_the_surface_stays_g1(tmp_path):
    creases = tmp_path / "one.json"
    creases.write_text(json.dumps({"creases": [[9, 8, 10]]}))  # catmark_cubes_infsharp's edge 9 - 8 alone
    mesh = tmp_path / "cubes.obj"
    text = shared_mesh("opensubdiv/catmark_cubes_infsharp.obj").read_text().splitlines()
    mesh.write_text("\n".join(line for line in text if not line.startswith("t ")) + "\n")
    result = run("check", mesh, "--exact-creases", "--creases", creases)
    assert result.exit_code == 0, result.output
    assert "1 infinitely sharp crease edges stay the sharpest G1 crease" in result.stderr
    assert "G1: yes" in result.output


def test_streamed_and_in_memory_files_are_identical(tmp_path):
    outputs = {}
    for stream in ("1", "0"):
        d = tmp_path / stream
        d.mkdir()
        result = run("convert", CUBE, "-o", d / "c.ply", "-r", 4, "--crease-angle", 40, "--exact-creases",
                     "--patches", d / "c.json", "--patches", d / "c.npz", env={"C1SURF_STREAM": stream})
        assert result.exit_code == 0, result.output
        outputs[stream] = [(d / name).read_bytes() for name in ("c.ply", "c.json", "c.npz")]
    assert outputs["1"] == outputs["0"]


def test_inspect_plans_the_seams_that_convert_makes(tmp_path):
    path = shared_mesh("opensubdiv/catmark_cubes_infsharp.obj")
    report = json.loads(run("inspect", path, "--exact-creases", "--json").output)
    assert "C0 creases: 17 of 17 infinitely sharp crease edges are C0 seams" in report["notes"]
    result = run("convert", path, "-o", tmp_path / "x.ply", "--exact-creases", "--patches", tmp_path / "x.json")
    assert result.exit_code == 0, result.output
    counts = json.loads((tmp_path / "x.json").read_text())["counts"]
    assert (report["patches"]["biquadratic"], report["patches"]["bicubic"]) == (counts["biquadratic"], counts["bicubic"])


def test_render_of_the_mesh_is_the_render_of_its_patch_file(sharp_cube, tmp_path):
    d, _ = sharp_cube
    from_mesh, from_file = tmp_path / "m.png", tmp_path / "f.png"
    # render reads a mesh's own tags (no --crease-angle): the cube with its 12 edges tagged
    tagged = tmp_path / "cube.obj"
    faces = [[int(v) - 1 for v in line.split()[1:]] for line in CUBE.read_text().splitlines() if line.startswith("f ")]
    edges = sorted({tuple(sorted((f[i], f[(i + 1) % 4]))) for f in faces for i in range(4)})
    tagged.write_text(CUBE.read_text() + "".join(f"t crease 2/1/0 {a} {b} 10\n" for a, b in edges))
    assert run("render", tagged, "--exact-creases", "--png", from_mesh, "--size", "64x64").exit_code == 0
    assert run("render", d / "cube.json", "--png", from_file, "--size", "64x64").exit_code == 0
    assert from_mesh.read_bytes() == from_file.read_bytes()


def test_a_dart_from_obj_tags_through_patch_files_and_check(tmp_path):
    """A crease line tagged in an OBJ file (OpenSubdiv `t crease`) that ends inside the surface: convert writes
    the dart's crease spoke among the patch file's crease sides, and check measures it C0, G1 elsewhere."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "construction"))
    from dart_meshes import polar_dart

    points, sizes, corners, features, _ = polar_dart([2, 1, 2, 2, 2], seed=3)
    faces = np.split(corners, np.cumsum(sizes)[:-1])
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in points) + "".join(
        "f " + " ".join(str(v + 1) for v in face) + "\n" for face in faces) + "".join(
        f"t crease 2/1/0 {a} {b} 10\n" for a, b in features.crease_edges)
    mesh = tmp_path / "dart.obj"
    mesh.write_text(text)
    result = run("convert", mesh, "-o", tmp_path / "dart.ply", "--patches", tmp_path / "dart.json")
    assert result.exit_code == 0, result.output
    assert "1 C0 crease lines end inside the surface (darts)" in result.stderr
    sides = json.loads((tmp_path / "dart.json").read_text())["crease_sides"]
    check = run("check", tmp_path / "dart.json")
    assert check.exit_code == 0, check.output
    assert f"crease edges:     {len(sides)} of {len(sides)} listed" in check.output and "G1: yes" in check.output
