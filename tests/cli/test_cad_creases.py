"""A CAD-like triangle mesh (a box with a filleted cylindrical boss, tests/cad_meshes.py) converted with
``--crease-angle 40 --exact-creases``: C0 along exactly the detected feature lines, G1 elsewhere, one
valid closed solid in STEP."""
from __future__ import annotations

import re

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.mesh.feature_edges import feature_edges

from cad_meshes import boss_box, write_obj
from conftest import ocp_shapes, read_step


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module", params=[(4, 0)], ids=["m4"])
def converted(request, tmp_path_factory):
    m, seed = request.param
    d = tmp_path_factory.mktemp(f"boss{m}")
    mesh = boss_box(m, seed)
    write_obj(d / "part.obj", *mesh)
    result = run("convert", d / "part.obj", "-o", d / "part.ply", "-r", 3, "--crease-angle", 40, "--exact-creases",
                 "--patches", d / "part.json", "--patches", d / "part.step", "--patches", d / "part.igs")
    assert result.exit_code == 0, result.output
    return d, mesh, m, result


def test_the_feature_lines_are_c0_seams_and_the_rest_is_g1(converted):
    d, (sizes, corners, points), m, result = converted
    detected = feature_edges(sizes, corners, points, 40.0)
    assert len(detected) == 12 * m + 4 * m  # the box's 12 edges and the boss's top rim
    assert f"C0 creases: {len(detected)} of {len(detected)} infinitely sharp crease edges are C0 seams" in result.stderr
    assert "merged" in result.stderr and "crease vertices" in result.stderr
    check = run("check", d / "part.json")
    assert check.exit_code == 0, check.output
    listed = re.search(r"crease edges: +(\d+) of (\d+) listed, max gap \S+ \((\S+) of the bounding box\)", check.output)
    # four pieces of crease curve along every crease edge (a pair of patch sides each), all listed and met
    assert listed[1] == listed[2] == str(4 * len(detected))
    assert float(listed[3]) <= 1e-12  # the gap, relative to the bounding box
    jump = re.search(r"max normal jump: +(\S+) rad", check.output)
    assert float(jump[1]) <= 1e-10  # every other shared side is G1
    assert "G1: yes" in check.output


def test_the_crease_sides_lie_on_the_detected_edges(converted):
    # every crease side runs along a box edge (two coordinates at the box's extremes) or along the
    # boss's top rim: the top plane, between the wall's radius and its polygon's smallest inradius (the
    # rim's vertices sit at the angles of points spaced evenly along the square: widest gap 2 atan(1/m);
    # the mesh's positions are rounded to 1e-10)
    from c1surf.api import surface_from_file
    from c1surf.evaluation.bezier import raise_degree
    from c1surf.evaluation.smoothness import side_frames

    d, _, m, _ = converted
    surface, _ = surface_from_file(d / "part.obj", crease_angle=40, exact_creases=True)
    cubic = np.concatenate([raise_degree(surface.biquadratic, 3, 3), surface.bicubic])
    sides = np.asarray(surface.crease_sides)
    assert len(sides) == 4 * (12 * m + 4 * m)
    points, _ = side_frames(cubic, sides.ravel(), np.linspace(0, 1, 5))
    points = points.reshape(-1, 3)
    x, y, z = np.abs(points[:, 0]), np.abs(points[:, 1]), points[:, 2]
    extremes = (np.abs(x - 1) <= 1e-12).astype(int) + (np.abs(y - 1) <= 1e-12) + (np.abs(z) <= 1e-12) + (np.abs(z + 0.6) <= 1e-12)
    radius = np.hypot(points[:, 0], points[:, 1])
    on_rim = (np.abs(z - 0.4) <= 1e-12) & (radius <= 0.45 + 1e-12) & (radius >= 0.45 * m / np.hypot(m, 1) - 1e-9)
    assert np.all((extremes >= 2) | on_rim), points[(extremes < 2) & ~on_rim][:5]
    assert on_rim.any() and (extremes >= 2).any()


