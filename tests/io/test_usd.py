"""USD in (issue 41): ``UsdGeom.Mesh`` prims written by usd-core's own API, their creases, corners and holes read as
OpenSubdiv's OBJ ``t`` lines are (the same surface: ``c1surf diff`` exit 0), several meshes, transforms, bad input
as one line, and the line saying what to install without usd-core."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.io.errors import MeshInputError
from c1surf.io.meshes.obj import read_obj
from c1surf.io.meshes.read import read_mesh
from c1surf.io.meshes.usd.stage import UsdReadOptions

pxr = pytest.importorskip("pxr")  # the test extra installs usd-core
from pxr import Gf, Usd, UsdGeom  # noqa: E402

OPENSUBDIV = Path(__file__).resolve().parents[2].parent / "shared" / "meshes" / "opensubdiv"

# A cube, corners on the float32 grid, faces turning counter-clockwise from outside
CORNERS = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
QUADS = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
# the same tags both ways: a crease chain 0-1-2 (one sharpness for the chain), an edge 4-5, a corner, a hole
OBJ_TAGS = ["t crease 3/1/0 0 1 2 10.0", "t crease 2/1/0 4 5 2.5", "t corner 1/1/0 6 3.0", "t hole 1/0/0 1"]


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def define_mesh(stage, prim_path, points=CORNERS, quads=QUADS):
    mesh = UsdGeom.Mesh.Define(stage, prim_path)
    mesh.CreatePointsAttr([Gf.Vec3f(*p) for p in points])
    mesh.CreateFaceVertexCountsAttr([len(q) for q in quads])
    mesh.CreateFaceVertexIndicesAttr([i for q in quads for i in q])
    return mesh


def tagged_cube(path: Path, per_edge: bool = False) -> Path:
    """The cube with OBJ_TAGS' creases, corner and hole, written by usd-core (sharpness one a crease, or one an edge)."""
    stage = Usd.Stage.CreateNew(str(path))
    mesh = define_mesh(stage, "/World/cube")
    mesh.CreateCreaseIndicesAttr([0, 1, 2, 4, 5])
    mesh.CreateCreaseLengthsAttr([3, 2])
    mesh.CreateCreaseSharpnessesAttr([10.0, 10.0, 2.5] if per_edge else [10.0, 2.5])
    mesh.CreateCornerIndicesAttr([6])
    mesh.CreateCornerSharpnessesAttr([3.0])
    mesh.CreateHoleIndicesAttr([1])
    stage.Save()
    return path


def obj_cube(path: Path, tags=OBJ_TAGS) -> Path:
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in CORNERS)
                    + "".join("f " + " ".join(str(i + 1) for i in q) + "\n" for q in QUADS)
                    + "".join(line + "\n" for line in tags))
    return path


@pytest.mark.parametrize("per_edge", [False, True], ids=["sharpness per crease", "sharpness per edge"])
def test_usd_tags_are_the_obj_tags(tmp_path, per_edge):
    usd = read_mesh(tagged_cube(tmp_path / "cube.usda", per_edge))
    obj = read_obj(obj_cube(tmp_path / "cube.obj"))
    assert np.array_equal(usd.points, obj.points) and np.array_equal(usd.face_vertices, obj.face_vertices)
    for name in ("crease_edges", "crease_sharpness", "corner_vertices", "corner_sharpness", "hole_faces"):
        assert np.array_equal(getattr(usd.tags, name), getattr(obj.tags, name)), name
    assert usd.tags.crease_edges.tolist() == [[0, 1], [1, 2], [4, 5]] and usd.tags.interpolate_boundary is None
    assert usd.reader_notes == []


def test_a_usd_file_converts_to_the_surface_of_the_equivalent_obj(tmp_path):
    """The acceptance: usd-core's own file with creases, corners and a hole against the OBJ with OpenSubdiv tags."""
    for name, source in (("usd", tagged_cube(tmp_path / "cube.usdc")), ("obj", obj_cube(tmp_path / "cube.obj"))):
        result = run("convert", source, "-o", tmp_path / f"{name}.ply", "--patches", tmp_path / f"{name}.npz", "-r", 3)
        assert result.exit_code == 0, result.output
        assert "sharp-feature tags honoured: crease (3 edges), corner (1 vertex), hole (1 face)" in result.stderr
    result = run("diff", tmp_path / "usd.npz", tmp_path / "obj.npz")
    assert result.exit_code == 0, result.output
    usd, obj = np.load(tmp_path / "usd.npz"), np.load(tmp_path / "obj.npz")
    assert all(np.array_equal(usd[k], obj[k]) for k in obj.files if k != "header")
    assert run("diff", tmp_path / "cube.usdc", tmp_path / "cube.obj").exit_code == 0  # as meshes too
    from pxr import Sdf, UsdUtils

    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(tmp_path / "cube.usdc")), str(tmp_path / "cube.usdz"))
    assert run("diff", tmp_path / "cube.usdz", tmp_path / "cube.obj").exit_code == 0  # and packaged as .usdz


