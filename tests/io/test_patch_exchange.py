"""Patch files as an exchange format: JSON / NPZ / IGES content, `tessellate`, round trips, determinism.

- adjacency stored in patch files (corners, side edges, directions) is the one
  found from the geometry alone, and really describes shared corners and sides;
- `c1surf tessellate PATCHES` writes byte for byte what `convert` writes;
- reading a patch file back and evaluating gives the same bits as evaluating
  the surface directly;
- the same input and options give byte-identical files, run after run, in
  every output format.
"""
from __future__ import annotations

import dataclasses
import json
import os
import re
import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.evaluation.adjacency import PatchAdjacency, SIDE_CORNERS, adjacency_from_geometry, patch_adjacency
from c1surf.evaluation.bezier import bernstein_basis, evaluate_patches
from c1surf.construction.surface import SurfaceOptions
from c1surf.evaluation.tessellate import tessellate, tessellate_patches
from c1surf.io.patches.iges_writer import write_iges
from c1surf.io.patches.json_patches import read_patch_set_json
from c1surf.io.patches.formats import load_patch_set
from c1surf.io.patches.npz import read_patch_set_npz, write_patch_set_npz
from c1surf.evaluation.patch_set import PatchSet

from conftest import CLOSED_SAMPLES, SAMPLES, shared_mesh, surface_of

MESH_SUFFIXES = (".obj", ".ply", ".stl", ".glb", ".off")
PATCH_SUFFIXES = (".json", ".npz", ".igs")
CORPUS = ["opensubdiv/catmark_torus_creases0.obj", "polyhedra-viewer/snub-dodecahedron.obj", "spot/spot_control_mesh.obj"]


def run(*args):
    """The command line; ``convert`` writes one face per patch (--no-merge) unless asked to merge:
    these tests compare patch files patch by patch (IGES and STEP are merged by default)."""
    args = [str(a) for a in args]
    if args[0] == "convert" and "--merge" not in args:
        args.append("--no-merge")
    return CliRunner().invoke(main, args, catch_exceptions=False)


T = np.linspace(0.0, 1.0, 9)


def side_points(patch: np.ndarray) -> list[np.ndarray]:
    """Points at T along sides 0..3, in increasing parameter (core.adjacency's numbering)."""
    polygons = [patch[:, 0], patch[-1, :], patch[:, -1], patch[0, :]]
    return [bernstein_basis(len(p) - 1, T) @ p for p in polygons]


def corner_points(patch: np.ndarray) -> np.ndarray:
    return np.array([patch[0, 0], patch[-1, 0], patch[-1, -1], patch[0, -1]])


# ----------------------------------------------------------------------------
# adjacency


@pytest.mark.parametrize("name", CLOSED_SAMPLES + CORPUS)
def test_adjacency_describes_the_geometry(name):
    path = SAMPLES / name if "/" not in name else shared_mesh(name)
    surface = surface_of(path)
    adjacency = patch_adjacency(surface.refined, surface.frames)
    adjacency.validate(surface.n_patches)
    # found again from the geometry alone: exactly the same arrays
    assert adjacency_from_geometry([surface.biquadratic, surface.bicubic]) == adjacency
    patches = [p for g in (surface.biquadratic, surface.bicubic) for p in g]
    size = np.ptp(np.concatenate([p.reshape(-1, 3) for p in patches]), axis=0).max()
    # closed input: every side has a neighbour, and neighbours are mutual
    nb = adjacency.neighbours()
    assert (nb >= 0).all()
    p, s = np.divmod(np.arange(4 * len(patches)), 4)
    back = nb[nb[p, s, 0], nb[p, s, 1]]
    assert np.array_equal(back, np.stack([p, s], axis=1))
    # sides with one edge id are the same curve, the same points at the same parameters (reversed when the flags differ)
    for k in range(len(patches)):
        for side in range(4):
            q, t = nb[k, side]
            a, b = side_points(patches[k])[side], side_points(patches[q])[t]
            if adjacency.reversed[k, side] != adjacency.reversed[q, t]:
                b = b[::-1]
            assert np.abs(a - b).max() <= 1e-12 * size
    # corners with one id are one point, and a side runs between its two corners
    corners = np.array([corner_points(p) for p in patches])
    for c in np.unique(adjacency.corners):
        pts = corners[adjacency.corners == c]
        assert np.abs(pts - pts[0]).max() <= 1e-12 * size
    # the two sides of an edge run between the same corner ids, in the directions the flags say
    ends = adjacency.corners[:, SIDE_CORNERS]  # (P, 4, 2): corner ids at the start and end of each side
    ends = np.where(adjacency.reversed[..., None], ends[..., ::-1], ends)  # in the edge's own direction
    assert np.array_equal(ends[nb[..., 0], nb[..., 1]], ends)


