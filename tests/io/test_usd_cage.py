"""USD out (issue 41): ``fit --cage cage.usda`` rebuilds the fitted surface bit for bit through ``convert``, its
creases are USD crease arrays usd-core reads (and Blender imports, where ``bpy`` is installed), and ``-o x.usd``
tessellations carry points, normals, the patch of each triangle and the float64 points."""
from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from plyfile import PlyData

from c1surf.cli.main import main
from c1surf.construction.features import SharpFeatures
from c1surf.io.meshes.read import read_mesh
from c1surf.io.meshes.usd.write import write_usd_cage

pytest.importorskip("pxr")  # the test extra installs usd-core
from pxr import Gf, Usd, UsdGeom  # noqa: E402


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def convert_flags(cage: Path) -> list:
    """The ``convert`` options the cage's layer doc names (``c1surf convert NAME FLAGS gives ...``)."""
    stage = Usd.Stage.Open(str(cage))  # held: the layer lives as long as its stage
    doc = stage.GetRootLayer().documentation
    first = doc.splitlines()[0]
    assert first.startswith("c1surf fit cage: the fitted control mesh; c1surf convert "), doc
    words = shlex.split(first.split("c1surf convert ", 1)[1].split(" gives ")[0])
    assert words[0] == cage.name
    return words[1:]


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """A cylinder scan (512 triangles) fitted at 80 faces (90 control faces, 28 crease edges) with
    --crease-angle 45 (its rims: closed crease loops),
    the cage written as USD, then converted with the options its doc names. Returns the folder."""
    folder = tmp_path_factory.mktemp("usd_cage")
    scan = trimesh.creation.cylinder(radius=1.0, height=1.5, sections=32).subdivide()
    scan.export(folder / "cylinder.obj")
    result = run("fit", folder / "cylinder.obj", "--faces", 80, "--crease-angle", 45, "--iterations", 3, "-r", 4,
                 "--cage", folder / "cage.usda", "--patches", folder / "fit.npz", "-o", folder / "fit.usdc",
                 "--report", folder / "fit.json")
    assert result.exit_code == 0, result.output
    assert "--cage" not in result.stderr  # no note: the fit read its cage back and got its own bits
    result = run("convert", folder / "cage.usda", "-r", 4, "--patches", folder / "convert.npz",
                 "-o", folder / "convert.usdc", *convert_flags(folder / "cage.usda"))
    assert result.exit_code == 0, result.output
    assert "differ from c1surf's float64 copy" not in result.stderr
    return folder


def test_the_usd_cage_converts_to_the_fitted_surface_bit_for_bit(fitted):
    steps = json.loads((fitted / "fit.json").read_text())["patches"]["refinements"]
    assert steps == 1  # C0 rims at one Doo-Sabin step (issue 40)
    assert convert_flags(fitted / "cage.usda") == ["--refinements", str(steps)]
    fit, converted = np.load(fitted / "fit.npz"), np.load(fitted / "convert.npz")
    assert sorted(fit.files) == sorted(converted.files) and fit["biquadratic"].size and fit["bicubic"].size
    for key in fit.files:
        if key != "header":  # the header names the source file
            assert fit[key].dtype == converted[key].dtype and np.array_equal(fit[key], converted[key]), key
    assert (fitted / "fit.usdc").read_bytes() == (fitted / "convert.usdc").read_bytes()
    again = fitted / "tessellate.usdc"  # from the patch file: the same bytes, patch ids included
    assert run("tessellate", fitted / "fit.npz", "-r", 4, "-o", again, "-q").exit_code == 0
    assert again.read_bytes() == (fitted / "fit.usdc").read_bytes()


