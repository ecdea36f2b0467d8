"""Surfaces whose merged pieces close on themselves read back from every patch format c1surf writes.

A piece (or a strip of one, the default CAD packing) that goes round a tube, a torus or a scan's limb has its
first and last rows of control points equal. c1surf's IGES writer flags it closed (PROP1/PROP2, never periodic);
the STEP writer (Open CASCADE's ``GeomToStep``) sets ``u_closed``/``v_closed``. Open CASCADE's STEP *reader* makes
every such B-spline surface periodic whatever the flags say (``ShapeCustom_Surface::ConvertToPeriodic``), so the
STEP reader gives the clamped net back (``io.patches.brep.step_faces._clamped_seam``). Every format is read back by
``diff`` (against the NPZ: exit 0), ``check`` (G1 certified) and ``measure`` (equal to the NPZ's).
Needs Open CASCADE (cadquery-ocp): skipped without it; the fitted scans run with C1SURF_SLOW_TESTS=1.
"""
from __future__ import annotations

import json
import os
import re

import numpy as np
import pytest
from click.testing import CliRunner

pytest.importorskip("OCP")

from c1surf.cli.main import main  # noqa: E402
from c1surf.io.patches.formats import load_patch_set  # noqa: E402

from conftest import ROOT, ocp_shapes, read_step  # noqa: E402

SCANS = ROOT.parent / "shared" / "scans"
SUFFIXES = (".json", ".npz", ".igs", ".step")
PACKINGS = {"strips": [], "pieces": ["--cad-pieces"]}
SLOW = pytest.mark.skipif(not os.environ.get("C1SURF_SLOW_TESTS"), reason="a scan fit: set C1SURF_SLOW_TESTS=1")


def run(*args, code=0) -> str:
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    assert result.exit_code == code, result.output
    return result.output


def write_obj(path, points, faces):
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(points, dtype=np.float64).tolist()]
    lines += ["f " + " ".join(str(v + 1) for v in face) for face in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def ring_faces(around: int, rows: int, closed: bool) -> list:
    """Quads of ``rows`` rings of ``around`` vertices, the last joined to the first where ``closed`` (a torus)."""
    ring = lambda k: (k % rows) * around if closed else k * around  # noqa: E731
    return [(ring(k) + i, ring(k) + (i + 1) % around, ring(k + 1) + (i + 1) % around, ring(k + 1) + i)
            for k in range(rows if closed else rows - 1) for i in range(around)]


def tube_obj(path, around: int = 8, along: int = 4, rational: bool = False):
    """An open tube of ``around`` x ``along`` regular quads (every interior vertex of valence 4): its merged pieces
    close round it. ``rational``: vertex weights in 0.5 .. 2 (OBJ ``v x y z w``: rational patches, A2a)."""
    a = 2 * np.pi * np.arange(around) / around
    points = [(np.cos(t), np.sin(t), 0.5 * k) for k in range(along + 1) for t in a]
    path = write_obj(path, points, ring_faces(around, along + 1, False))
    if rational:
        w = iter(np.random.default_rng(3).uniform(0.5, 2.0, len(points)).tolist())
        lines = path.read_text().splitlines()
        path.write_text("\n".join(f"{line} {next(w)!r}" if line.startswith("v ") else line for line in lines) + "\n")
    return path


def torus_obj(path, around: int = 8, rows: int = 6):
    """A torus of ``around`` x ``rows`` regular quads: one merged piece closing both ways."""
    a, b = 2 * np.pi * np.arange(around) / around, 2 * np.pi * np.arange(rows) / rows
    points = [((2 + np.cos(s)) * np.cos(t), (2 + np.cos(s)) * np.sin(t), np.sin(s)) for s in b for t in a]
    return write_obj(path, points, ring_faces(around, rows, True))


def grid_obj(path, n: int = 3):
    """An open n x n grid of quads, gently curved: no piece closes."""
    points = [(i, j, 0.1 * i * j) for i in range(n + 1) for j in range(n + 1)]
    faces = [(i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, i * (n + 1) + j + 1)
             for i in range(n) for j in range(n)]
    return write_obj(path, points, faces)


def periodic_faces(path) -> int:
    """How many faces of a STEP file Open CASCADE reads on a periodic surface."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopoDS import TopoDS

    to_face = TopoDS.Face_s if hasattr(TopoDS, "Face_s") else TopoDS.Face
    surfaces = [BRep_Tool.Surface_s(to_face(f)) for f in ocp_shapes(read_step(path), TopAbs_FACE)]
    return sum(s.IsUPeriodic() or s.IsVPeriodic() for s in surfaces)


def measured(path) -> dict:
    return json.loads(run("measure", path, "--json", "-q"))


def assert_reads_back(paths: dict) -> dict:
    """Every file of ``paths`` (suffix -> path, one surface): diff against the NPZ exits 0, check certifies G1,
    measure equals the NPZ's (JSON: bit for bit; IGES and STEP, which hold the pieces and cut the patches out
    again: to 1e-13, and the same numbers as each other). Returns the NPZ's measure."""
    npz = paths[".npz"]
    want = measured(npz)
    got = {}
    for suffix, path in paths.items():
        run("diff", npz, path)
        assert "G1: yes" in run("check", path)
        got[suffix] = measured(path)
        keys = ["area"] + (["volume"] if want["closed"] else [])
        assert got[suffix]["closed"] == want["closed"]
        for key in keys:
            assert got[suffix][key] == pytest.approx(want[key], rel=1e-13, abs=0), (suffix, key)
    assert got[".json"] == want
    assert got[".step"] == got[".igs"]  # the same pieces, read back exactly from either CAD format
    return want