def test_adjacency_numbering_is_canonical():
    """Ids appear in order 0, 1, 2, ... and each edge's first side runs forward."""
    surface = surface_of(SAMPLES / "twisted.obj")
    a = patch_adjacency(surface.refined, surface.frames)
    for ids in (a.corners.ravel(), a.edges.ravel()):
        first = np.unique(ids, return_index=True)[1]
        assert np.all(np.diff(first) > 0)
    first_side = np.unique(a.edges.ravel(), return_index=True)[1]
    assert not a.reversed.ravel()[first_side].any()
    # the welded grid numbers corners, then edge samples, then patch interiors
    tess = tessellate_patches([surface.biquadratic, surface.bicubic], a, 4)
    assert tess.grid[:, 0, 0].max() < a.n_corners
    assert tess.grid.max() + 1 == a.n_corners + 2 * a.n_edges + 4 * a.n_patches


def test_adjacency_validation_refuses_bad_arrays():
    ok = PatchAdjacency(np.array([[0, 1, 2, 3]]), np.array([[0, 1, 2, 3]]), np.zeros((1, 4), bool))
    ok.validate(1)
    with pytest.raises(ValueError, match="without gaps"):
        PatchAdjacency(np.array([[0, 1, 2, 5]]), ok.edges, ok.reversed).validate()
    with pytest.raises(ValueError, match="more than two"):
        PatchAdjacency(np.zeros((2, 4), int) + [0, 1, 2, 3], np.zeros((2, 4), int), np.zeros((2, 4), bool)).validate()
    with pytest.raises(ValueError, match="patches"):
        ok.validate(2)


# ----------------------------------------------------------------------------
# tessellate == convert


@pytest.mark.parametrize("name", ["twisted.obj", "high_valence.obj", "double_torus.obj"])
@pytest.mark.parametrize("resolution", [2, 5])
def test_tessellate_reproduces_convert_byte_for_byte(tmp_path, name, resolution):
    converted = tmp_path / "convert.obj"
    for suffix in PATCH_SUFFIXES:
        patches = tmp_path / f"surface{suffix}"
        assert run("convert", SAMPLES / name, "-o", converted, "-r", resolution, "--patches", patches, "-q").exit_code == 0
        again = tmp_path / f"from{suffix}.obj"
        result = run("tessellate", patches, "-o", again, "-r", resolution, "-q")
        assert result.exit_code == 0, result.output
        assert again.read_bytes() == converted.read_bytes(), suffix


@pytest.mark.parametrize("suffix", MESH_SUFFIXES)
def test_tessellate_every_mesh_format(tmp_path, suffix):
    converted = tmp_path / f"convert{suffix}"
    patches = tmp_path / "p.npz"
    assert run("convert", SAMPLES / "hexagon_six_valent.obj", "-o", converted, "-r", 4, "--patches", patches).exit_code == 0
    again = tmp_path / f"again{suffix}"
    assert run("tessellate", patches, "-o", again, "-r", 4).exit_code == 0
    assert again.read_bytes() == converted.read_bytes()


def test_tessellate_without_stored_adjacency_welds_from_geometry(tmp_path):
    """An older JSON without adjacency still tessellates to the same mesh."""
    converted, patches = tmp_path / "c.off", tmp_path / "p.json"
    assert run("convert", SAMPLES / "dodecahedron.obj", "-o", converted, "-r", 3, "--patches", patches).exit_code == 0
    doc = json.loads(patches.read_text())
    for p in doc["patches"]:
        for key in ("corners", "edges", "reversed", "neighbours"):
            del p[key]
    patches.write_text(json.dumps(doc))
    assert read_patch_set_json(patches).adjacency is None
    again = tmp_path / "a.off"
    assert run("tessellate", patches, "-o", again, "-r", 3).exit_code == 0
    assert again.read_bytes() == converted.read_bytes()