def test_the_step_file_is_one_valid_closed_solid(converted):
    pytest.importorskip("OCP")
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.TopAbs import TopAbs_SOLID

    d, *_ = converted
    shape = read_step(d / "part.step")
    assert len(ocp_shapes(shape, TopAbs_SOLID)) == 1 and BRepCheck_Analyzer(shape).IsValid()


@pytest.mark.parametrize("suffix", [".step", ".igs"])
def test_check_of_a_cad_file_measures_the_edges_bending_more_than_the_crease_angle_as_creases(converted, suffix):
    # IGES and STEP files list no crease sides: without --crease-angle every crease is a normal jump (and a
    # note says what to pass); with it the edges bending more are measured for their gap, the rest for G1
    pytest.importorskip("OCP")
    d, (sizes, corners, points), *_ = converted
    path = d / f"part{suffix}"
    if suffix == ".igs":  # check's note, whichever CAD reader gave it the patches (the STEP file is 25 MB: 12 s a read)
        plain = run("check", path)
        assert plain.exit_code == 1 and "G1: NO" in plain.output
        assert "lists no crease sides" in plain.stderr and "--crease-angle" in plain.stderr
    check = run("check", path, "--crease-angle", 20, "--blend", 0.3)
    assert check.exit_code == 0, check.output
    found = re.search(r"crease edges: +(\d+) bending more than 20 degrees, max gap \S+ \((\S+) of the bounding box\)",
                      check.output)
    listed = re.search(r"crease edges: +(\d+) of", run("check", d / "part.json").output)
    assert found[1] == listed[1]  # the same pieces as the JSON file lists (the merged faces split back into patches)
    assert float(found[2]) <= 1e-12
    assert float(re.search(r"max normal jump: +(\S+) rad", check.output)[1]) <= 1e-10
    assert "--blend: used only when the input is a mesh" in check.stderr
    json_note = run("check", d / "part.json", "--crease-angle", 20)
    assert "lists its crease sides: --crease-angle is not used" in json_note.stderr


def test_the_fandisk_at_a_crease_angle_is_c0_along_its_feature_lines():
    # pmp-library's fandisk (a CAD part, 764 quads, no tags) at --crease-angle 40: every feature line a C0
    # seam, the 4 lines that fade out inside the surface too, up to their ends (darts: the dart's hole)
    from c1surf.api import check_surface, surface_from_file
    from conftest import shared_mesh

    surface, mesh = surface_from_file(shared_mesh("pmp-library/fandisk_quads.obj"), crease_angle=40)
    sheets = surface.topology.crease_sheets
    assert len(sheets.cut_edges) == 265 and len(sheets.kept_edges) == 0 and sheets.dart_vertex.size == 4
    assert len(mesh.sector_merge[3]) == 0
    report = check_surface(surface)
    assert report.crease_edges == len(surface.crease_sides) == 1060 and report.unpaired_crease_sides == 0
    assert report.relative_crease_gap <= 1e-12 and report.max_normal_jump <= 1e-10


@pytest.mark.parametrize("name", ["odedstein-meshes/plane_holes.obj", "opensubdiv/catmark_hole_test1.obj",
                                  "opensubdiv/catmark_fan.obj"])
def test_open_holed_and_non_manifold_meshes_at_a_crease_angle(name):
    # plane_holes (open, 27 boundary loops): an even hole at a boundary that no crease reaches keeps its own
    # perturbation (its ghost-layer points are no mirror partners: once 1.5e-3 rad); hole_test1: a crease
    # along a hole tag's rim has patches on one side only, a boundary side; catmark_fan: its fins are folded
    # at the non-manifold line's middle vertex (a corner there in the fins' sheets, so in the plate's too)
    from c1surf.api import check_surface, surface_from_file
    from conftest import shared_mesh

    surface, _ = surface_from_file(shared_mesh(name), crease_angle=40)
    assert surface.topology.crease_sheets is not None
    report = check_surface(surface)
    assert report.unpaired_crease_sides == 0 and report.crease_edges > 0
    assert report.relative_crease_gap <= 1e-12 and report.max_normal_jump <= 1e-10
