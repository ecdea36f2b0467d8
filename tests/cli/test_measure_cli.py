"""``c1surf measure``: patch files of every readable format and meshes, text and --json, open surfaces, errors."""
from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.cli.main import main

from conftest import SAMPLES

KEYS = {"area", "volume", "centroid", "inertia"}


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def measured(*args) -> dict:
    result = run("measure", *args, "--json")
    assert result.exit_code == 0, result.output + result.stderr
    return json.loads(result.stdout)


@pytest.fixture(scope="module")
def cube_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cube")
    paths = [folder / f"cube{suffix}" for suffix in (".json", ".npz", ".igs")]
    patches = [arg for p in paths for arg in ("--patches", p)]
    result = run("convert", SAMPLES / "cube.obj", "-o", folder / "cube.ply", "-r", "2", "-q", *patches)
    assert result.exit_code == 0, result.output
    return paths


def test_mesh_and_every_patch_format_give_the_same_numbers(cube_files):
    from_mesh = measured(SAMPLES / "cube.obj")
    assert KEYS <= set(from_mesh) and from_mesh["closed"] is True and from_mesh["reason"] is None
    assert len(from_mesh["centroid"]) == 3 and np.shape(from_mesh["inertia"]) == (3, 3)
    assert from_mesh["volume"] > 0 and from_mesh["area"] > 0
    for path in cube_files:
        doc = measured(path)
        for key in KEYS:
            np.testing.assert_allclose(doc[key], from_mesh[key], rtol=1e-13, atol=1e-15)


def test_text_report_names_the_reference_point(cube_files):
    result = run("measure", cube_files[0])
    assert result.exit_code == 0
    for word in ("area:", "volume:", "centroid:", "about the centroid", "closed"):
        assert word in result.stdout


def test_open_surface_has_null_volume_and_says_why(tmp_path):
    mesh = tmp_path / "open.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0.3\nv 2 1 0.3\nf 1 2 3 4\nf 2 5 6 3\n")
    doc = measured(mesh)
    assert doc["area"] > 0 and doc["closed"] is False
    assert doc["volume"] is None and doc["centroid"] is None and doc["inertia"] is None
    assert "open" in doc["reason"]
    text = run("measure", mesh).stdout
    assert "not defined" in text and "open" in text


def test_options_of_the_construction_apply_to_a_mesh():
    default = measured(SAMPLES / "cube.obj")
    tighter = measured(SAMPLES / "cube.obj", "--blend", "0.2")
    assert tighter["volume"] > default["volume"]  # closer to the unit-edge mesh cube


@pytest.mark.parametrize("content, suffix", [("not json", ".json"), ("", ".obj")])
def test_unreadable_input_is_one_line_error(tmp_path, content, suffix):
    path = tmp_path / f"bad{suffix}"
    path.write_text(content)
    result = run("measure", path)
    assert result.exit_code == 1
    assert result.stderr.startswith("c1surf: error: ") and result.stderr.count("\n") == 1


def test_missing_file_and_unknown_suffix(tmp_path):
    for path in (tmp_path / "none.json", tmp_path / "x.stl"):
        result = run("measure", path)
        assert result.exit_code == 1 and result.stderr.startswith("c1surf: error: ")