def test_usd_core_reads_the_cage_creases(fitted):
    stage = Usd.Stage.Open(str(fitted / "cage.usda"))
    mesh = UsdGeom.Mesh(stage.GetDefaultPrim())
    assert mesh and mesh.GetSubdivisionSchemeAttr().Get() == "catmullClark" and UsdGeom.GetStageUpAxis(stage) == "Z"
    counts, indices = np.array(mesh.GetFaceVertexCountsAttr().Get()), np.array(mesh.GetFaceVertexIndicesAttr().Get())
    creases = np.array(mesh.GetCreaseIndicesAttr().Get()).reshape(-1, 2)
    lengths, sharpness = np.array(mesh.GetCreaseLengthsAttr().Get()), np.array(mesh.GetCreaseSharpnessesAttr().Get())
    report = json.loads((fitted / "fit.json").read_text())["control_mesh"]
    assert len(counts) == report["faces"] and len(creases) == report["crease_edges"] >= 16
    assert np.all(lengths == 2) and np.all(sharpness == 10.0)
    # every crease is an edge of a face, and the creases close into loops (the cylinder's rims)
    offsets = np.concatenate(([0], np.cumsum(counts)))
    edges = {frozenset((int(f[k]), int(f[(k + 1) % len(f)]))) for f in np.split(indices, offsets[1:-1])
             for k in range(len(f))}
    assert all(frozenset(map(int, pair)) in edges for pair in creases)
    assert np.all(np.bincount(creases.ravel())[np.unique(creases)] == 2)
    # any reader sees the float points; c1surf's float64 copy rounds to them
    points = np.array(mesh.GetPointsAttr().Get())
    exact = np.array(UsdGeom.PrimvarsAPI(mesh).GetPrimvar("c1surf:points").Get())
    assert points.dtype == np.float32 and np.array_equal(exact.astype(np.float32), points)
    assert not np.array_equal(exact, points.astype(np.float64))  # the doubles carry more than the floats


def test_the_usd_tessellation_holds_points_normals_and_patches(fitted, tmp_path):
    result = run("convert", fitted / "cage.usda", "-r", 4, "-o", tmp_path / "s.usda", *convert_flags(fitted / "cage.usda"))
    assert result.exit_code == 0, result.output
    assert run("convert", fitted / "cage.usda", "-r", 4, "-o", tmp_path / "s.ply",
               *convert_flags(fitted / "cage.usda")).exit_code == 0
    vertex = PlyData.read(str(tmp_path / "s.ply"))["vertex"]
    ply_points = np.stack([vertex[c] for c in "xyz"], axis=1)
    stage = Usd.Stage.Open(str(tmp_path / "s.usda"))
    mesh = UsdGeom.Mesh(stage.GetDefaultPrim())
    assert mesh.GetSubdivisionSchemeAttr().Get() == "none"
    assert np.array_equal(np.array(mesh.GetPointsAttr().Get()), ply_points.astype(np.float32))
    primvars = UsdGeom.PrimvarsAPI(mesh)
    assert np.array_equal(np.array(primvars.GetPrimvar("c1surf:points").Get()), ply_points)  # every bit
    normals = np.array(mesh.GetNormalsAttr().Get())
    assert mesh.GetNormalsInterpolation() == "vertex" and np.allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-6)
    patch = primvars.GetPrimvar("c1surf:patch")
    n_patches = len(np.load(fitted / "fit.npz")["source_kind"])
    assert patch.GetInterpolation() == "uniform"
    assert np.array_equal(np.array(patch.Get()), np.repeat(np.arange(n_patches), 2 * 3 ** 2))
    assert np.all(np.array(mesh.GetFaceVertexCountsAttr().Get()) == 3)
    floats = tmp_path / "f.usd"
    assert run("convert", fitted / "cage.usda", "-r", 4, "-o", floats, "--float32", "-q").exit_code == 0
    stage = Usd.Stage.Open(str(floats))
    assert not UsdGeom.PrimvarsAPI(UsdGeom.Mesh(stage.GetDefaultPrim())).HasPrimvar("c1surf:points")


