"""c1surf's own IGES (and STEP) output, read back by Open CASCADE.

For the sample meshes and a corpus subset: `convert --patches X.igs` gives a
file Open CASCADE loads without a failure or warning, one face per patch, and
the surfaces evaluate (through Open CASCADE) to c1surf's own points within
1e-9 of the bounding-box diagonal. The faces of a closed input sew into one
closed, valid shell bounding the same volume as the tessellation. STEP output
(`--patches X.step`, the optional `cad` extra) is checked the same way.

Open CASCADE comes from `cadquery-ocp` (test extra); without it these tests fail.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree
from click.testing import CliRunner

from c1surf.api import surface_from_file
from c1surf.cli.main import main
from c1surf.evaluation.bezier import evaluate_patches
from c1surf.evaluation.merge import merge_biquadratic

from conftest import ocp_shapes as shapes
from conftest import CLOSED_SAMPLES, SAMPLES, read_step, shared_mesh, surface_of

try:
    from OCP.BRep import BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepGProp import BRepGProp
    from OCP.BRepTools import BRepTools
    from OCP.GProp import GProp_GProps
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.IGESControl import IGESControl_Reader
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID
    from OCP.TopoDS import TopoDS

    OCP_ERROR = None
except ImportError as exc:  # pragma: no cover
    OCP_ERROR = exc

CORPUS = [
    "opensubdiv/catmark_torus_creases0.obj",
    "polyhedra-viewer/snub-dodecahedron.obj",
    "spot/spot_control_mesh.obj",
    "odedstein-meshes/fish_control_mesh.obj",
]
UV = np.array([0.0, 0.3, 0.5, 0.77, 1.0])  # 25 parameter pairs per patch, corners included
WORST = {}  # mesh -> largest relative disagreement, for the summary below


@pytest.fixture(autouse=True)
def need_ocp():
    if OCP_ERROR is not None:
        pytest.fail(f"Open CASCADE (OCP) is not importable ({OCP_ERROR}): pip install -e '.[test]'", pytrace=False)


def convert(tmp_path, mesh, suffix=".igs", *options):
    """One face per patch (--no-merge) unless the options say otherwise: these tests compare faces and patches."""
    out = tmp_path / f"surface{suffix}"
    merge = [] if "--merge" in options else ["--no-merge"]
    result = CliRunner().invoke(main, ["convert", str(mesh), "-o", str(tmp_path / "mesh.ply"), "-r", "2",
                                       "--patches", str(out), "-q", *merge, *map(str, options)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    return out


def read_iges(path):
    reader = IGESControl_Reader()
    assert reader.ReadFile(str(path)) == IFSelect_RetDone
    assert reader.WS().ModelCheckList().IsEmpty(False)  # no failure and no warning on any entity
    roots = reader.NbRootsForTransfer()
    assert reader.TransferRoots()
    return reader, reader.OneShape(), roots


def faces(shape) -> list:
    return [TopoDS.Face(f) for f in shapes(shape, TopAbs_FACE)]


def relative_disagreement(face_list, surface, scale=1.0, match=False) -> float:
    """Largest |OCC point - c1surf point| over UV x UV on every face, relative to the bbox diagonal.

    Faces are in patch order, or with ``match`` are first paired with patches
    by their centre points (a one-to-one pairing is required).
    """
    expected = np.concatenate([evaluate_patches(g, UV, UV) for g in (surface.biquadratic, surface.bicubic) if len(g)])
    pts = np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)])
    diagonal = float(np.linalg.norm(pts.max(0) - pts.min(0)))
    assert len(face_list) == len(expected)
    if match:
        centres = np.array([[c.X(), c.Y(), c.Z()] for c in (BRep_Tool.Surface_s(f).Value(0.5, 0.5) for f in face_list)])
        distance, order = cKDTree(expected[:, 2, 2] * scale).query(centres)
        assert np.array_equal(np.sort(order), np.arange(len(expected)))  # one face per patch
        expected = expected[order]
    worst = 0.0
    for face, want in zip(face_list, expected):
        geom = BRep_Tool.Surface_s(face)
        assert BRepTools.UVBounds_s(face) == pytest.approx((0.0, 1.0, 0.0, 1.0), abs=1e-12)
        got = np.array([[[p.X(), p.Y(), p.Z()] for p in (geom.Value(float(u), float(v)) for v in UV)] for u in UV])
        worst = max(worst, float(np.abs(got / scale - want).max()) / diagonal)
    return worst


@pytest.mark.parametrize("name", CLOSED_SAMPLES + CORPUS)
def test_iges_opens_in_open_cascade_and_agrees(tmp_path, name):
    mesh = SAMPLES / name if "/" not in name else shared_mesh(name)
    surface = surface_from_file(mesh)[0]  # what convert builds: the file's sharp-feature tags honoured
    reader, shape, roots = read_iges(convert(tmp_path, mesh))
    assert roots == 1  # the solid (type 186): CAD shows one object
    model = reader.IGESModel()
    types = [model.Entity(i).TypeNumber() for i in range(1, model.NbEntities() + 1)]
    assert types.count(128) == surface.n_patches and types.count(186) == 1  # one surface per face, one B-rep solid
    assert model.GlobalSection().IGESVersion() == 11 and model.GlobalSection().UnitName().ToCString() == "MM"
    face_list = faces(shape)
    assert len(face_list) == surface.n_patches
    for face, degree in zip(face_list, [2] * len(surface.biquadratic) + [3] * len(surface.bicubic)):
        geom = BRep_Tool.Surface_s(face)
        assert (geom.UDegree(), geom.VDegree()) == (degree, degree)
        assert not geom.IsURational() and not geom.IsVRational()
    WORST[name] = relative_disagreement(face_list, surface)
    assert WORST[name] <= 1e-9, WORST[name]


def test_iges_units_and_without_group(tmp_path):
    surface = surface_of(SAMPLES / "triangular_prism.obj")
    reader, shape, roots = read_iges(convert(tmp_path, SAMPLES / "triangular_prism.obj", ".iges", "--units", "in", "--no-group"))
    assert roots == surface.n_patches  # independent surfaces
    assert reader.IGESModel().GlobalSection().UnitFlag() == 1
    # Open CASCADE hands the model back in millimetres: 25.4 per inch
    assert relative_disagreement(faces(shape), surface, scale=25.4) <= 1e-9


def sew(face_list, surface):
    pts = surface.bicubic.reshape(-1, 3)
    sewing = BRepBuilderAPI_Sewing(1e-7 * float(np.linalg.norm(pts.max(0) - pts.min(0))))
    for face in face_list:
        sewing.Add(face)
    sewing.Perform()
    return sewing


def tessellated_volume(mesh_path) -> float:
    tess = trimesh.load(mesh_path, force="mesh", process=True)
    assert tess.is_watertight
    return float(tess.volume)


@pytest.mark.parametrize("name", ["cube.obj", "twisted.obj", "double_torus.obj", "hexagon_all_six_valent.obj"])
def test_iges_faces_of_a_closed_mesh_sew_into_one_closed_shell(tmp_path, name):
    surface = surface_of(SAMPLES / name)
    _, shape, _ = read_iges(convert(tmp_path, SAMPLES / name))
    sewing = sew(faces(shape), surface)
    sewn = sewing.SewedShape()
    assert sewing.NbFreeEdges() == 0 and sewing.NbMultipleEdges() == 0 and sewing.NbDegeneratedShapes() == 0
    shells = shapes(sewn, TopAbs_SHELL)
    assert len(shells) == 1
    shell = TopoDS.Shell(shells[0])
    assert BRep_Tool.IsClosed_s(shell)
    assert len(shapes(shell, TopAbs_FACE)) == surface.n_patches
    assert BRepCheck_Analyzer(sewn).IsValid()
    solid = BRepBuilderAPI_MakeSolid(shell).Solid()
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid, props)
    # the exact surface bounds (nearly) the volume of a fine tessellation of it
    fine = tmp_path / "fine.ply"
    CliRunner().invoke(main, ["convert", str(SAMPLES / name), "-o", str(fine), "-r", "12", "-q"], catch_exceptions=False)
    assert abs(props.Mass()) == pytest.approx(tessellated_volume(fine), rel=2e-3)


@pytest.mark.parametrize("name", ["twisted.obj", "torus.obj"])
def test_step_is_one_closed_solid_that_agrees(tmp_path, name):
    surface = surface_of(SAMPLES / name)
    path = convert(tmp_path, SAMPLES / name, ".step")
    shape = read_step(path)
    assert len(shapes(shape, TopAbs_SOLID)) == 1
    shells = shapes(shape, TopAbs_SHELL)
    assert len(shells) == 1 and BRep_Tool.IsClosed_s(TopoDS.Shell(shells[0]))
    face_list = faces(shape)
    assert len(face_list) == surface.n_patches
    assert BRepCheck_Analyzer(shape).IsValid()
    # every patch is one face, its surface exact (the STEP file orders faces by shell, not by patch)
    assert relative_disagreement(face_list, surface, match=True) <= 1e-9
    header = path.read_text()[:600]
    assert "FILE_NAME('surface.step','1970-01-01T00:00:00'" in header and "AUTOMOTIVE_DESIGN" in header


def test_step_is_reproducible(tmp_path):
    outputs = []
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        outputs.append(convert(tmp_path / name, SAMPLES / "cube.obj", ".step").read_bytes())
    assert outputs[0] == outputs[1]


def test_report_worst_disagreement():
    """Summary line (run with -s to see it): the largest IGES disagreement over all meshes above."""
    if WORST:
        name = max(WORST, key=WORST.get)
        print(f"\nlargest Open CASCADE vs c1surf disagreement: {WORST[name]:.2e} of the bbox diagonal ({name}); "
              f"over {len(WORST)} meshes")
        assert max(WORST.values()) <= 1e-9


@pytest.mark.parametrize("pieces", [False, True], ids=["strips", "pieces"])
@pytest.mark.parametrize("suffix", [".igs", ".step"])
def test_cad_files_are_packed_by_default(tmp_path, suffix, pieces):
    """Without --merge/--no-merge, IGES and STEP get the merged B-spline faces, cut into strips one span wide
    (min(m, n) for an m x n piece) or, with --cad-pieces, one face each; JSON keeps every patch."""
    mesh = SAMPLES / "twisted.obj"
    packed = tmp_path / f"packed{suffix}"
    js = tmp_path / "patches.json"
    result = CliRunner().invoke(main, ["convert", str(mesh), "-o", str(tmp_path / "m.ply"), "-r", "2", "-q",
                                       "--patches", str(packed), "--patches", str(js)] + ["--cad-pieces"] * pieces,
                                catch_exceptions=False)
    assert result.exit_code == 0, result.output
    surface = surface_from_file(mesh)[0]
    pieces_list = merge_biquadratic(surface)
    covered = sum(p.patches.size for p in pieces_list if pieces or p.patches.size > 1)
    faces_of_pieces = (len(pieces_list) if pieces
                       else sum(min(p.patches.shape) for p in pieces_list if p.patches.size > 1))
    expected_faces = faces_of_pieces + len(surface.biquadratic) - covered + len(surface.bicubic)
    assert expected_faces < surface.n_patches / (2 if pieces else 1.9)  # twisted: 165 strips, 320 patches
    if suffix == ".igs":
        face_list = faces(read_iges(packed)[1])
    else:
        face_list = faces(read_step(packed))
    assert len(face_list) == expected_faces
    assert "merged" not in json.loads(js.read_text())  # JSON: one entry per patch unless --merge
    report = CliRunner().invoke(main, ["check", str(packed)], catch_exceptions=False)
    assert "G1: yes" in report.stdout