def test_tessellate_keeps_the_old_entry_point():
    surface = surface_of(SAMPLES / "cube.obj")
    a = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 4)
    b = tessellate_patches([surface.biquadratic, surface.bicubic], patch_adjacency(surface.refined, surface.frames), 4)
    assert np.array_equal(a.grid, b.grid) and np.array_equal(a.points, b.points)


def one_line(tmp_path, *args):
    proc = subprocess.run([sys.executable, "-m", "c1surf.cli.main", *map(str, args)], capture_output=True, text=True, cwd=tmp_path)
    return proc.returncode, proc.stderr.strip().splitlines()


def test_tessellate_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    trimmed = tmp_path / "bspline.igs"
    P = np.random.default_rng(1).standard_normal((5, 4, 3))
    write_iges(trimmed, [{"points": P, "knots_u": [0, 0, 0, 0, 0.5, 1, 1, 1, 1], "knots_v": [0, 0, 0, 0, 1, 1, 1, 1], "degree": (3, 3)}])
    # rational patches are read now (test_rational_and_merged_iges_read_back); a transformation matrix is not
    moved = tmp_path / "moved.igs"
    write_iges(moved, [{"points": P[:4]}], group=False)
    lines = moved.read_text().splitlines(keepends=True)
    first_de = next(k for k, line in enumerate(lines) if line[72] == "D")
    lines[first_de] = lines[first_de][:48] + f"{1:8d}" + lines[first_de][56:]  # DE field 7: transformation matrix
    moved.write_text("".join(lines))
    text = tmp_path / "text.json"
    text.write_text("{nope")
    cases = [(bad, "not an NPZ patch file"), (trimmed, "interior knots"), (moved, "transformation matrix"),
             (text, "not a JSON patch file"), (tmp_path / "missing.json", "no such file")]
    for path, words in cases:
        code, lines = one_line(tmp_path, "tessellate", path, "-o", tmp_path / "x.obj")
        assert code == 1 and len(lines) == 1, lines
        assert lines[0].startswith(f"c1surf: error: {path}") and words in lines[0], lines
    assert not (tmp_path / "x.obj").exists()
    code, lines = one_line(tmp_path, "tessellate", tmp_path / "x.step", "-o", tmp_path / "x.obj")  # STEP is read now
    assert code == 1 and len(lines) == 1 and lines[0] == f"c1surf: error: {tmp_path / 'x.step'}: no such file", lines
    code, lines = one_line(tmp_path, "tessellate", tmp_path / "x.3dm", "-o", tmp_path / "x.obj")
    assert code == 2


# ----------------------------------------------------------------------------
# file content and round trips


