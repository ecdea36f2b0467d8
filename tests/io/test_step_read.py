"""STEP patch files read back (``read_patch_set_step``): check, measure and diff accept .step as they accept JSON.

For every sample mesh, ``convert --patches X.step`` gives back the surface's
coefficients (faces paired with patches by their centres: STEP keeps the
shell order, not the patch order), and ``check``, ``measure --json`` and
``diff`` say of X.step what they say of X.json. Merged pieces (``--merge``)
and rational surfaces (OBJ ``v x y z w``) come back too, the writer keeps
every double (17 significant digits), a reversed face keeps its normal, and
faces c1surf does not read (planes, trimmed faces) are refused with one line.
Needs Open CASCADE (cadquery-ocp): skipped without it.
"""
from __future__ import annotations

import json
import re
import sys

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial import cKDTree

pytest.importorskip("OCP")

from c1surf.api import surface_from_file  # noqa: E402
from c1surf.cli.main import main  # noqa: E402
from c1surf.evaluation.bezier import evaluate_patches  # noqa: E402
from c1surf.evaluation.compare import bbox_diagonal, patch_centres  # noqa: E402
from c1surf.evaluation.patch_set import PatchSet  # noqa: E402
from c1surf.evaluation.smoothness import measure_smoothness  # noqa: E402
from c1surf.io.errors import MeshInputError  # noqa: E402
from c1surf.io.patches.formats import load_patch_set, write_patch_set  # noqa: E402
from c1surf.io.patches.brep.step_brep import bezier_surface, bspline_surface, occ_classes  # noqa: E402
from c1surf.io.patches.merged import cad_patch_set  # noqa: E402
from c1surf.io.patches.step import read_patch_set_step, write_step_shape  # noqa: E402

from conftest import CLOSED_SAMPLES, SAMPLES, weighted_cube  # noqa: E402

WORST = {}  # what -> largest relative disagreement found, for the summary below



# free faces (no shared edges), to write STEP files the writer would not: test-only
def bezier_faces(patch_groups, weights=None) -> list:
    """One free ``TopoDS_Face`` per patch (in order), on an exact ``Geom_BezierSurface`` over [0,1]^2 (no shared edges).

    Parameters
    ----------
    patch_groups : list of (p_k, du+1, dv+1, >= 3) float
    weights : None or a list parallel to ``patch_groups`` of (p_k, du+1, dv+1) float or None each (rational patches)
    """
    occ = occ_classes()
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    faces = []
    for group, group_weights in zip(patch_groups, weights or [None] * len(patch_groups)):
        for k, points in enumerate(np.asarray(group, dtype=np.float64)):
            surface = bezier_surface(occ, points, None if group_weights is None else group_weights[k])
            faces.append(BRepBuilderAPI_MakeFace(surface, 1e-7).Face())
    return faces


def bspline_faces(pieces) -> list:
    """One free ``TopoDS_Face`` per merged piece, on its clamped ``Geom_BSplineSurface`` of degree (2, 2)."""
    occ = occ_classes()
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    return [BRepBuilderAPI_MakeFace(bspline_surface(occ, piece), 1e-7).Face() for piece in pieces]

def run(*args, code=0):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    assert result.exit_code == code, result.output
    return result.output


def convert(tmp_path, mesh, *options):
    """convert MESH with --patches s.step and s.json in one run: (step path, json path).

    One face per patch (--no-merge) unless the options ask for --merge: both files then hold the same patches.
    """
    step, js = tmp_path / "s.step", tmp_path / "s.json"
    merge = [] if "--merge" in options else ["--no-merge"]
    run("convert", mesh, "-o", tmp_path / "s.ply", "-r", "2", "--patches", step, "--patches", js, "-q", *merge, *options)
    return step, js


def pairing(want: np.ndarray, got: np.ndarray, want_weights=None, got_weights=None) -> np.ndarray:
    """Index into ``want`` of each patch of ``got``, by their centres; one to one."""
    _, order = cKDTree(patch_centres(want, want_weights)).query(patch_centres(got, got_weights))
    assert np.array_equal(np.sort(order), np.arange(len(want)))
    return order


def turned_distance(want: np.ndarray, got: np.ndarray) -> np.ndarray:
    """(p,) largest coefficient distance of ``got`` to ``want`` turned by the best quarter turn, patch by patch."""
    turns = np.stack([np.abs(np.rot90(want, k, axes=(1, 2)) - got).max(axis=(1, 2, 3)) for k in range(4)])
    return turns.min(axis=0)