def opensubdiv_shapes():
    """Tagged OpenSubdiv shapes with creases, corners or holes (the shared corpus; skipped where it is absent)."""
    names = ["catmark_cube_creases1.obj", "catmark_cube_corner3.obj", "catmark_hole_test1.obj"]
    return [n for n in names if (OPENSUBDIV / n).exists()]


@pytest.mark.parametrize("name", opensubdiv_shapes())
def test_opensubdiv_shapes_written_as_usd_convert_as_their_obj(tmp_path, name):
    """Each shape's points and sharpness rounded to float32 (USD's point3f and float), written as OBJ text and by
    usd-core with the same tags (one crease of 2 vertices an edge): the same patches, ==."""
    from c1surf.io.meshes.obj_out import write_cage

    source = read_obj(OPENSUBDIV / name)
    tags = source.tags
    points = source.points.astype(np.float32).astype(np.float64)
    for name in ("crease_sharpness", "corner_sharpness"):
        setattr(tags, name, getattr(tags, name).astype(np.float32).astype(np.float64))
    write_cage(tmp_path / "shape.obj", points, source.face_sizes, source.face_vertices, tags)
    stage = Usd.Stage.CreateNew(str(tmp_path / "shape.usda"))
    offsets = np.concatenate(([0], np.cumsum(source.face_sizes)))
    quads = [source.face_vertices[a:b].tolist() for a, b in zip(offsets[:-1], offsets[1:])]
    mesh = define_mesh(stage, "/shape", points.tolist(), quads)
    if len(tags.crease_edges):
        mesh.CreateCreaseIndicesAttr(tags.crease_edges.ravel().tolist())
        mesh.CreateCreaseLengthsAttr([2] * len(tags.crease_edges))
        mesh.CreateCreaseSharpnessesAttr(tags.crease_sharpness.tolist())
    if len(tags.corner_vertices):
        mesh.CreateCornerIndicesAttr(tags.corner_vertices.tolist())
        mesh.CreateCornerSharpnessesAttr(tags.corner_sharpness.tolist())
    if len(tags.hole_faces):
        mesh.CreateHoleIndicesAttr(tags.hole_faces.tolist())
    stage.Save()
    for suffix in (".obj", ".usda"):
        result = run("convert", tmp_path / f"shape{suffix}", "-o", tmp_path / f"{suffix[1:]}.ply", "-r", 2,
                     "--patches", tmp_path / f"{suffix[1:]}.npz")
        assert result.exit_code == 0, result.output
    assert run("diff", tmp_path / "obj.npz", tmp_path / "usda.npz").exit_code == 0


def two_cubes(path: Path) -> Path:
    """Two cubes under Xforms, the second moved by (3, 0, 0) and turned left-handed (its faces reversed)."""
    stage = Usd.Stage.CreateNew(str(path))
    define_mesh(stage, "/World/a/cube")
    moved = UsdGeom.Xform.Define(stage, "/World/b")
    moved.AddTranslateOp().Set(Gf.Vec3d(3, 0, 0))
    left = define_mesh(stage, "/World/b/cube", quads=[q[::-1] for q in QUADS])
    left.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)
    UsdGeom.Camera.Define(stage, "/World/camera")
    stage.DefinePrim("/Looks/red", "Material")
    UsdGeom.PrimvarsAPI(left).CreatePrimvar("st", pxr.Sdf.ValueTypeNames.TexCoord2fArray).Set([(0, 0)] * 8)
    stage.Save()
    return path


