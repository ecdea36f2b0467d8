"""The outputs' last line of defence and hostile output paths (issue 30): every writer refuses NaN and infinity
before the rename (a bug becomes a one-line refusal naming the output, never a file), the temporary name fits
any legal output name, a symlinked output keeps its kind or is refused, batch never overwrites its inputs."""
from __future__ import annotations

import os
import shutil

import numpy as np
import pytest

from c1surf.io.atomic import atomic_output
from c1surf.io.errors import OutputError
from c1surf.io.finite import NonFiniteOutput, refuse_non_finite
from c1surf.io.meshes.write import TriangleMesh, write_mesh, write_streamed_mesh
from c1surf.io.patches.formats import write_patch_set, write_patch_stream

from hostile_cases import SAMPLES, assert_outcome, run

TRIANGLE = (np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))


def _mesh(bad_points=False, bad_normals=False, big=False) -> TriangleMesh:
    points, triangles = TRIANGLE[0].copy(), TRIANGLE[1]
    normals = np.tile([0.0, 0.0, 1.0], (3, 1))
    if bad_points:
        points[1, 2] = np.nan
    if bad_normals:
        normals[2, 0] = np.inf
    if big:
        points[2, 0] = 1e300  # finite, beyond float32
    return TriangleMesh(points, triangles, normals)


class _Blocks:
    """A streamed tessellation of one triangle (``evaluation.stream`` duck type), NaN in its second block."""

    n_vertices, n_triangles, dim = 3, 1, 3

    def __init__(self, bad: bool):
        self.bad = bad

    def vertex_blocks(self):
        points, _ = TRIANGLE
        normals = np.tile([0.0, 0.0, 1.0], (3, 1))
        yield points[:2], normals[:2]
        last = points[2:].copy()
        if self.bad:
            last[0, 1] = np.nan
        yield last, normals[2:]

    def triangle_blocks(self):
        yield TRIANGLE[1]

    def triangle_point_blocks(self):
        corners = TRIANGLE[0][TRIANGLE[1]].copy()
        if self.bad:
            corners[0, 1, 1] = np.nan
        yield corners


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".off", ".stl", ".glb"])
@pytest.mark.parametrize("how", ["points", "normals", "float32"])
def test_mesh_writers_refuse_and_leave_nothing(tmp_path, suffix, how):
    mesh = _mesh(bad_points=how == "points", bad_normals=how == "normals", big=how == "float32")
    float32 = how == "float32"
    target = tmp_path / f"out{suffix}"
    if how == "float32" and suffix in (".obj", ".off"):
        pytest.skip("text formats hold any double")
    with pytest.raises(NonFiniteOutput) as info:
        with atomic_output(target) as tmp:
            write_mesh(tmp, mesh, suffix, float32=float32)
    assert info.value.path == str(target) and "nothing was written" in str(info.value)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".stl", ".glb"])
def test_streamed_mesh_writers_refuse_per_block(tmp_path, suffix):
    target = tmp_path / f"out{suffix}"
    with pytest.raises(NonFiniteOutput):
        with atomic_output(target) as tmp:
            write_streamed_mesh(tmp, _Blocks(bad=True), suffix)
    assert os.listdir(tmp_path) == []
    with atomic_output(target) as tmp:  # the same blocks without NaN: written
        write_streamed_mesh(tmp, _Blocks(bad=False), suffix)
    assert target.is_file()


@pytest.mark.parametrize("suffix", [".json", ".npz", ".igs", ".step"])
def test_patch_writers_refuse(tmp_path, suffix):
    from c1surf.io.patches.formats import load_patch_set

    source = tmp_path / "good.json"
    assert run("convert", SAMPLES / "cube.obj", "-o", tmp_path / "c.ply", "-r", "2", "--patches", source).exit_code == 0
    patches = load_patch_set(source)
    patches.groups[1] = patches.groups[1].copy()
    patches.groups[1][3, 1, 2, 0] = np.nan
    target = tmp_path / f"out{suffix}"
    with pytest.raises(OutputError) as info:
        with atomic_output(target) as tmp:
            write_patch_set(tmp, patches, suffix)
    assert info.value.path == str(target)
    assert sorted(os.listdir(tmp_path)) == ["c.ply", "good.json"]


def test_exr_refuses_nan_but_keeps_the_background_depth(tmp_path):
    from c1surf.io.images.exr import write_exr

    depth = np.array([[1.0, np.inf], [2.0, 3.0]])
    write_exr(tmp_path / "ok.exr", {"Z": depth, "R": np.zeros((2, 2))})
    with pytest.raises(NonFiniteOutput):
        write_exr(tmp_path / "bad.exr", {"Z": depth, "R": np.array([[0.0, np.nan], [0.0, 0.0]])})
    with pytest.raises(NonFiniteOutput):
        write_exr(tmp_path / "bad.exr", {"Z": -depth, "R": np.zeros((2, 2))})