def test_json_and_npz_hold_the_same_content(tmp_path):
    js, npz = tmp_path / "s.json", tmp_path / "s.npz"
    assert run("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "s.obj", "--patches", js, "--alpha", 0.7).exit_code == 0
    assert run("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "s.obj", "--patches", npz, "--alpha", 0.7).exit_code == 0
    a, b = read_patch_set_json(js), read_patch_set_npz(npz)
    assert a.header == b.header
    # every option, by name (convert's C0 creases are its default: --exact-creases/--g1-creases)
    assert a.header["options"] == dataclasses.asdict(SurfaceOptions(alpha=0.7, exact_creases=True))
    assert a.header["c1surf_version"] and a.header["input"]["faces"] == 18
    assert len(a.groups) == len(b.groups) == 2
    for g, h in zip(a.groups, b.groups):
        assert np.array_equal(g, h)
    assert a.adjacency == b.adjacency
    assert np.array_equal(a.source_kind, b.source_kind) and np.array_equal(a.source, b.source)
    with np.load(npz) as data:  # plain numpy reads it, no pickles
        assert data["neighbours"].shape == (a.n_patches, 4, 2)
        assert np.array_equal(data["neighbours"], a.adjacency.neighbours())
        assert json.loads(data["header"].item()) == a.header
    doc = json.loads(js.read_text())
    assert doc["counts"] == {"biquadratic": len(a.groups[0]), "bicubic": len(a.groups[1]),
                             "corners": a.adjacency.n_corners, "edges": a.adjacency.n_edges}
    # file order: biquadratic, then bicubic; sources name real input elements
    kinds = [p["kind"] for p in doc["patches"]]
    assert kinds == sorted(kinds, key=lambda k: k != "biquadratic")
    for p in doc["patches"]:
        (kind, value), = p["source"].items()
        assert kind in ("face", "edge", "vertex")
        assert all(0 <= v < (18 if kind == "face" else 24) for v in np.atleast_1d(value))


@pytest.mark.parametrize("suffix", PATCH_SUFFIXES)
def test_round_trip_evaluation_is_bit_exact(tmp_path, suffix):
    surface = surface_of(SAMPLES / "high_valence.obj")
    patches = tmp_path / f"s{suffix}"
    assert run("convert", SAMPLES / "high_valence.obj", "-o", tmp_path / "s.ply", "--patches", patches).exit_code == 0
    loaded = load_patch_set(patches)
    t = np.linspace(0.0, 1.0, 7)
    for direct, read in zip([surface.biquadratic, surface.bicubic], loaded.groups):
        for du, dv in ((0, 0), (1, 0), (0, 1)):
            assert np.array_equal(evaluate_patches(read, t, t, du, dv), evaluate_patches(direct, t, t, du, dv))
    assert [len(g) for g in load_patch_set(patches).by_degree()] == [len(surface.biquadratic), len(surface.bicubic)]


def test_npz_opens_in_milliseconds(tmp_path):
    """200 000 bicubic patches (77 MB): opening maps the arrays instead of reading them."""
    rng = np.random.default_rng(0)
    n = 200_000
    cubic = rng.standard_normal((n, 4, 4, 3))
    ids = np.arange(4 * n).reshape(n, 4)
    adjacency = PatchAdjacency(ids, ids.copy(), np.zeros((n, 4), bool))
    header = {"format": "c1surf-patches", "version": 1}
    path = tmp_path / "big.npz"
    write_patch_set_npz(path, PatchSet([cubic], adjacency, None, None, header))
    read_patch_set_npz(path)  # warm the page cache
    best = min(_timed(read_patch_set_npz, path) for _ in range(3))
    loaded = read_patch_set_npz(path)
    assert np.array_equal(loaded.groups[0], cubic) and loaded.adjacency == adjacency
    assert best < 0.25, f"{best:.3f} s"  # about 0.03 s here


def _timed(f, *args):
    t = time.perf_counter()
    f(*args)
    return time.perf_counter() - t


def test_npz_members_are_plain_and_dated_1980(tmp_path):
    path = tmp_path / "s.npz"
    assert run("convert", SAMPLES / "cube.obj", "-o", tmp_path / "s.obj", "--patches", path).exit_code == 0
    with zipfile.ZipFile(path) as zf:
        infos = zf.infolist()
    assert [i.filename for i in infos] == [f"{k}.npy" for k in ("header", "biquadratic", "bicubic", "source_kind", "source",
                                                                 "corners", "edges", "reversed", "neighbours")]
    assert all(i.compress_type == zipfile.ZIP_STORED and i.date_time == (1980, 1, 1, 0, 0, 0) for i in infos)


def test_iges_patch_file_reads_back_exactly(tmp_path):
    surface = surface_of(SAMPLES / "twisted.obj")
    path = tmp_path / "s.igs"
    assert run("convert", SAMPLES / "twisted.obj", "-o", tmp_path / "s.obj", "--patches", path, "--units", "in").exit_code == 0
    loaded = load_patch_set(path)
    assert loaded.adjacency is None and loaded.source is None
    assert np.array_equal(loaded.groups[0], surface.biquadratic) and np.array_equal(loaded.groups[1], surface.bicubic)
    lines = path.read_text().splitlines()
    global_section = "".join(line[:72] for line in lines if line[72] == "G")
    assert "5Hs.igs," in global_section and ".tmp-c1surf" not in global_section  # the final name, not the temporary one
    assert re.search(r",1,\s*4HINCH,", global_section)  # units flag 1, name INCH (records wrap at delimiters)
    start = " ".join(line[:72] for line in lines if line[72] == "S")
    assert "twisted.obj" in start and "biquadratic" in start


# ----------------------------------------------------------------------------
# determinism

_RUNS = [(".obj", ".json"), (".ply", ".npz"), (".stl", ".igs"), (".glb", ".json"), (".off", ".npz")]


def _convert_all(directory, mesh):
    for mesh_suffix, patch_suffix in _RUNS:
        stem = mesh_suffix[1:]
        result = run("convert", mesh, "-o", directory / f"{stem}{mesh_suffix}", "-r", 4,
                     "--patches", directory / f"{stem}{patch_suffix}", "-q")
        assert result.exit_code == 0, result.output


def test_outputs_are_byte_identical_across_runs(tmp_path, monkeypatch):
    """Every format, twice in this process and once in a fresh one with another hash seed."""
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    mesh = SAMPLES / "twisted.obj"
    dirs = [tmp_path / d for d in ("a", "b", "c")]
    for d in dirs:
        d.mkdir()
    _convert_all(dirs[0], mesh)
    _convert_all(dirs[1], mesh)
    script = (
        "import sys, pathlib; sys.path[:0] = [sys.argv[1], str(pathlib.Path(sys.argv[1]).parent)];"
        "from test_patch_exchange import _convert_all; _convert_all(pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3]))"
    )
    env = {k: v for k, v in os.environ.items() if k != "SOURCE_DATE_EPOCH"}
    env["PYTHONHASHSEED"] = "12345"
    subprocess.run([sys.executable, "-c", script, os.path.dirname(__file__), str(dirs[2]), str(mesh)], check=True, env=env)
    names = sorted(p.name for p in dirs[0].iterdir())
    assert {os.path.splitext(n)[1] for n in names} == {".obj", ".ply", ".stl", ".glb", ".off", ".json", ".npz", ".igs"}
    for name in names:
        first = (dirs[0] / name).read_bytes()
        assert (dirs[1] / name).read_bytes() == first, name
        assert (dirs[2] / name).read_bytes() == first, name


def test_convert_writes_several_patch_files_at_once(tmp_path):
    out = tmp_path / "s.obj"
    paths = [tmp_path / f"s{suffix}" for suffix in PATCH_SUFFIXES]
    args = [a for p in paths for a in ("--patches", p)]
    assert run("convert", SAMPLES / "cube.obj", "-o", out, *args, "-q").exit_code == 0
    sets = [load_patch_set(p) for p in paths]
    for other in sets[1:]:
        assert [np.array_equal(g, h) for g, h in zip(sets[0].groups, other.groups)] == [True, True]
    assert sets[0].adjacency == sets[1].adjacency == sets[2].welding()
    # two outputs with one name: a usage error, nothing written
    code, lines = one_line(tmp_path, "convert", SAMPLES / "cube.obj", "-o", tmp_path / "t.obj",
                           "--patches", tmp_path / "t.json", "--patches", tmp_path / "t.json")
    assert code == 2 and not (tmp_path / "t.obj").exists() and not (tmp_path / "t.json").exists()


def test_open_mesh_adjacency_and_tessellate(tmp_path):
    """An open input: boundary sides have no neighbour, and everything else works the same."""
    mesh = shared_mesh("opensubdiv/catmark_bishop.obj")
    surface = surface_of(mesh)
    adjacency = patch_adjacency(surface.refined, surface.frames)
    assert adjacency_from_geometry([surface.biquadratic, surface.bicubic]) == adjacency
    boundary = (adjacency.neighbours() < 0).all(axis=2)
    assert boundary.sum() > 0 and np.bincount(adjacency.edges.ravel())[adjacency.edges[boundary]].max() == 1
    converted, patches = tmp_path / "c.ply", tmp_path / "p.npz"
    assert run("convert", mesh, "-o", converted, "-r", 3, "--patches", patches, "-q").exit_code == 0
    assert run("tessellate", patches, "-o", tmp_path / "t.ply", "-r", 3, "-q").exit_code == 0
    assert (tmp_path / "t.ply").read_bytes() == converted.read_bytes()