def normal_jump(output: str) -> float:
    assert "G1: yes" in output, output
    return float(re.search(r"max normal jump:\s+(\S+) rad", output).group(1))


@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_every_sample_reads_back_and_checks_measures_and_diffs_as_json(tmp_path, name):
    surface = surface_from_file(SAMPLES / name)[0]  # what convert builds
    step, js = convert(tmp_path, SAMPLES / name)
    back = read_patch_set_step(step)
    assert isinstance(back, PatchSet) and back.weights is None and back.merged == [] and back.adjacency is None
    want = [g for g in (surface.biquadratic, surface.bicubic) if len(g)]
    assert [g.shape for g in back.groups] == [g.shape for g in want]  # biquadratic group, then bicubic
    diagonal = bbox_diagonal(np.concatenate([g.reshape(-1, 3) for g in want]))
    worst = 0.0
    for w, g in zip(want, back.groups):
        order = pairing(w, g)
        worst = max(worst, float(np.abs(g - w[order]).max()) / diagonal)
        centres = evaluate_patches(g, np.array([0.5]), np.array([0.5]))[:, 0, 0]
        assert np.allclose(centres, evaluate_patches(w[order], np.array([0.5]), np.array([0.5]))[:, 0, 0], rtol=0, atol=1e-12 * diagonal)
    WORST[f"coefficients {name}"] = worst
    assert worst <= 1e-12, worst
    # check, measure and diff read X.step as they read X.json
    jumps = [normal_jump(run("check", path)) for path in (js, step)]
    assert abs(jumps[0] - jumps[1]) <= 1e-12, jumps  # as printed (4 digits); and at full precision:
    exact = [measure_smoothness(s.groups, samples=11, tolerance=1e-9).max_normal_jump for s in (load_patch_set(js), back)]
    WORST[f"normal jump {name}"] = abs(exact[0] - exact[1])
    assert abs(exact[0] - exact[1]) <= 1e-12, exact
    measures = [json.loads(run("measure", path, "--json")) for path in (js, step)]
    assert_same_measure(*measures, name)
    assert "equal within 1e-12" in run("diff", js, step)
    assert "equal within 1e-12" in run("diff", step, js)


def assert_same_measure(a: dict, b: dict, name: str) -> None:
    """measure --json of JSON and STEP agree to 1e-12 relative: each quantity against its largest entry, the
    centroid (0 for a centred surface) against the length sqrt(area)."""
    assert a["closed"] == b["closed"] and a["reason"] == b["reason"]
    worst = 0.0
    for key in ("area", "volume", "centroid", "inertia"):
        x, y = np.asarray(a[key], float), np.asarray(b[key], float)
        scale = np.sqrt(a["area"]) if key == "centroid" else float(np.abs(x).max())
        worst = max(worst, float(np.abs(x - y).max()) / scale)
    WORST[f"measure {name}"] = worst
    assert worst <= 1e-12, (worst, a, b)


@pytest.mark.parametrize("merge", [False, "pieces", "strips"])
@pytest.mark.parametrize("rational", [False, True])
def test_merged_pieces_and_weights_round_trip(tmp_path, rational, merge):
    """--no-merge, --merge --cad-pieces and --merge (JSON: the pieces; STEP: the pieces cut into strips)."""
    flags = {False: [], "pieces": ["--merge", "--cad-pieces"], "strips": ["--merge"]}[merge]
    step, js = convert(tmp_path, weighted_cube(tmp_path, rational), *flags)
    want, back = load_patch_set(js), load_patch_set(step)
    assert (back.weights is None) == (want.weights is None) == (not rational)
    assert [g.shape for g in back.groups] == [g.shape for g in want.groups]
    diagonal = bbox_diagonal(np.concatenate([g.reshape(-1, 3) for g in want.groups]))
    worst = 0.0
    for k, (w, g) in enumerate(zip(want.groups, back.groups)):
        ww, gw = (None, None) if not rational else (want.weights[k], back.weights[k])
        order = pairing(w, g, ww, gw)
        # a merged piece's patches come back in the piece's (u, v): turned, the same patch
        distance = turned_distance(w[order], g) if merge else np.abs(g - w[order]).max(axis=(1, 2, 3))
        worst = max(worst, float(distance.max()) / diagonal)
        if rational:
            h = np.concatenate([w * ww[..., None], ww[..., None]], axis=-1)[order]  # weights turn with their points
            hg = np.concatenate([g * gw[..., None], gw[..., None]], axis=-1)
            assert turned_distance(h, hg).max() <= 1e-12 * max(diagonal, float(ww.max()))
    WORST[f"cube rational={rational} merge={merge}"] = worst
    assert worst <= 1e-12, worst
    assert (len(want.merged) > 0) == bool(merge)
    written = cad_patch_set(want).merged if merge == "strips" else want.merged  # what the STEP file holds
    assert len(back.merged) == len(written)
    for piece in written:  # the same B-spline surfaces: pair the pieces by their spans and control nets
        got = min(back.merged, key=lambda p: (p.points.shape != piece.points.shape,
                                              np.abs(p.points.mean(axis=(0, 1)) - piece.points.mean(axis=(0, 1))).max()))
        assert got.points.shape == piece.points.shape and np.abs(got.points - piece.points).max() <= 1e-12 * diagonal
        assert np.array_equal(got.knots_u, piece.knots_u) and np.array_equal(got.knots_v, piece.knots_v)
        assert (got.weights is None) == (not rational)
        assert got.weights is None or np.abs(got.weights - piece.weights).max() <= 1e-12 * piece.weights.max()
        assert got.patches.shape == piece.patches.shape and not got.rotation.any()
    jumps = [normal_jump(run("check", path)) for path in (js, step)]
    assert abs(jumps[0] - jumps[1]) <= 1e-12, jumps
    assert_same_measure(*(json.loads(run("measure", path, "--json")) for path in (js, step)), f"cube {rational} {merge}")
    if not merge:  # merged: the pieces' patches come back turned and renumbered, which diff reports
        run("diff", js, step)


