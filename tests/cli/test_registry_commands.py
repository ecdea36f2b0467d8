"""Every command on a tiny file of every format it reads (``io.registry``): the same surface whichever the format.

Commands that build a surface from a mesh (convert, check, inspect, render, measure, batch) take every format of
``MESH_READERS``; commands that read patches (check, measure, render, tessellate, diff) every format of
``PATCH_READERS``. Each run exits 0 with the numbers of the OBJ cube (a format's reader may change nothing).
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.io.registry import MESH_READERS, MESH_WRITERS, PATCH_READERS

from conftest import SAMPLES

QUADS = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
CORNERS = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def write_cube(path):
    """The unit cube as quads (OBJ, PLY, OFF: read as written) or triangles (STL: the only faces it has)."""
    suffix = path.suffix
    if suffix == ".obj":
        path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in CORNERS)
                        + "".join("f " + " ".join(str(i + 1) for i in q) + "\n" for q in QUADS))
    elif suffix == ".off":
        path.write_text(f"OFF\n8 6 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in CORNERS)
                        + "".join("4 " + " ".join(map(str, q)) + "\n" for q in QUADS))
    elif suffix == ".ply":
        path.write_text("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 6\nproperty list uchar int vertex_indices\nend_header\n"
                        + "".join(f"{x} {y} {z}\n" for x, y, z in CORNERS)
                        + "".join("4 " + " ".join(map(str, q)) + "\n" for q in QUADS))
    elif suffix == ".stl":
        triangles = [[q[0], q[1], q[2]] for q in QUADS] + [[q[0], q[2], q[3]] for q in QUADS]
        trimesh.Trimesh(CORNERS, triangles, process=False).export(path)
    elif suffix == ".usd":  # written by usd-core's own API: a UsdGeom.Mesh of the quads
        from pxr import Usd, UsdGeom

        stage = Usd.Stage.CreateNew(str(path))
        cube = UsdGeom.Mesh.Define(stage, "/cube")
        cube.CreatePointsAttr(CORNERS)
        cube.CreateFaceVertexCountsAttr([4] * len(QUADS))
        cube.CreateFaceVertexIndicesAttr([i for q in QUADS for i in q])
        stage.Save()
    else:
        raise AssertionError(f"no tiny file for {suffix}: add one for the new format")


def measured(path) -> dict:
    result = run("measure", path, "--json")
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


@pytest.mark.parametrize("suffix", sorted({f.suffixes[0] for f in MESH_READERS.values()}))
def test_every_mesh_command_reads_every_mesh_format(tmp_path, suffix):
    mesh = tmp_path / f"cube{suffix}"
    write_cube(mesh)
    quads = suffix != ".stl"
    out = tmp_path / "out.ply"
    assert run("convert", mesh, "-o", out, "-r", 3, "-q").exit_code == 0 and out.exists()
    check = run("check", mesh)
    assert check.exit_code == 0 and "G1: yes" in check.stdout
    inspected = run("inspect", mesh, "--json")
    assert inspected.exit_code == 0, inspected.output
    report = json.loads(inspected.stdout)
    assert report["refused"] is None and report["faces"] == (6 if quads else 12)
    volume = measured(mesh)["volume"]
    if quads:  # the same surface as the OBJ cube's
        reference = tmp_path / "reference.obj"
        write_cube(reference)
        assert volume == pytest.approx(measured(reference)["volume"], rel=1e-14)
    assert 0.3 < volume < 1.0
    rendered = run("render", mesh, "--png", tmp_path / "cube.png", "--size", "32x32", "-q")
    assert rendered.exit_code == 0, rendered.output
    batch = run("batch", str(tmp_path / f"*{suffix}"), "-o", tmp_path / "batch", "-r", 2, "--blend", 0.4, "-q")
    assert batch.exit_code == 0 and (tmp_path / "batch" / "cube.ply").exists()


@pytest.fixture(scope="module")
def patch_files(tmp_path_factory):
    """The patches of the sample cube in every format c1surf writes and reads."""
    folder = tmp_path_factory.mktemp("patches")
    paths = [folder / f"cube{f.suffixes[0]}" for f in dict.fromkeys(PATCH_READERS.values())]
    args = [a for p in paths for a in ("--patches", p)]
    assert run("convert", SAMPLES / "cube.obj", "-o", folder / "cube.ply", "-r", 3, *args, "-q").exit_code == 0
    return paths


@pytest.mark.parametrize("index", range(len(dict.fromkeys(PATCH_READERS.values()))))
def test_every_patch_command_reads_every_patch_format(tmp_path, patch_files, index):
    path, first = patch_files[index], patch_files[0]
    check = run("check", path)
    assert check.exit_code == 0 and "G1: yes" in check.stdout
    assert measured(path)["volume"] == pytest.approx(measured(first)["volume"], rel=1e-12)
    out = tmp_path / "t.ply"
    assert run("tessellate", path, "-o", out, "-r", 3, "-q").exit_code == 0
    assert run("render", path, "--png", tmp_path / "p.png", "--size", "32x32", "-q").exit_code == 0
    assert run("diff", first, path).exit_code in (0, 1)  # packed CAD files differ in structure (issue 30)


def test_help_names_exactly_the_formats_a_command_reads():
    mesh, patches = "OBJ, PLY, STL, OFF, USD", "JSON, NPZ, IGES, STEP"
    assert MESH_READERS.names() == mesh and PATCH_READERS.names() == patches
    reads = {"convert": [mesh], "check": [mesh, patches], "measure": [mesh, patches], "render": [mesh, patches],
             "inspect": [mesh], "batch": [mesh], "tessellate": [patches, MESH_WRITERS.names()], "diff": [mesh, patches]}
    for command, names in reads.items():
        text = " ".join(run(command, "--help").stdout.split())
        assert all(name in text for name in names), command
    # every reader takes keep_degenerate; the USD reader also its own options (io.meshes.read.read_mesh's usd=)
    defaults = [dict(MESH_READERS[s].function.__kwdefaults__) for s in MESH_READERS]
    assert np.all([d.pop("keep_degenerate") is False and d in ({}, {"usd": None}) for d in defaults])
