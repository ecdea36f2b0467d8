"""io.registry: one suffix table per kind of file, the one suffix check and its message, used by the commands."""
from __future__ import annotations

import pytest
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.io.errors import C1SurfFileError
from c1surf.io.registry import (CAGE_WRITERS, IMAGE_WRITERS, MESH_READERS, MESH_WRITERS, PATCH_READERS, PATCH_WRITERS,
                                UnsupportedFormat, suffix_list, suffix_of)

TABLES = [MESH_READERS, MESH_WRITERS, PATCH_READERS, PATCH_WRITERS, IMAGE_WRITERS, CAGE_WRITERS]


@pytest.mark.parametrize("table", TABLES, ids=lambda t: f"{t.noun} {t.verb}")
def test_every_format_names_a_function_of_io(table):
    for suffix, fmt in table.items():
        assert suffix == suffix.lower() and suffix.startswith(".") and suffix in fmt.suffixes
        module, name = fmt.target.split(":")
        assert module.startswith("c1surf.io.") and fmt.description
        assert callable(fmt.function) and fmt.function.__name__ == name
        if fmt.streamed:  # the writer by blocks of a mesh format
            assert fmt.streamed.startswith("c1surf.io.") and callable(fmt.streamed_function)


def test_suffix_of_is_the_one_check():
    assert suffix_of("a/B.PLY", MESH_READERS) == ".ply" and suffix_of("x.IGES", PATCH_READERS) == ".iges"
    with pytest.raises(UnsupportedFormat) as info:
        suffix_of("dir/mesh.glb", MESH_READERS)
    assert str(info.value) == ("dir/mesh.glb: unsupported mesh format (suffix '.glb'): c1surf reads .obj, .off, .ply, "
                               ".stl, .usd, .usda, .usdc, .usdz files")
    assert isinstance(info.value, C1SurfFileError) and isinstance(info.value, ValueError)
    with pytest.raises(UnsupportedFormat, match=r"\(no suffix\): c1surf writes .iges, .igs, .json, .npz, .step, .stp"):
        suffix_of("surface", PATCH_WRITERS)


def test_what_the_formats_keep():
    assert MESH_WRITERS.holding("attributes") == (".obj", ".ply")
    assert MESH_WRITERS.holding("properties") == (".ply",)
    assert suffix_list(MESH_WRITERS) == ".glb, .obj, .off, .ply, .stl, .usd, .usda, .usdc"
    assert MESH_WRITERS.holding("patch ids") == (".usd", ".usdc", ".usda")


def test_commands_take_suffixes_and_help_from_the_registry(tmp_path):
    runner = CliRunner()
    help_text = " ".join(runner.invoke(main, ["convert", "--help"]).output.split())
    assert f"({suffix_list(MESH_WRITERS)})" in help_text and f"({suffix_list(PATCH_WRITERS)})" in help_text
    mesh = tmp_path / "m.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    for args in (["convert", str(mesh), "-o", str(tmp_path / "m.xyz")],
                 ["convert", str(mesh), "-o", str(tmp_path / "m.ply"), "--patches", str(tmp_path / "p.txt")],
                 ["tessellate", str(tmp_path / "p.txt"), "-o", str(tmp_path / "m.ply")]):
        result = runner.invoke(main, args)
        assert result.exit_code == 2 and "unsupported" in result.output and "c1surf " in result.output, result.output