def test_refuse_non_finite_counts_and_passes_integers():
    refuse_non_finite(np.arange(5), "ids")
    refuse_non_finite(None, "nothing")
    refuse_non_finite(np.zeros((0, 3)), "nothing")
    with pytest.raises(NonFiniteOutput, match="2 of the 6 normals"):
        refuse_non_finite(np.array([[0, np.nan, 1], [np.inf, 0, 0]]), "normals")
    with pytest.raises(NonFiniteOutput, match="float32"):
        refuse_non_finite(np.array([1e39]), "points", dtype=np.float32)


def test_long_output_names(tmp_path):
    """A 250-byte output name (legal) is written: the temporary name drops the start of it, not the suffix."""
    for length in (200, 240, 251):
        out = tmp_path / ("a" * (length - 4) + ".ply")
        result = run("convert", SAMPLES / "cube.obj", "-o", out, "-r", "2", "-q")
        assert_outcome(result, tmp_path, [out])
        assert result.exit_code == 0 and out.is_file()
        out.unlink()


def test_symlinked_outputs(tmp_path):
    real = tmp_path / "real.ply"
    real.write_text("old")
    link = tmp_path / "link.ply"
    link.symlink_to(real)
    result = run("convert", SAMPLES / "cube.obj", "-o", link, "-r", "2", "-q")
    assert result.exit_code == 0 and link.is_symlink() and real.stat().st_size > 100
    device = tmp_path / "null.ply"
    device.symlink_to(os.devnull)
    before = os.stat(os.devnull)
    result = run("convert", SAMPLES / "cube.obj", "-o", device, "-r", "2", "-q")
    assert_outcome(result, tmp_path, [], must_refuse=True)
    assert "character device" in result.stderr and device.is_symlink()
    after = os.stat(os.devnull)
    assert (after.st_mode, after.st_rdev) == (before.st_mode, before.st_rdev)


def test_fifo_output_refused(tmp_path):
    fifo = tmp_path / "pipe.ply"
    os.mkfifo(fifo)
    result = run("convert", SAMPLES / "cube.obj", "-o", fifo, "-r", "2", "-q")
    assert_outcome(result, tmp_path, [], must_refuse=True)
    assert "named pipe" in result.stderr


def test_batch_into_its_input_folder(tmp_path):
    """Refused when an output would be an input (same folder, same format); beside them in another format: fine."""
    for name in ("a.obj", "b.obj"):
        shutil.copy(SAMPLES / "cube.obj", tmp_path / name)
    result = run("batch", str(tmp_path / "*.obj"), "-o", tmp_path, "-f", ".obj", "-q")
    assert_outcome(result, tmp_path, [], refused_status=(2,), must_refuse=True)
    assert "would overwrite the input" in result.stderr
    assert (tmp_path / "a.obj").read_text() == (SAMPLES / "cube.obj").read_text()
    result = run("batch", str(tmp_path / "*.obj"), "-o", tmp_path, "-r", "2", "-q")
    assert result.exit_code == 0 and (tmp_path / "a.ply").is_file() and (tmp_path / "b.ply").is_file()


@pytest.mark.parametrize("patches", [".json", ".npz"])
def test_streamed_patch_writers_refuse_per_block(tmp_path, patches):
    class Stream:
        header = {"format": "c1surf-patches"}
        counts = (1, 0)
        n_patches = 1
        INTEGERS = ()

        def blocks(self, kind, size):
            if kind == 0:
                yield 0, np.full((1, 3, 3, 3), np.nan)

        def integers(self, name, a, z):
            return np.zeros((z - a, 4), dtype=np.int64)

        def source_dicts(self, a, z):
            return [{}] * (z - a)

    target = tmp_path / f"out{patches}"
    with pytest.raises(NonFiniteOutput):
        with atomic_output(target) as tmp:
            write_patch_stream(tmp, Stream(), patches)
    assert os.listdir(tmp_path) == []


def test_obj_beyond_fixed_point_is_refused_not_a_traceback(tmp_path):
    """OBJ numbers are fixed point from int64 digits: coordinates of 1e20 are refused with what to write instead."""
    points = TRIANGLE[0] * 1e20
    target = tmp_path / "out.obj"
    with pytest.raises(OutputError, match="write .ply"):
        with atomic_output(target) as tmp:
            write_mesh(tmp, TriangleMesh(points, TRIANGLE[1], None), ".obj")
    assert os.listdir(tmp_path) == []
    source = tmp_path / "big.obj"
    source.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist()) + "f 1 2 3\n")
    result = run("convert", source, "-o", target, "-r", "2", "-q")
    assert_outcome(result, tmp_path, [target], must_refuse=True)
    result = run("convert", source, "-o", tmp_path / "out.ply", "-r", "2", "-q")  # doubles hold it
    assert_outcome(result, tmp_path, [tmp_path / "out.ply"])
    assert result.exit_code == 0, result.stderr
