"""Edges in more than two faces cut into manifold sheets (mesh.creases.non_manifold) that meet along one
C0 crease: every sheet builds the same curve there, G1 inside each sheet; the patch files list the
pieces, check measures them side against side, STEP keeps every sheet."""
from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.api import check_surface, surface_from_file
from c1surf.cli.main import main
from c1surf.evaluation.adjacency import match_patch_sides
from c1surf.evaluation.bezier import raise_degree
from c1surf.evaluation.smoothness import side_frames
from c1surf.mesh.creases.non_manifold import split_non_manifold_edges

from conftest import ocp_shapes, read_step, shared_mesh

BOOK = [[0, 1, 2, 3], [1, 0, 4, 5], [0, 1, 6, 7]]  # three pages on the edge 0 - 1


def test_a_book_of_three_pages_becomes_three_sheets():
    sizes = np.array([4, 4, 4])
    split = split_non_manifold_edges(sizes, np.concatenate(BOOK), 8)
    assert split.edges.tolist() == [[0, 1]]
    faces = split.face_vertices.reshape(3, 4)
    # the spine's two vertices: one copy per page after the first; the other corners untouched
    source = split.vertex_source
    assert source[:8].tolist() == list(range(8)) and sorted(source[8:].tolist()) == [0, 0, 1, 1]
    spines = [tuple(f[:2]) for f in faces.tolist()]
    assert len({v for spine in spines for v in spine}) == 6  # no two pages share a spine vertex
    assert [sorted(source[list(spine)].tolist()) for spine in spines] == [[0, 1]] * 3
    assert faces[:, 2:].tolist() == [[2, 3], [4, 5], [6, 7]]
    assert split.corners.tolist() == [0, 1]  # the spine ends at both
    assert split_non_manifold_edges(np.array([4, 4]), np.concatenate(BOOK[:2]), 8) is None


def test_two_closed_surfaces_that_share_an_edge_stay_apart(tmp_path):
    # two cubes whose faces name the same two vertices for one edge (not welded: the file's own numbers):
    # each sheet holds the edge in two faces, so they only touch there: two closed cubes, no crease
    cube = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    first = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    second = [(1, -1, 0), (2, -1, 0), (2, 0, 0), (1, 0, 0), (1, -1, 1), (2, -1, 1), (2, 0, 1), (1, 0, 1)]
    points = first + [p for p in second if p not in first]
    number = {p: points.index(p) for p in points}
    faces = cube + [[number[second[i]] for i in f] for f in cube]
    path = tmp_path / "two_cubes.obj"
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in points) + "".join(
        "f " + " ".join(str(i + 1) for i in f) + "\n" for f in faces))
    surface, mesh = surface_from_file(path, weld=None)
    assert len(mesh.non_manifold_edges) == 1 and mesh.non_manifold_seams == 0
    report = check_surface(surface)
    assert report.boundary_edges == 0 and report.crease_edges == 0 and report.max_normal_jump <= 1e-10
    assert surface.n_patches == 2 * 96


def sheet_sides(surface):
    """(gap, k): the largest distance between the sides found in more than two patches (the sheets'
    common curves), sampled; k such sides."""
    groups = [surface.biquadratic, surface.bicubic]
    cubic = np.concatenate([raise_degree(surface.biquadratic, 3, 3), surface.bicubic])
    sides = match_patch_sides(groups, 1e-9 * 10)
    over = sides.overshared_sides
    labels = sides.edges.ravel()[over]
    forward = sides.forward.ravel()[over]
    t = np.linspace(0, 1, 9)
    worst = 0.0
    for label in np.unique(labels):
        members = over[labels == label]
        x0, _ = side_frames(cubic, members[:1], t)
        for m, f in zip(members[1:], forward[labels == label][1:]):
            x, _ = side_frames(cubic, np.array([m]), t, np.array([f != forward[labels == label][0]]))
            worst = max(worst, float(np.abs(x - x0).max()))
    return worst, over.size


@pytest.mark.parametrize("name, edges", [("catmark_fan", 4), ("catmark_nonman_edge100", 1)])
def test_non_manifold_corpus_files_meet_along_their_crease_curves(name, edges):
    surface, mesh = surface_from_file(shared_mesh(f"opensubdiv/{name}.obj"), exact_creases=True)
    assert len(mesh.non_manifold_edges) == edges
    report = check_surface(surface)
    assert report.overshared_edges == 0 and report.unpaired_crease_sides == 0  # every such edge is a listed piece
    assert report.crease_edges == len(surface.crease_sides) > 0
    assert report.relative_crease_gap <= 1e-12 and report.max_normal_jump <= 1e-10
    gap, count = sheet_sides(surface)  # measured again from the geometry alone
    points = np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)])
    assert count > 0 and gap <= 1e-12 * np.linalg.norm(np.ptp(points, axis=0))


def test_the_fan_converts_to_files_that_check_and_a_valid_step(tmp_path):
    path = shared_mesh("opensubdiv/catmark_fan.obj")
    run = lambda *a: CliRunner().invoke(main, [str(x) for x in a], catch_exceptions=False)
    refused = run("convert", path, "-o", tmp_path / "no.ply", "--non-manifold", "refuse")
    assert refused.exit_code == 1 and "cuts such edges into sheets that meet along one C0 crease" in refused.stderr
    assert not (tmp_path / "no.ply").exists()
    result = run("convert", path, "--exact-creases", "-o", tmp_path / "fan.ply", "--patches", tmp_path / "fan.json",
                 "--patches", tmp_path / "fan.step")
    assert result.exit_code == 0, result.output
    assert ("cut 4 edges in more than two faces (vertices 7-8, 8-9, 9-10, 10-11, 0-based) into manifold sheets: 4 are a "
            "C0 crease the sheets meet along") in result.stderr
    rows = np.array(json.loads((tmp_path / "fan.json").read_text())["crease_sides"])
    assert len(rows) == 32  # 4 edges x 4 pieces x (3 sheets - 1)
    check = run("check", tmp_path / "fan.json")
    assert check.exit_code == 0 and "crease edges:     32 of 32 listed" in check.output, check.output
    pytest.importorskip("OCP")
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    try:  # cadquery-ocp 8
        from OCP.collections import IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as EdgeFaces
    except ImportError:  # cadquery-ocp 7
        from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape as EdgeFaces

    # one open shell of the plate and the two fins, which share the crease's edges: each in three faces (Open
    # CASCADE's reader then regroups the faces into manifold shells, two or three depending on their order)
    text = (tmp_path / "fan.step").read_text()
    assert text.count("OPEN_SHELL") == 1 and "MANIFOLD_SOLID_BREP" not in text
    shape = read_step(tmp_path / "fan.step")
    assert BRepCheck_Analyzer(shape).IsValid()
    faces_of = EdgeFaces()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, faces_of)
    uses = np.array([faces_of.FindFromIndex(i).Size() for i in range(1, faces_of.Extent() + 1)])
    assert set(uses.tolist()) == {1, 2, 3} and (uses == 3).sum() >= 1  # boundary, inner, crease edges