def convert_all(tmp_path, mesh, packing: str) -> dict:
    paths = {suffix: tmp_path / f"s{suffix}" for suffix in SUFFIXES}
    patches = [a for p in paths.values() for a in ("--patches", p)]
    run("convert", mesh, "-o", tmp_path / "s.ply", "-r", "2", "-q", *patches, *PACKINGS[packing])
    return paths


@pytest.mark.parametrize("name, packing", [("tube", "strips"), ("tube", "pieces"), ("torus", "strips"),
                                           ("torus", "pieces"), ("rational tube", "pieces")])
def test_closed_pieces_read_back_in_every_format(tmp_path, name, packing):
    mesh = (torus_obj(tmp_path / "torus.obj") if name == "torus"
            else tube_obj(tmp_path / "tube.obj", rational=name == "rational tube"))
    paths = convert_all(tmp_path, mesh, packing)
    closing = periodic_faces(paths[".step"])
    assert closing > 0  # the case this is about: Open CASCADE reads the closing faces periodic
    assert assert_reads_back(paths)["closed"] == (name == "torus")
    # the pieces come back from STEP as the IGES reader gives them (the clamped nets the writer wrote), bit for bit
    iges, step = load_patch_set(paths[".igs"]), load_patch_set(paths[".step"])
    assert len(step.merged) == len(iges.merged) > 0
    key = lambda p: (p.points + 0.0).tobytes()  # noqa: E731  (+ 0.0: -0.0 sorts as 0.0)
    for a, b in zip(sorted(step.merged, key=key), sorted(iges.merged, key=key)):
        assert np.array_equal(a.points, b.points) and np.array_equal(a.knots_u, b.knots_u)
        assert np.array_equal(a.knots_v, b.knots_v)
        assert (a.weights is None) == (b.weights is None) == (name != "rational tube")
        assert a.weights is None or np.array_equal(a.weights, b.weights)


def inside_out_solids(shape):
    """``shape`` with every solid's shell reversed: what Open CASCADE's STEP healing (``ShapeFix_Solid``) does when
    its ray classifier finds the point at infinity inside a solid (boot fitted at 300 faces, in strips)."""
    from OCP.BRep import BRep_Builder
    from OCP.TopAbs import TopAbs_SHELL, TopAbs_SOLID
    from OCP.TopoDS import TopoDS_Compound, TopoDS_Solid

    builder, compound = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(compound)
    for solid in ocp_shapes(shape, TopAbs_SOLID):
        turned = TopoDS_Solid()
        builder.MakeSolid(turned)
        for shell in ocp_shapes(solid, TopAbs_SHELL):
            builder.Add(turned, shell.Reversed())
        builder.Add(compound, turned)
    return compound


@pytest.mark.parametrize("packing", PACKINGS)
def test_a_solid_the_reader_turns_inside_out_reads_back(tmp_path, monkeypatch, packing):
    """Open CASCADE's STEP reader may heal a solid inside out (its classifier erred on boot at 300 faces in strips,
    and every face came back with u and v swapped: 10,936 coefficients moved). c1surf goes by the volume its own
    Gauss rules give the faces as read, so the torus read back with its solid reversed is still the NPZ's surface."""
    import c1surf.io.patches.step as step
    import c1surf.io.patches.brep.step_faces as step_faces
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    paths = convert_all(tmp_path, torus_obj(tmp_path / "torus.obj"), packing)
    read_shape = step_faces._read_shape

    def turned(path):
        shape, reader = read_shape(path)
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(turned_shape := inside_out_solids(shape), props)
        assert props.Mass() < 0  # Open CASCADE's own volume of the shape the reader now gives: inside out
        return turned_shape, reader

    monkeypatch.setattr(step_faces, "_read_shape", turned)
    monkeypatch.setattr(step, "CONTAINED", False)  # the replaced reader runs in this process, not in the child
    assert assert_reads_back(paths)["closed"]
    assert load_patch_set(paths[".step"]).n_patches == load_patch_set(paths[".npz"]).n_patches