def test_write_usd_cage_round_trips_every_bit_and_every_tag(tmp_path):
    rng = np.random.default_rng(5)
    points = rng.normal(size=(8, 3)) * 10.0 ** rng.integers(-12, 12, size=(8, 3))
    points[0] = [1 / 3, -0.0, 5e-324]
    sizes, corners = np.array([4, 3, 5]), np.array([0, 1, 2, 3, 3, 2, 4, 4, 2, 5, 6, 7])
    features = SharpFeatures(crease_edges=[[0, 1], [2, 3]], crease_sharpness=[10.0, 2.0 / 3.0],
                             corner_vertices=[7], corner_sharpness=[0.1], hole_faces=[1])
    for suffix in (".usda", ".usdc"):
        path = tmp_path / f"cage{suffix}"
        write_usd_cage(path, points, sizes, corners, features, ["one", "two"])
        mesh = read_mesh(path)
        assert np.array_equal(mesh.points.view(np.int64), points.view(np.int64))  # -0.0 and the subnormal too
        assert np.array_equal(mesh.face_sizes, sizes) and np.array_equal(mesh.face_vertices, corners)
        tags = mesh.tags
        assert np.array_equal(tags.crease_edges, features.crease_edges)
        assert np.array_equal(tags.crease_sharpness, features.crease_sharpness)  # 2/3 in float64, not float32
        assert np.array_equal(tags.corner_vertices, [7]) and np.array_equal(tags.corner_sharpness, [0.1])
        assert np.array_equal(tags.hole_faces, [1]) and mesh.reader_notes == []
        stage = Usd.Stage.Open(str(path))
        assert stage.GetRootLayer().documentation == "one\ntwo"


def test_a_point_moved_in_another_tool_is_read_from_the_float_points(tmp_path):
    path = tmp_path / "cage.usda"
    points = np.array([[0.1, 0.2, 0.3], [1.1, 0.2, 0.3], [1.1, 1.2, 0.3], [0.1, 1.2, 0.3]])
    write_usd_cage(path, points, [4], [0, 1, 2, 3])
    stage = Usd.Stage.Open(str(path))
    attr = UsdGeom.Mesh(stage.GetDefaultPrim()).GetPointsAttr()
    moved = list(attr.Get())
    moved[2] = Gf.Vec3f(2.0, 2.0, 0.5)
    attr.Set(moved)
    stage.Save()
    mesh = read_mesh(path)
    assert np.array_equal(mesh.points[[0, 1, 3]], points[[0, 1, 3]]) and np.array_equal(mesh.points[2], [2, 2, 0.5])
    assert any("1 of 4 points differ from c1surf's float64 copy" in note for note in mesh.reader_notes)


BLENDER_IMPORT = """
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[-1])
mesh = [o for o in bpy.context.scene.objects if o.type == "MESH"][0].data
crease = mesh.attributes.get("crease_edge")
values = [0.0] * len(mesh.edges)
if crease is not None:
    crease.data.foreach_get("value", values)
print("C1SURF", len(mesh.vertices), len(mesh.polygons), sum(v == 1.0 for v in values), sum(v > 0 for v in values))
"""


def test_blender_imports_every_crease_of_the_usd_cage(fitted):
    """Where ``bpy`` (Blender as a module) is installed: the cage imports with every vertex, face and crease
    (``crease_edge`` 1.0 for sharpness 10). Run in its own process: bpy pins its own numpy."""
    python = [os.environ.get("C1SURF_BPY_PYTHON") or sys.executable]
    probe = subprocess.run([*python, "-c", "import bpy"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("bpy is not installed (pip install bpy, or C1SURF_BPY_PYTHON=a Python that has it)")
    done = subprocess.run([*python, "-c", BLENDER_IMPORT, str(fitted / "cage.usda")], capture_output=True, text=True,
                          timeout=300)
    line = next(l for l in done.stdout.splitlines() if l.startswith("C1SURF "))
    vertices, faces, sharp, creased = map(int, line.split()[1:])
    stage = Usd.Stage.Open(str(fitted / "cage.usda"))
    mesh = UsdGeom.Mesh(stage.GetDefaultPrim())
    n_creases = len(mesh.GetCreaseLengthsAttr().Get())
    assert (vertices, faces) == (len(mesh.GetPointsAttr().Get()), len(mesh.GetFaceVertexCountsAttr().Get()))
    assert sharp == creased == n_creases
