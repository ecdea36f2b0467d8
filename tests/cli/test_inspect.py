"""`c1surf inspect`: its counts against independent ones (plain Python over the file's text), its
patch counts and output sizes against a real conversion, refusals as `convert` words them."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.api import surface_from_file, tessellate_surface
from c1surf.cli.main import main
from c1surf.io.errors import C1SurfFileError
from c1surf.mesh.errors import TopologyError

from conftest import ROOT, SAMPLES, SHARED_MESHES

SAMPLE_FILES = sorted(p.name for p in SAMPLES.glob("*.obj"))
CORPUS = sorted(p.relative_to(SHARED_MESHES).as_posix() for p in SHARED_MESHES.glob("*/*.obj")) if SHARED_MESHES.exists() else []
KEYS = {"file", "vertices", "faces", "edges", "face_sizes", "valences", "unused_vertices", "boundary_edges",
        "boundary_loops", "non_manifold_edges", "pinched_vertices", "valence2_interior_vertices",
        "euler_characteristic", "components", "degenerate_faces", "collapsed_corners", "tags", "repairs", "notes",
        "refused", "patches", "output"}
COMPONENT_KEYS = {"vertices", "edges", "faces", "boundary_edges", "boundary_loops", "non_manifold_edges",
                  "euler_characteristic", "orientable", "genus", "nonorientable_genus"}
CUBE_POINTS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def inspect_json(path, *options) -> dict:
    result = run("inspect", path, "--json", *options)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def write_obj(path, points, faces):
    """An OBJ file of ``points`` and 0-based ``faces``."""
    lines = [f"v {x} {y} {z}" for x, y, z in points] + ["f " + " ".join(str(v + 1) for v in f) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


# -- the independent count: plain Python over the file's lines -------------------------------------


def parse_obj_faces(path):
    """(number of v lines, faces as lists of 0-based vertices with consecutive repeats dropped)."""
    n_vertices, faces = 0, []
    for line in path.read_text().splitlines():
        tokens = line.split("#")[0].split()
        if not tokens:
            continue
        if tokens[0] == "v":
            n_vertices += 1
        elif tokens[0] == "f":
            face = [int(t.split("/")[0]) for t in tokens[1:]]
            face = [v - 1 if v > 0 else n_vertices + v for v in face]
            faces.append([v for i, v in enumerate(face) if v != face[(i + 1) % len(face)]])
    return n_vertices, faces


class Find:
    """Union-find over hashable items."""

    def __init__(self):
        self.parent = {}

    def __call__(self, x):
        self.parent.setdefault(x, x)
        while self.parent[x] != x:
            self.parent[x] = self.parent[self.parent[x]]
            x = self.parent[x]
        return x

    def union(self, a, b):
        self.parent[self(a)] = self(b)

    def classes(self) -> int:
        return len({self(x) for x in list(self.parent)})


def independent_counts(path) -> dict:
    """Counts of an OBJ file by dicts over its edges (faces of fewer than 3 vertices left out of the topology)."""
    n_vertices, faces = parse_obj_faces(path)
    sizes = {}
    for f in faces:
        sizes[str(len(f))] = sizes.get(str(len(f)), 0) + 1
    n_faces = len(faces)
    faces = [f for f in faces if len(f) >= 3]
    edge_faces, corners = {}, {}
    for i, f in enumerate(faces):
        for a, b in zip(f, f[1:] + f[:1]):
            edge_faces.setdefault(frozenset((a, b)), []).append(i)
        for v in f:
            corners[v] = corners.get(v, 0) + 1
    boundary = [e for e, fs in edge_faces.items() if len(fs) == 1]
    on_boundary = {v for e in boundary for v in e}
    loops = Find()
    for e in boundary:
        loops.union(*e)
    fans = {v: Find() for v in corners}  # faces around v, joined across edges at v in two or more faces
    for i, f in enumerate(faces):
        for v in f:
            fans[v](i)
    for e, fs in edge_faces.items():
        for v in e:
            for g in fs[1:]:
                fans[v].union(fs[0], g)

    def histogram(vertices):
        out = {}
        for v in sorted(vertices, key=lambda v: corners[v]):
            out[str(corners[v])] = out.get(str(corners[v]), 0) + 1
        return out

    interior = [v for v in corners if v not in on_boundary]
    return {
        "vertices": n_vertices, "faces": n_faces,
        "face_sizes": dict(sorted(sizes.items(), key=lambda kv: int(kv[0]))), "edges": len(edge_faces),
        "boundary_edges": len(boundary), "non_manifold_edges": sum(len(fs) > 2 for fs in edge_faces.values()),
        "unused_vertices": n_vertices - len(corners),
        "valences": {"interior": histogram(interior), "boundary": histogram(on_boundary)},
        "valence2_interior_vertices": sum(corners[v] == 2 for v in interior),
        "pinched_vertices": sum(fans[v].classes() > 1 for v in corners),
        "raw_boundary_loops": loops.classes(),
        "raw_euler_characteristic": len(corners) - len(edge_faces) + len(faces),
        "small_faces": sum(v for k, v in sizes.items() if int(k) < 3),
    }


def assert_matches(report: dict, path):
    counts = independent_counts(path)
    for key in ("vertices", "faces", "face_sizes", "edges", "boundary_edges", "non_manifold_edges", "unused_vertices",
                "valences", "valence2_interior_vertices", "pinched_vertices"):
        assert report[key] == counts[key], key
    if counts["pinched_vertices"] == 0:  # pinches split boundary loops and add vertices to chi
        assert report["boundary_loops"] == counts["raw_boundary_loops"]
        assert report["euler_characteristic"] == counts["raw_euler_characteristic"]
    components = report["components"]
    assert {k for c in components for k in c} == COMPONENT_KEYS
    for key in ("faces", "edges", "boundary_edges", "boundary_loops", "non_manifold_edges", "euler_characteristic"):
        left_out = counts["small_faces"] if key == "faces" else 0  # faces of fewer than 3 vertices: in no component
        assert sum(c[key] for c in components) == report[key] - left_out, key
    for c in components:
        if c["genus"] is not None:
            assert c["euler_characteristic"] == 2 - 2 * c["genus"] - c["boundary_loops"]
    # inspect says what convert does: refused exactly when the conversion is
    expect_refused = conversion_refused(path)
    assert (report["refused"] is not None) == expect_refused, report["refused"]
    assert (report["patches"] is None) == expect_refused
    return counts


# -- sample meshes ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_sample_mesh_counts_and_patches_match_a_conversion(name):
    path = SAMPLES / name
    report = inspect_json(path)
    assert set(report) == KEYS
    assert_matches(report, path)
    surface, _ = surface_from_file(path)
    patches = report["patches"]
    assert patches["biquadratic"] == len(surface.biquadratic) and patches["bicubic"] == len(surface.bicubic)
    assert patches["total"] == surface.n_patches and report["refused"] is None
    expected_genus = {"double_torus.obj": 2, "torus.obj": 1}.get(name, 0)
    assert [c["genus"] for c in report["components"]] == [expected_genus]


@pytest.mark.parametrize("name,resolution", [("cube.obj", 8), ("twisted.obj", 3), ("torus.obj", 2), ("high_valence.obj", 5)])
def test_output_sizes_are_those_of_the_tessellation(name, resolution):
    output = inspect_json(SAMPLES / name, "-r", resolution)["output"]
    surface, _ = surface_from_file(SAMPLES / name)
    tess = tessellate_surface(surface, resolution)
    assert output["resolution"] == resolution and output["patches"] == surface.n_patches
    assert (output["vertices"], output["triangles"]) == (len(tess.points), len(tess.triangles))


def test_ply_size_estimate_is_close_to_the_written_file(tmp_path):
    output = inspect_json(SAMPLES / "twisted.obj", "-r", 6)["output"]
    out = tmp_path / "twisted.ply"
    assert run("convert", SAMPLES / "twisted.obj", "-o", out, "-r", 6, "-q").exit_code == 0
    assert abs(output["ply_bytes"] - out.stat().st_size) < 0.01 * out.stat().st_size
    assert output["memory_bytes"] > out.stat().st_size  # the memory guard's estimate of the peak


def test_text_report_names_what_convert_will_do():
    result = run("inspect", SAMPLES / "double_torus.obj")
    assert result.exit_code == 0 and result.stderr == ""
    text = result.stdout
    assert "genus 2" in text and "will convert" in text and re.search(r"patches\s+\d+ \(\d+ biquadratic \+ \d+ bicubic", text)


def test_open_mesh_reports_boundary_and_the_ghost_layer(tmp_path):
    n = 3
    k = lambda i, j: i * (n + 1) + j  # noqa: E731
    points = [(i, j, 0) for i in range(n + 1) for j in range(n + 1)]
    faces = [[k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1)] for i in range(n) for j in range(n)]
    report = inspect_json(write_obj(tmp_path / "grid.obj", points, faces))
    assert report["boundary_edges"] == 12 and report["boundary_loops"] == 1
    assert report["components"][0]["genus"] == 0 and report["repairs"]["boundary_edges"] == 12
    assert report["valences"] == {"interior": {"4": 4}, "boundary": {"1": 4, "2": 8}}
    assert any("ghost layer" in note for note in report["notes"])


def test_moebius_strip_is_non_orientable_and_built_on_the_double_cover(tmp_path):
    n, width = 12, 0.3
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rings = [np.c_[(1 + w * np.cos(t / 2)) * np.cos(t), (1 + w * np.cos(t / 2)) * np.sin(t), w * np.sin(t / 2)] for w in (-width, width)]
    faces = [[i, i + 1, n + i + 1, n + i] for i in range(n - 1)] + [[n - 1, n, 0, 2 * n - 1]]
    path = write_obj(tmp_path / "moebius.obj", np.concatenate(rings), faces)
    report = inspect_json(path)
    [component] = report["components"]
    assert not component["orientable"] and component["genus"] is None and component["nonorientable_genus"] == 1
    assert report["repairs"]["non_orientable"] and report["boundary_loops"] == 1
    surface, _ = surface_from_file(path)
    assert report["patches"]["total"] == surface.n_patches
    tess = tessellate_surface(surface, 4)
    assert report["output"]["vertices"] != 0 and inspect_json(path, "-r", 4)["output"]["vertices"] == len(tess.points)


def test_tags_are_counted_by_kind(tmp_path):
    path = tmp_path / "tagged.obj"
    write_obj(path, CUBE_POINTS, [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])
    path.write_text(path.read_text() + "t crease 5/1/0 0 1 2 3 0 10\nt corner 1/1/0 6 2\nt interpolateboundary 1/0/0 1\n"
                    "t creasemethod 0/0/1 chaikin\n")
    tags = inspect_json(path)["tags"]
    assert (tags["crease_edges"], tags["corner_vertices"], tags["hole_faces"], tags["interpolate_boundary"]) == (4, 1, 0, 1)
    assert tags["other"] == {"creasemethod": 1} and tags["summary"].startswith("crease (4 edges)")


# -- refusals and errors ----------------------------------------------------------------------------


def conversion_refused(path) -> bool:
    """Does ``convert`` (``api.surface_from_file``, the same steps) refuse this file?"""
    try:
        surface_from_file(path)
    except (TopologyError, C1SurfFileError, ValueError):
        return True
    return False


def convert_error(path, tmp_path, *options, output: str = "out.ply") -> str:
    result = run("convert", path, "-o", tmp_path / output, "-q", *options)
    assert result.exit_code == 1
    [line] = result.stderr.strip().splitlines()
    return line.removeprefix("c1surf: error: ")


def test_a_valence_two_vertex_is_counted_and_its_dissolving_reported(tmp_path):
    # a cube with one face split by a diagonal's midpoint: that vertex is interior and in two faces only
    points = CUBE_POINTS + [(0.5, 0.5, 0)]
    faces = [[0, 8, 2, 1], [0, 3, 2, 8], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    path = write_obj(tmp_path / "valence2.obj", points, faces)
    report = inspect_json(path)
    assert report["valence2_interior_vertices"] == 1 and report["refused"] is None
    surface, _ = surface_from_file(path)
    assert report["patches"]["total"] == surface.n_patches
    assert any("dissolved 1 interior vertices of valence 2" in note and "vertices 9," in note for note in report["notes"])


def test_a_refused_mesh_is_reported_with_converts_reason_and_exit_0(tmp_path):
    # a cube with a fin: the edge 0-1 in three faces, whose line of such edges ends inside the cube (its
    # sheets cannot meet exactly there: mesh.creases.non_manifold, construction.topology.check_sheets_meet)
    points = CUBE_POINTS + [(0.5, -1.0, 0.0)]
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [0, 1, 8]]
    path = write_obj(tmp_path / "fin.obj", points, faces)
    report = inspect_json(path)
    assert report["non_manifold_edges"] == 1
    assert report["refused"] == convert_error(path, tmp_path)
    assert "in more than two faces and its sheets cannot be made to meet exactly" in report["refused"]
    assert report["patches"] is None and report["output"] is None
    text = run("inspect", path)
    assert text.exit_code == 0 and f"refused: {report['refused']}" in text.stdout


def test_a_face_the_reader_refuses_is_counted_and_the_reason_given(tmp_path):
    points = CUBE_POINTS
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [0, 1, 1, 0]]
    path = write_obj(tmp_path / "degenerate.obj", points, faces)
    report = inspect_json(path)
    assert report["degenerate_faces"] == 1 and report["faces"] == 7 and report["face_sizes"] == {"2": 1, "4": 6}
    assert report["refused"] == convert_error(path, tmp_path) and report["refused"].startswith(f"{path}:15:")  # 8 v lines, then the 7th face
    assert_matches(report, path)


def test_repeated_corners_are_dropped_as_convert_drops_them(tmp_path):
    faces = [[0, 3, 2, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7, 7]]
    path = write_obj(tmp_path / "repeats.obj", CUBE_POINTS, faces)
    report = inspect_json(path)
    assert report["degenerate_faces"] == 2 and report["collapsed_corners"] == 2 and report["refused"] is None
    assert report["face_sizes"] == {"4": 6} and any("dropped 2 repeated corners" in n for n in report["notes"])


def test_a_missing_file_is_one_line_and_exit_1(tmp_path):
    result = run("inspect", tmp_path / "nothing.obj")
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr.strip().splitlines() == [f"c1surf: error: {tmp_path / 'nothing.obj'}: no such file: check the path"]


def test_an_unreadable_file_is_one_line_with_its_line_and_exit_1(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    result = run("inspect", path, "--json")
    assert result.exit_code == 1 and result.stdout == ""
    [line] = result.stderr.strip().splitlines()
    assert line.startswith(f"c1surf: error: {path}:4: ")


# -- the corpus -------------------------------------------------------------------------------------


def manifest_rows() -> dict:
    """{file: (V, F, notes)} from ../shared/meshes/MANIFEST.md."""
    rows = {}
    for line in (SHARED_MESHES / "MANIFEST.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 9 and cells[4].isdigit():
            rows[cells[0]] = (int(cells[4]), int(cells[5]), cells[8])
    return rows


@pytest.mark.skipif(not CORPUS, reason="../shared/meshes not available")
@pytest.mark.parametrize("relative", CORPUS)
def test_corpus_file_counts(relative):
    path = SHARED_MESHES / relative
    report = inspect_json(path)
    counts = assert_matches(report, path)
    n_vertices, n_faces, notes = manifest_rows()[relative]
    assert (report["vertices"], report["faces"]) == (n_vertices, n_faces)
    if (genus := re.search(r"genus (\d+)", notes)) is not None:
        assert sum(c["genus"] for c in report["components"]) == int(genus.group(1))
    loops = re.search(r"(\d+) loops", notes)
    if report["degenerate_faces"] == 0:  # MANIFEST counts the faces as written, before repeated corners are dropped
        pinches = re.search(r"pinch vertices (\d+)", notes)
        assert report["pinched_vertices"] == (int(pinches.group(1)) if pinches else 0)
    if counts["pinched_vertices"] == 0 and report["degenerate_faces"] == 0:
        assert report["boundary_loops"] == (int(loops.group(1)) if loops else 0)
        non_manifold = re.search(r"non-manifold edges (\d+)", notes)
        assert report["non_manifold_edges"] == (int(non_manifold.group(1)) if non_manifold else 0)
    if report["refused"] is None and report["valence2_interior_vertices"] == 0:
        # (the repair acts on the mesh after dissolving valence-2 vertices, which may remove pinches)
        assert report["repairs"]["split_vertices"] == report["pinched_vertices"]


def test_docs_document_every_json_key():
    text = (ROOT / "docs" / "cli.md").read_text()
    section = text[text.index("## Inspecting a mesh"):]
    section = section[:re.search(r"\n#+ ", section[4:]).start() + 4]
    for key in KEYS | COMPONENT_KEYS:
        assert f"`{key}`" in section, key


def test_a_ply_face_the_reader_refuses_is_reported_as_convert_refuses_it(tmp_path):
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [0, 4, 1, 4]]
    header = ["ply", "format ascii 1.0", "element vertex 8", "property float x", "property float y", "property float z",
              f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    rows = [" ".join(map(str, p)) for p in CUBE_POINTS] + [f"{len(f)} " + " ".join(map(str, f)) for f in faces]
    path = tmp_path / "repeat.ply"
    path.write_text("\n".join(header + rows) + "\n")
    report = inspect_json(path)
    assert report["degenerate_faces"] == 1 and report["faces"] == 7
    assert report["refused"] == convert_error(path, tmp_path) and "visits vertex 4 twice" in report["refused"]


def test_refinements_option_gives_the_patches_of_that_conversion():
    path = SAMPLES / "cube.obj"
    patches = inspect_json(path, "--refinements", "auto")["patches"]
    surface, _ = surface_from_file(path, refinements="auto")
    assert patches["total"] == surface.n_patches and patches["refinements"] == surface.topology.refinements


def test_too_few_refinements_are_refused_as_convert_refuses_them(tmp_path):
    path = SAMPLES / "cube.obj"
    report = inspect_json(path, "--refinements", "1")
    assert report["refused"] == convert_error(path, tmp_path, "--refinements", "1") and "R2" in report["refused"]
    assert report["repairs"] == inspect_json(path)["repairs"]  # the repairs ran before the refusal


def test_an_output_too_big_for_memory_is_refused_as_convert_refuses_it(tmp_path):
    """As an in-memory conversion refuses it (an .off output); .ply, .obj, .stl and .glb are streamed
    (tests/cli/test_streamed_convert.py), so the mesh itself is not refused: only outputs held in memory are."""
    path = SAMPLES / "cube.obj"
    report = inspect_json(path, "-r", 100000)
    available = lambda line: re.sub(r"about [\d.]+ GiB is available", "about ... GiB is available", line)  # noqa: E731
    refusal = report["output"]["in_memory_refusal"]
    assert available(refusal) == available(convert_error(path, tmp_path, "-r", "100000", output="out.off"))
    assert "--force" in refusal and report["refused"] is None
    text = CliRunner().invoke(main, ["inspect", str(path), "-r", "100000"])
    assert "held in memory" in text.stdout and "plain .obj, .ply, .stl, .glb outputs stream" in text.stdout
    assert report["output"]["triangles"] == 2 * 96 * 99999 ** 2 and report["patches"]["total"] == 96