def test_several_meshes_are_one_surface_by_default_each_where_the_scene_puts_it(tmp_path):
    mesh = read_mesh(two_cubes(tmp_path / "two.usda"))
    assert mesh.n_vertices == 16 and mesh.n_faces == 12
    assert mesh.group_names == ["/World/a/cube", "/World/b/cube"] and mesh.face_groups.tolist() == [0] * 6 + [1] * 6
    assert np.array_equal(mesh.points[8:], np.array(CORNERS) + [3, 0, 0])
    assert np.array_equal(mesh.face_vertices[24:], np.array(QUADS).ravel() + 8)  # left-handed: reversed back
    notes = " | ".join(mesh.reader_notes)
    assert "2 meshes read as one surface: /World/a/cube (6 faces), /World/b/cube (6 faces)" in notes
    assert "ignored 1 Camera, 1 Material prims" in notes and "primvars st" in notes
    local = read_mesh(tmp_path / "two.usda", usd=UsdReadOptions(world=False))
    assert np.array_equal(local.points[8:], CORNERS)


def test_one_mesh_by_its_prim_path(tmp_path):
    path = two_cubes(tmp_path / "two.usdc")
    one = read_mesh(path, usd=UsdReadOptions(prim="/World/b"))
    assert one.n_faces == 6 and np.array_equal(one.points, np.array(CORNERS) + [3, 0, 0]) and one.face_groups is None
    result = run("convert", path, "--usd-prim", "/World/b/cube", "--usd-local", "-o", tmp_path / "b.ply", "-q")
    assert result.exit_code == 0, result.output
    result = run("convert", path, "--usd-prim", "/World/nothing", "-o", tmp_path / "c.ply")
    assert result.exit_code == 1 and "its meshes: /World/a/cube, /World/b/cube" in result.stderr
    obj = obj_cube(tmp_path / "cube.obj", [])
    result = run("convert", obj, "--usd-prim", "/World", "-o", tmp_path / "d.ply")
    assert result.exit_code == 1 and "apply to .usd, .usda, .usdc and .usdz files only" in result.stderr


def stage_with(path: Path, edit) -> Path:
    stage = Usd.Stage.CreateNew(str(path))
    edit(define_mesh(stage, "/cube"), stage)
    stage.Save()
    return path