def test_every_double_comes_back_exactly(tmp_path):
    """The writer writes 17 significant digits (Open CASCADE's own default is 12): the same bits come back."""
    rng = np.random.default_rng(7)
    scales = np.array([1e-7, 1.0, 3e5])
    quad = rng.normal(size=(5, 3, 3, 3)) * scales
    cubic = rng.normal(size=(4, 4, 4, 3)) * scales
    quad[..., 1] += 100.0 * np.arange(5)[:, None, None]  # apart, so that sewing joins (and turns) none of them
    cubic[..., 1] += 100.0 * np.arange(5, 9)[:, None, None]
    quad[0, 0, 0] = [0.0, 1e-120, -0.1]  # a three-digit exponent, and zero
    weights = [rng.uniform(0.3, 3.0, (5, 3, 3)), rng.uniform(0.3, 3.0, (4, 4, 4))]
    for patch_weights in (None, weights):
        write_patch_set(tmp_path / "x.step", PatchSet([quad, cubic], weights=patch_weights))
        back = read_patch_set_step(tmp_path / "x.step")
        for k, (want, got) in enumerate(zip([quad, cubic], back.groups)):
            order = pairing(want, got)
            assert np.array_equal(got, want[order])
            assert patch_weights is None or np.array_equal(back.weights[k], patch_weights[k][order])


def test_coordinates_beyond_1e100_are_refused(tmp_path):
    from c1surf.io.errors import OutputError

    with pytest.raises(OutputError, match="below 1e100"):
        write_patch_set(tmp_path / "x.step", PatchSet([np.full((1, 3, 3, 3), -2e100)]))


def compound(faces):
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    builder, shape = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(shape)
    for face in faces:
        builder.Add(shape, face)
    return shape


def centre_normals(points: np.ndarray) -> np.ndarray:
    half = np.array([0.5])
    nu = evaluate_patches(points, half, half, du=1)[:, 0, 0]
    nv = evaluate_patches(points, half, half, dv=1)[:, 0, 0]
    n = np.cross(nu, nv)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def test_reversed_faces_keep_their_normals(tmp_path):
    """A TopAbs_REVERSED face comes back with u and v swapped: x_u x x_v points as the face's normal."""
    surface = surface_from_file(SAMPLES / "twisted.obj")[0]
    quad, cubic = surface.biquadratic[:6], surface.bicubic[:6]
    faces = bezier_faces([quad, cubic])
    reverse = np.arange(12) % 2 == 1
    faces = [f.Reversed() if r else f for f, r in zip(faces, reverse)]
    from c1surf.evaluation.merge import merge_biquadratic

    piece = max(merge_biquadratic(surface), key=lambda p: p.patches.size)
    write_step_shape(tmp_path / "r.step", compound(faces + [bspline_faces([piece])[0].Reversed()]), "r.step")
    back = read_patch_set_step(tmp_path / "r.step")
    assert [g.shape[0] for g in back.groups] == [6 + piece.patches.size, 6]
    got_piece = back.merged[0]
    assert np.array_equal(got_piece.points, piece.points.transpose(1, 0, 2)[..., :3])  # u and v swapped
    assert np.array_equal(got_piece.knots_u, piece.knots_v) and got_piece.patches.shape == piece.patches.shape[::-1]
    for want, got, flipped in ((quad, back.groups[0][:6], reverse[:6]), (cubic, back.groups[1], reverse[6:])):
        order = pairing(want, got)
        assert np.array_equal(flipped[order], [not np.array_equal(g, w) for g, w in zip(got, want[order])])
        assert np.array_equal(got[flipped[order]], want[order][flipped[order]].transpose(0, 2, 1, 3))
        dots = np.sum(centre_normals(got) * centre_normals(want[order]), axis=1)
        assert np.allclose(dots, np.where(flipped[order], -1.0, 1.0), atol=1e-12)  # the face's normal, as written
    # the patches cut out of the reversed piece: normals opposite to the original patches'
    cut = back.groups[0][6:]
    original = surface.biquadratic[piece.patches.ravel()]
    dots = np.sum(centre_normals(cut) * centre_normals(original[pairing(original, cut)]), axis=1)
    assert np.allclose(dots, -1.0, atol=1e-12)