@pytest.mark.parametrize("flag", ["F", "T"])
def test_closed_flags_are_information_only(tmp_path, flag):
    """Another writer's flags do not matter: the tube's closed strips written with u_closed/v_closed .F., and
    a grid's open faces written with .T., read as c1surf's own files do (Open CASCADE goes by the net)."""
    mesh = tube_obj(tmp_path / "tube.obj", along=2) if flag == "F" else grid_obj(tmp_path / "grid.obj")
    paths = convert_all(tmp_path, mesh, "strips")
    text = paths[".step"].read_text()
    flags = re.compile(r"\.UNSPECIFIED\.,\.([TF])\.,\.([TF])\.,\.F\.")
    written = {m.groups() for m in flags.finditer(text)}
    assert (("F", "T") in written) == (flag == "F")  # the tube's strips close, the grid's faces do not
    path = tmp_path / "flags.step"
    path.write_text(flags.sub(f".UNSPECIFIED.,.{flag}.,.{flag}.,.F.", text))
    assert {m.groups() for m in flags.finditer(path.read_text())} == {(flag, flag)}
    run("diff", paths[".step"], path)
    assert measured(path) == measured(paths[".step"])
    # IGES: c1surf writes PROP2 (closed in v) = 1 on the tube's strips, never PROP4/PROP5 (periodic); the reader goes
    # by the knots and the net, so every closed and periodic flag set, or none, reads the same surface
    text = paths[".igs"].read_text()
    props = re.compile(r"^(128,\d+,\d+,\d+,\d+,)([01]),([01]),([01]),([01]),([01]),", re.M)
    written = {(m.group(2), m.group(3), m.group(5), m.group(6)) for m in props.finditer(text)}
    assert (("0", "1", "0", "0") in written) == (flag == "F") and all(p[2:] == ("0", "0") for p in written)
    path = tmp_path / "flags.igs"
    value = "1" if flag == "T" else "0"
    path.write_text(props.sub(lambda m: f"{m.group(1)}{value},{value},{m.group(4)},{value},{value},", text))
    assert path.read_text() != text
    run("diff", paths[".igs"], path)
    assert measured(path) == measured(paths[".igs"])


def test_periodic_through_its_seam_is_refused_with_its_own_line(tmp_path):
    """A B-spline surface periodic in u with simple knots (smooth across its seam: no c1surf piece is) names it."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    from c1surf.io.patches.brep.step_brep import occ_classes, occ_integers, occ_poles, occ_reals
    from c1surf.io.patches.step import write_step_shape

    occ, n = occ_classes(), 8
    a = 2 * np.pi * np.arange(n) / n
    points = np.stack([np.c_[np.cos(a), np.sin(a), np.full(n, z)] for z in (0.0, 1.0, 2.0)], axis=1)  # (n, 3, 3)
    surface = occ.BSpline(occ_poles(occ, points), occ_reals(occ, np.ones((n, 3))),
                          occ_reals(occ, np.arange(n + 1.0)), occ_reals(occ, np.array([0.0, 1.0])),
                          occ_integers(occ, np.ones(n + 1, np.int64)), occ_integers(occ, np.array([3, 3])),
                          2, 2, True, False)
    assert surface.IsUPeriodic()
    write_step_shape(tmp_path / "periodic.step", BRepBuilderAPI_MakeFace(surface, 1e-7).Face(), "periodic")
    assert periodic_faces(tmp_path / "periodic.step") == 1
    result = CliRunner().invoke(main, ["measure", str(tmp_path / "periodic.step")])
    assert result.exit_code == 1 and "Traceback" not in result.output
    line = result.output.strip()
    assert "\n" not in line and "face 1 is on a B-spline surface periodic in u through its seam" in line, line
    assert "seam knot multiplicity 1, degree 2" in line


@SLOW
@pytest.mark.parametrize("packing", PACKINGS)
@pytest.mark.parametrize("scan, faces, closing", [("scorpion_low_resolution.obj", 1000, True), ("boot.obj", 300, False)])
def test_fitted_scans_read_back_in_every_format(tmp_path, scan, faces, closing, packing):
    """Fits of the shared scans at small face counts: scorpion at 1,000 faces has a piece round a limb (two strips
    in strips), boot at 300 none (none at 200 to 2,500 faces either); 4-5 minutes each on 2 busy cores."""
    paths = {suffix: tmp_path / f"s{suffix}" for suffix in SUFFIXES}
    patches = [a for p in paths.values() for a in ("--patches", p)]
    run("fit", SCANS / scan, "--faces", faces, "-q", *patches, *PACKINGS[packing])
    assert (periodic_faces(paths[".step"]) > 0) == closing
    assert_reads_back(paths)