BAD = {
    "no points": (lambda m, s: m.GetPointsAttr().Clear(), "mesh /cube has no points"),
    "no faces": (lambda m, s: m.GetFaceVertexCountsAttr().Clear(), "mesh /cube has no faces"),
    "NaN point": (lambda m, s: m.GetPointsAttr().Set([Gf.Vec3f(float("nan"), 0, 0)] + [Gf.Vec3f(*p) for p in CORNERS[1:]]),
                  "mesh /cube: point 0 has a NaN or infinite coordinate"),
    "index out of range": (lambda m, s: m.GetFaceVertexIndicesAttr().Set([i for q in QUADS for i in q][:-1] + [8]),
                           "mesh /cube: face 5 refers to point 8 but the mesh has 8 points"),
    "counts do not sum": (lambda m, s: m.GetFaceVertexCountsAttr().Set([4, 4, 4, 4, 4, 3]),
                          "faceVertexCounts sum to 23 but faceVertexIndices has 24 entries"),
    "a face of 2": (lambda m, s: m.GetFaceVertexCountsAttr().Set([4, 4, 4, 4, 4, 2, 2]),
                    "mesh /cube: face 5 has 2 vertices"),
    "crease index out of range": (lambda m, s: (m.CreateCreaseIndicesAttr([0, 9]), m.CreateCreaseLengthsAttr([2]),
                                                m.CreateCreaseSharpnessesAttr([10.0])),
                                  "mesh /cube: crease names vertex 9 but the mesh has 8 vertices"),
    "crease not an edge": (lambda m, s: (m.CreateCreaseIndicesAttr([0, 6]), m.CreateCreaseLengthsAttr([2]),
                                         m.CreateCreaseSharpnessesAttr([10.0])), "crease pair 0 6 is not an edge"),
    "crease lengths do not sum": (lambda m, s: (m.CreateCreaseIndicesAttr([0, 1, 2]), m.CreateCreaseLengthsAttr([2]),
                                                m.CreateCreaseSharpnessesAttr([10.0])),
                                  "creaseLengths sum to 2 but creaseIndices has 3"),
    "crease sharpness count": (lambda m, s: (m.CreateCreaseIndicesAttr([0, 1, 2]), m.CreateCreaseLengthsAttr([3]),
                                             m.CreateCreaseSharpnessesAttr([1.0, 2.0, 3.0])),
                               "3 creaseSharpnesses for 1 creases of 2 edges"),
    "negative sharpness": (lambda m, s: (m.CreateCornerIndicesAttr([0]), m.CreateCornerSharpnessesAttr([-1.0])),
                           "corner sharpness -1 is not a number >= 0"),
    "corner count": (lambda m, s: (m.CreateCornerIndicesAttr([0, 1]), m.CreateCornerSharpnessesAttr([1.0])),
                     "2 cornerIndices but 1 cornerSharpnesses"),
    "hole out of range": (lambda m, s: m.CreateHoleIndicesAttr([6]), "hole names face 6 but the mesh has 6 faces"),
    "no mesh": (lambda m, s: (s.RemovePrim("/cube"), UsdGeom.Camera.Define(s, "/camera")),
                "no UsdGeom.Mesh prim in the stage (its prims: Camera)"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_usd_input_is_one_line_and_nothing_written(tmp_path, case):
    edit, message = BAD[case]
    path = stage_with(tmp_path / "bad.usda", edit)
    result = run("convert", path, "-o", tmp_path / "out.ply", "--patches", tmp_path / "out.npz")
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 1 and len(lines) == 1 and lines[0].startswith(f"c1surf: error: {path}: "), result.output
    assert message in lines[0] and "Traceback" not in result.output
    assert not (tmp_path / "out.ply").exists() and not (tmp_path / "out.npz").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.usda"]


@pytest.mark.parametrize("suffix, data", [(".usda", b"#usda 1.0\ndef Mesh \"a\" { int[] x = [1, \n"),
                                          (".usdc", b"PXR-USDC\0\0\0garbage"), (".usd", b"v 0 0 0\nf 1 2 3\n"),
                                          (".usdz", b"PK\3\4 not a zip")])
def test_a_file_that_is_not_usd_is_one_line(tmp_path, suffix, data):
    path = tmp_path / f"scene{suffix}"
    path.write_bytes(data)
    result = run("convert", path, "-o", tmp_path / "out.ply")
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 1 and len(lines) == 1, result.output
    assert re.match(rf"c1surf: error: {re.escape(str(path))}: not a USD file usd-core can read \(.+\): export", lines[0])


def test_without_usd_core_a_usd_path_gets_one_line_saying_what_to_install(tmp_path, monkeypatch):
    path = tagged_cube(tmp_path / "cube.usda")
    obj = obj_cube(tmp_path / "cube.obj")
    monkeypatch.setitem(sys.modules, "pxr", None)  # import pxr raises ImportError, as where usd-core is missing
    for args in (["convert", path, "-o", tmp_path / "a.ply"], ["convert", obj, "-o", tmp_path / "a.usd"],
                 ["fit", obj, "--faces", 8, "--cage", tmp_path / "cage.usda"]):
        result = run(*args)
        lines = result.stderr.strip().splitlines()
        assert result.exit_code == 1 and len(lines) == 1, result.output
        assert lines[0].endswith("USD files need usd-core: pip install 'c1surf[usd]' (or pip install usd-core)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cube.obj", "cube.usda"]
    with pytest.raises(MeshInputError, match="pip install"):
        read_mesh(path)


def test_an_animated_mesh_is_read_at_its_first_time_sample(tmp_path):
    def animate(mesh, stage):
        points = mesh.GetPointsAttr()
        points.Clear()
        for time, scale in ((1.0, 1.0), (2.0, 2.0)):
            points.Set([Gf.Vec3f(*(np.array(p) * scale)) for p in CORNERS], time)
        stage.SetStartTimeCode(1)
        stage.SetEndTimeCode(2)
    mesh = read_mesh(stage_with(tmp_path / "moving.usda", animate))
    assert np.array_equal(mesh.points, CORNERS)
    assert any("mesh /cube is animated: read at its first time sample" in n for n in mesh.reader_notes)


def test_usd_core_warnings_are_notes(tmp_path):
    """A reference to a missing file: usd-core's warning is one note, not a line of its own on stderr."""
    path = tmp_path / "scene.usda"
    stage = Usd.Stage.CreateNew(str(path))
    define_mesh(stage, "/cube")
    stage.DefinePrim("/other").GetReferences().AddReference("missing.usda")
    stage.Save()
    # a process of its own: usd-core would print from C++ straight to the file descriptor
    result = subprocess.run([sys.executable, "-m", "c1surf", "convert", str(path), "-o", str(tmp_path / "out.ply")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert all(line.startswith("c1surf: note: ") for line in result.stderr.strip().splitlines()), result.stderr
    assert f"c1surf: note: {path}: usd-core: In </other>: Could not open asset @missing.usda@ for reference " \
           f"introduced by @{path}@</other>." in result.stderr.splitlines()