def one_line_refusal(tmp_path, shape, pattern):
    """The STEP file of ``shape`` is refused with one line by the reader and by check, measure and diff."""
    path = tmp_path / "x.step"
    write_step_shape(path, shape, "x.step")
    with pytest.raises(MeshInputError, match=pattern) as info:
        read_patch_set_step(path)
    assert "\n" not in str(info.value) and str(info.value).startswith(f"{path}: ")
    for args in (["check", path], ["measure", path], ["diff", path, path]):
        result = CliRunner().invoke(main, [str(a) for a in args])
        assert result.exit_code == 1 and len(result.output.strip().splitlines()) == 1, result.output
        assert re.search(pattern, result.output)


def test_a_box_of_planes_is_refused(tmp_path):
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    one_line_refusal(tmp_path, BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape(), r"face 1 is on a Geom_Plane surface")


def test_a_trimmed_face_is_refused(tmp_path):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.BRep import BRep_Tool

    patch = surface_from_file(SAMPLES / "cube.obj")[0].bicubic[:1]
    surface = BRep_Tool.Surface_s(bezier_faces([patch])[0])
    half = BRepBuilderAPI_MakeFace(surface, 0.0, 0.5, 0.0, 1.0, 1e-7).Face()
    one_line_refusal(tmp_path, half, r"face 1 is trimmed \(parameter bounds 0, 0.5, 0, 1")


def test_a_general_bspline_is_refused(tmp_path):
    patch = surface_from_file(SAMPLES / "cube.obj")[0].biquadratic[:1]
    from c1surf.evaluation.merge import MergedPiece

    knots_u, knots_v = np.array([0.0, 0, 0, 0.3, 1, 1, 1]), np.array([0.0, 0, 0, 1, 1, 1])  # not 0 0 0 1 2 2 2
    points = np.concatenate([patch[0], patch[0, -1:] + 1.0])  # (4, 3, 3): two spans in u
    piece = MergedPiece(points, None, knots_u, knots_v, np.zeros((2, 1), int), np.zeros((2, 1), int))
    one_line_refusal(tmp_path, bspline_faces([piece])[0], "has interior knots and is not a merged c1surf surface")


def test_without_open_cascade_the_reader_says_what_to_install(tmp_path, monkeypatch):
    step, _ = convert(tmp_path, SAMPLES / "tetrahedron.obj")
    monkeypatch.setitem(sys.modules, "OCP", None)  # import OCP raises ImportError
    with pytest.raises(MeshInputError, match=r"pip install 'c1surf\[cad\]'"):
        read_patch_set_step(step)


def test_missing_and_unreadable_files_are_one_line(tmp_path):
    with pytest.raises(MeshInputError, match="no such file"):
        read_patch_set_step(tmp_path / "none.step")
    (tmp_path / "bad.stp").write_text("not a STEP file\n")
    with pytest.raises(MeshInputError, match="not a STEP file"):
        read_patch_set_step(tmp_path / "bad.stp")


def test_report_worst_disagreement():
    """Summary line (run with -s to see it): the largest STEP vs c1surf disagreement above."""
    if WORST:
        name = max(WORST, key=WORST.get)
        print(f"\nlargest STEP read-back disagreement: {WORST[name]:.2e} ({name}); over {len(WORST)} comparisons")
        assert max(WORST.values()) <= 1e-12
