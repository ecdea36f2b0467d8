"""The streamed conversion (issue 15): ``convert`` writes by blocks the bytes it writes in memory.

Each case converts twice in this process, streamed and with ``C1SURF_STREAM=0``
(the in-memory path every option that needs the whole surface takes), and
compares the files byte for byte: every streamed mesh format
(``MESH_WRITERS.streamed()``) and patch format (``PATCH_WRITERS.streamed()``),
at the default block sizes and with every block size forced tiny (the product
blocks of A2/A3, the tessellation's vertex and grid blocks, the patch cache,
the patch files' blocks), so that blocks cut through holes, groups and the
three vertex ranges (corners, edges, interiors).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf import resources
from c1surf.cli import convert as convert_module
from c1surf.cli.main import main
from c1surf.construction import patch_blocks
from c1surf.construction.stencils import layout
from c1surf.construction.surface import Surface
from c1surf.evaluation import tessellate
from c1surf.evaluation.stream import StreamedTessellation, UndefinedNormals, welded
from c1surf.io.meshes.read import read_mesh
from c1surf.io.patches import json_patches, npz
from c1surf.io.registry import MESH_WRITERS, PATCH_WRITERS

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = sorted((ROOT / "sample_meshes").glob("*.obj"))
SHARED = ROOT.parent / "shared" / "meshes"
CORPUS = ["spot/spot_control_mesh.obj", "opensubdiv/catmark_cube_creases1.obj", "pmp-library/hole_capsule.obj",
          "pmp-library/fandisk_quads.obj", "polyhedra-viewer/snub-cube.obj"]


@pytest.fixture
def tiny_blocks(monkeypatch):
    """Every block size of the construction and the tessellation at a few items."""
    monkeypatch.setattr(layout, "_BLOCK_POINTS", 40)
    monkeypatch.setattr(layout, "_THREAD_POINTS", 200)
    monkeypatch.setattr(tessellate, "_BLOCK_SAMPLES", 37)
    monkeypatch.setattr(tessellate, "_GRID_BLOCK_SAMPLES", 50)
    monkeypatch.setattr(patch_blocks, "DEFAULT_CACHE_BYTES", 1 << 12)  # a few blocks: evicted and made again
    monkeypatch.setattr(json_patches, "_STREAM_BLOCK", 7)
    monkeypatch.setattr(npz, "_STREAM_BLOCK", 5)
    # the corners' table made 47 rows at a time: two passes or more on every mesh here (the tetrahedron's 50
    # corners at -r 2); 13 rows made the fandisk's 12,200 corners 941 passes, 2 of this file's 5 minutes
    monkeypatch.setattr(welded, "CORNER_TABLE_BYTES", 48 * 47)


def _convert(monkeypatch, tmp_path: Path, mesh: Path, name: str, stream: bool, *options, patches=()) -> list:
    """The bytes of the mesh ``name`` and of each patch file (suffixes ``patches``) one conversion writes."""
    monkeypatch.setenv("C1SURF_STREAM", "1" if stream else "0")
    out = tmp_path / name
    paths = [out.with_name(f"{out.stem}-patches{suffix}") for suffix in patches]
    result = CliRunner().invoke(main, ["convert", str(mesh), "-o", str(out), "-q", *options,
                                       *(arg for path in paths for arg in ("--patches", str(path)))])
    assert result.exit_code == 0, result.output
    return [path.read_bytes() for path in (out, *paths)] if patches else out.read_bytes()


def _same_bytes(monkeypatch, tmp_path: Path, mesh: Path, suffix: str, *options, patches=()) -> None:
    streamed = _convert(monkeypatch, tmp_path, mesh, "streamed" + suffix, True, *options, patches=patches)
    whole = _convert(monkeypatch, tmp_path, mesh, "whole" + suffix, False, *options, patches=patches)
    if not patches:
        streamed, whole = [streamed], [whole]
    assert len(streamed) == len(whole) == 1 + len(patches)
    for name, a, b in zip([suffix, *patches], streamed, whole):
        assert a == b, f"{mesh.name} {options}: the streamed {name} file differs from the in-memory one"


def _shared(name: str) -> Path:
    path = SHARED / name
    if not path.exists():
        pytest.skip(f"{path} is not here")
    return path


@pytest.mark.parametrize("mesh", SAMPLES, ids=lambda p: p.stem)
@pytest.mark.parametrize("suffix", MESH_WRITERS.streamed())
def test_sample_meshes_stream_the_in_memory_bytes(monkeypatch, tmp_path, mesh, suffix):
    for options in (["-r", "2"], ["-r", "3", "--float32"], []):
        _same_bytes(monkeypatch, tmp_path, mesh, suffix, *options)


@pytest.mark.parametrize("mesh", SAMPLES, ids=lambda p: p.stem)
@pytest.mark.parametrize("suffix", MESH_WRITERS.streamed())
def test_sample_meshes_stream_the_in_memory_bytes_in_tiny_blocks(monkeypatch, tmp_path, tiny_blocks, mesh, suffix):
    for options in (["-r", "2"], ["-r", "4"]):
        _same_bytes(monkeypatch, tmp_path, mesh, suffix, *options)


@pytest.mark.parametrize("mesh", SAMPLES, ids=lambda p: p.stem)
@pytest.mark.parametrize("tiny", [False, True], ids=["default blocks", "tiny blocks"])
def test_patch_files_stream_the_in_memory_bytes(monkeypatch, tmp_path, request, mesh, tiny):
    """A mesh and every patch format written by blocks in one conversion: the in-memory files, byte for byte."""
    if tiny:
        request.getfixturevalue("tiny_blocks")
    _same_bytes(monkeypatch, tmp_path, mesh, ".ply", "-r", "3", patches=PATCH_WRITERS.streamed())
    _same_bytes(monkeypatch, tmp_path, mesh, ".stl", "-r", "2", "--no-merge", patches=PATCH_WRITERS.streamed()[::-1])


@pytest.mark.parametrize("name", CORPUS)
@pytest.mark.parametrize("tiny", [False, True], ids=["default blocks", "tiny blocks"])
def test_corpus_meshes_stream_the_in_memory_bytes(monkeypatch, tmp_path, request, name, tiny):
    """Open meshes (kept patches only), creases, a mesh of many holes, a larger mesh."""
    if tiny:
        request.getfixturevalue("tiny_blocks")
    for suffix in MESH_WRITERS.streamed():
        _same_bytes(monkeypatch, tmp_path, _shared(name), suffix, "-r", "3")
        if not tiny:
            _same_bytes(monkeypatch, tmp_path, _shared(name), suffix, "--blend", "0.3")
    _same_bytes(monkeypatch, tmp_path, _shared(name), ".ply", "-r", "2", patches=PATCH_WRITERS.streamed())


@pytest.mark.parametrize("suffix", MESH_WRITERS.streamed())
def test_a_sample_without_normal_is_written_in_memory_with_the_same_bytes(monkeypatch, tmp_path, suffix):
    """Blend 0: degenerate patch points (no normal) take their neighbours', which needs the whole mesh; STL
    stores no vertex normals and streams anyway."""
    mesh = ROOT / "sample_meshes" / "cube.obj"
    m = read_mesh(mesh)
    surface = Surface(m.face_sizes, m.face_vertices, m.points, convert_module.SurfaceOptions(blend=0.0),
                      lazy_patches=True)
    adjacency = tessellate.patch_adjacency(surface.refined, surface.frames)
    with pytest.raises(UndefinedNormals):
        for _ in StreamedTessellation(surface.patch_source(), adjacency, 4).vertex_blocks():
            pass
    made = _spy_patch_arrays(monkeypatch)
    _same_bytes(monkeypatch, tmp_path, mesh, suffix, "--blend", "0", "-r", "4")
    assert sum(made) == (1 if suffix == ".stl" else 2)  # made by the in-memory conversion, and the streamed one's fallback


def _spy_patch_arrays(monkeypatch) -> list:
    """A list that gets, each time a Surface makes its patch arrays, whether they were made then; and True
    each time a PatchSource makes them all at once (the streamed conversion's fallback, which keeps no Surface)."""
    made = []
    original, whole = Surface._patch_arrays, patch_blocks.PatchSource.arrays

    def spy(self):
        made.append(self._patches is None)
        return original(self)

    def spy_whole(self):
        made.append(True)
        return whole(self)

    monkeypatch.setattr(Surface, "_patch_arrays", spy)
    monkeypatch.setattr(patch_blocks.PatchSource, "arrays", spy_whole)
    return made


def test_options_that_need_the_whole_surface_do_not_stream(monkeypatch):
    monkeypatch.delenv("C1SURF_STREAM", raising=False)
    assert convert_module.streams(".ply", [], False, False)
    assert convert_module.streams(".ply", ["p.json", "p.NPZ"], False, False)  # patch files written by blocks
    assert convert_module.streams(".ply", ["p.json"], False, False, merge=False)
    assert not convert_module.streams(".ply", ["p.json"], False, False, merge=True)  # merged pieces: the whole surface
    assert not convert_module.streams(".ply", ["p.json", "p.igs"], False, False)  # IGES, STEP: written whole
    assert not convert_module.streams(".ply", ["p.step"], False, False)
    assert convert_module.streams(".ply", [], False, False, merge=True)  # no patch file to merge
    assert not convert_module.streams(".ply", [], True, False)
    assert not convert_module.streams(".ply", [], False, True)
    assert not convert_module.streams(".off", [], False, False)  # written whole (through trimesh)
    for suffix in (".obj", ".stl", ".glb"):
        assert convert_module.streams(suffix, [], False, False)
    monkeypatch.setenv("C1SURF_STREAM", "0")
    assert not convert_module.streams(".ply", [], False, False)


@pytest.mark.parametrize("suffix", MESH_WRITERS.streamed())
def test_a_streamed_conversion_builds_no_patch_arrays(monkeypatch, tmp_path, suffix):
    """The surface the streamed path builds never makes its (Nq, 3, 3, d) / (Nc, 4, 4, d) arrays."""
    made = _spy_patch_arrays(monkeypatch)
    _convert(monkeypatch, tmp_path, ROOT / "sample_meshes" / "twisted.obj", "t" + suffix, True,
             patches=PATCH_WRITERS.streamed())
    assert not made
    _convert(monkeypatch, tmp_path, ROOT / "sample_meshes" / "twisted.obj", "t" + suffix, False)
    assert made


def test_streamed_counts_match_the_file(monkeypatch, tmp_path):
    data = _convert(monkeypatch, tmp_path, ROOT / "sample_meshes" / "torus.obj", "t.ply", True, "-r", "5")
    header = data[: data.index(b"end_header")].decode().splitlines()
    vertices = int(next(line for line in header if line.startswith("element vertex")).split()[-1])
    faces = int(next(line for line in header if line.startswith("element face")).split()[-1])
    body = len(data) - data.index(b"end_header") - len(b"end_header\n")
    assert body == vertices * 48 + faces * 13
    assert np.isfinite(np.frombuffer(data[-body:][: vertices * 48], dtype="<f8")).all()


def test_a_streamed_output_is_refused_on_memory_per_patch_and_on_disk(monkeypatch, tmp_path):
    """No whole-tessellation memory guard: one patch's sample matrices must fit, and the file on the disk."""
    monkeypatch.delenv("C1SURF_STREAM", raising=False)
    mesh = ROOT / "sample_meshes" / "cube.obj"
    runner = CliRunner()
    result = runner.invoke(main, ["convert", str(mesh), "-o", str(tmp_path / "o.ply"), "-q", "-r", "100000"])
    assert result.exit_code == 1 and "for one patch" in result.output and "--force" in result.output
    monkeypatch.setattr(resources.shutil, "disk_usage", lambda folder: type("U", (), {"free": 10_000})())
    result = runner.invoke(main, ["convert", str(mesh), "-o", str(tmp_path / "o.ply"), "-q", "-r", "3"])
    assert result.exit_code == 1 and "MiB but only" in result.output
    assert not list(tmp_path.iterdir())  # nothing written, no temporary file left


def test_a_rational_surface_is_written_in_memory_with_its_weights(monkeypatch, tmp_path):
    """Vertex weights (A2a) make rational patches: streams() says yes, the surface says no (written whole)."""
    lines = (ROOT / "sample_meshes" / "cube.obj").read_text().splitlines()
    first = next(k for k, line in enumerate(lines) if line.startswith("v "))
    lines[first] += " 2.0"
    mesh = tmp_path / "weighted.obj"
    mesh.write_text("\n".join(lines) + "\n")
    made = _spy_patch_arrays(monkeypatch)
    _same_bytes(monkeypatch, tmp_path, mesh, ".obj", "-r", "3", patches=PATCH_WRITERS.streamed())
    assert sum(made) == 2  # both conversions made the patch arrays
    assert b'"weights"' in (tmp_path / "streamed-patches.json").read_bytes()
