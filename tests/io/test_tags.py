"""Sharp-feature tags: OpenSubdiv OBJ ``t`` lines and PLY edge creases / vertex corners, read and checked."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

from c1surf.io.errors import MeshInputError
from c1surf.io.meshes.obj import read_obj
from c1surf.io.meshes.ply import read_ply
from c1surf.io.meshes.tags.obj_tags import parse_tag_lines

OPENSUBDIV = Path(__file__).resolve().parents[2].parent / "shared" / "meshes" / "opensubdiv"
TAGGED = sorted(p.name for p in OPENSUBDIV.glob("*.obj") if re.search(rb"^t ", p.read_bytes(), re.M))

# A cube, vertices 1..8 in OBJ numbering (0..7 in tags), faces 0..5 (lines 9..14).
CUBE = """v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
"""


def cube_with(tmp_path, *tag_lines) -> Path:
    path = tmp_path / "cube.obj"
    path.write_text(CUBE + "".join(line + "\n" for line in tag_lines))
    return path


def test_an_untagged_file_has_empty_tags(tmp_path):
    tags = read_obj(cube_with(tmp_path)).tags
    assert tags.is_empty() and tags.summary() == "" and tags.crease_edges.shape == (0, 2)


def test_every_tag_kind_is_read(tmp_path):
    tags = read_obj(cube_with(tmp_path, "t crease 2/1/0 0 1 10.0", "t crease 4/1/0 4 5 6 7 2.5  # a chain",
                              "t crease 3/2/0 0 3 7 1 2", "t corner 2/1/0 0 6 3.0", "t corner 2/2/0 1 2 4 5",
                              "t hole 2/0/0 1 5", "t interpolateboundary 1/0/0 2",
                              "t creasemethod 0/0/1 chaikin", "t vertexedit 1/1/2 3 0.5 set P")).tags
    assert tags.crease_edges.tolist() == [[0, 1], [4, 5], [5, 6], [6, 7], [0, 3], [3, 7]]
    assert tags.crease_sharpness.tolist() == [10, 2.5, 2.5, 2.5, 1, 2]
    assert tags.crease_lines.tolist() == [15, 16, 16, 16, 17, 17]
    assert tags.corner_vertices.tolist() == [0, 6, 1, 2] and tags.corner_sharpness.tolist() == [3, 3, 4, 5]
    assert tags.corner_lines.tolist() == [18, 18, 19, 19]
    assert tags.hole_faces.tolist() == [1, 5] and tags.hole_lines.tolist() == [20, 20]
    assert tags.interpolate_boundary == 2
    assert tags.other == [("creasemethod", 22), ("vertexedit", 23)]
    assert tags.summary() == ("crease (6 edges), corner (4 vertices), hole (2 faces), interpolateboundary 2, "
                              "creasemethod (1 tag), vertexedit (1 tag)")


@pytest.mark.parametrize("line, message", [
    ("t crease", "malformed tag line"),
    ("t crease 2/1 0 1 1.0", "malformed tag line"),
    ("t crease 2/1/0 0 1", "declares 2/1/0 values but the line has 2"),
    ("t crease 2/1/0 0 1 1.0 7", "declares 2/1/0 values but the line has 4"),
    ("t crease 2/1/0 0 x 1.0", "cannot read 'x' as an integer"),
    ("t crease 2/1/0 0 1 soft", "cannot read 'soft' as a number"),
    ("t crease 1/1/0 0 1.0", "malformed `crease` tag"),
    ("t crease 3/3/0 0 1 2 1 1 1", "malformed `crease` tag"),
    ("t corner 2/3/0 0 1 1 1 1", "malformed `corner` tag"),
    ("t hole 1/1/0 0 1.0", "malformed `hole` tag"),
    ("t interpolateboundary 1/0/0 3", "malformed `interpolateboundary` tag"),
    ("t crease 2/1/0 0 8 1.0", "crease names vertex 8 but the file has 8 vertices"),
    ("t crease 2/1/0 -1 0 1.0", "crease names vertex -1"),
    ("t corner 1/1/0 9 1.0", "corner names vertex 9"),
    ("t crease 2/1/0 0 6 1.0", "crease pair 0 6 is not an edge of the mesh"),
    ("t crease 2/1/0 0 0 1.0", "crease pair 0 0 is not an edge"),
    ("t hole 1/0/0 6", "hole names face 6 but the file has 6 faces"),
    ("t crease 2/1/0 0 1 -1", "crease sharpness -1 is not a number >= 0"),
    ("t corner 1/1/0 0 nan", "corner sharpness nan is not a number >= 0"),
])
def test_a_bad_tag_is_refused_at_its_line(tmp_path, line, message):
    path = cube_with(tmp_path, "t crease 2/1/0 0 1 10.0", line, "t hole 1/0/0 0")
    with pytest.raises(MeshInputError) as caught:
        read_obj(path)
    assert caught.value.line == 16 and message in caught.value.message
    assert str(caught.value).startswith(f"{path}:16: ") and "\n" not in str(caught.value)


def grep_counts(path: Path) -> dict:
    """Independent count of the tags of an OpenSubdiv file: {kind: entries}, other kinds by lines."""
    counts = {}
    for line in path.read_text().splitlines():
        words = line.split("#")[0].split()
        if not words or words[0] != "t":
            continue
        n_int = int(words[2].split("/")[0])
        entries = {"crease": n_int - 1, "corner": n_int, "hole": n_int}.get(words[1], 1)
        counts[words[1]] = counts.get(words[1], 0) + entries
    return counts


@pytest.mark.skipif(not TAGGED, reason="../shared/meshes/opensubdiv is not there")
@pytest.mark.parametrize("name", TAGGED)
def test_every_tagged_opensubdiv_file_reads_its_tags(tmp_path, name):
    path = OPENSUBDIV / name
    try:
        tags = read_obj(path).tags
    except MeshInputError as error:  # a problem of the mesh itself: the same without the tag lines
        untagged = tmp_path / name
        untagged.write_bytes(re.sub(rb"(?m)^t .*$", b"", path.read_bytes()))
        with pytest.raises(MeshInputError) as again:
            read_obj(untagged)
        assert again.value.message == error.message and again.value.line == error.line
        lines = [(i + 1, text) for i, text in enumerate(path.read_bytes().splitlines()) if text.startswith(b"t ")]
        tags = parse_tag_lines(lines, str(path))
    got = {"crease": len(tags.crease_edges), "corner": len(tags.corner_vertices), "hole": len(tags.hole_faces)}
    if tags.interpolate_boundary is not None:
        got["interpolateboundary"] = 1
    for other, _ in tags.other:
        got[other] = got.get(other, 0) + 1
    assert {k: v for k, v in got.items() if v} == grep_counts(path)


def write_ply(tmp_path, edges=None, corner=None, text=True) -> Path:
    """The cube as PLY, with an optional edge element (v1, v2, crease) and a vertex corner property."""
    points = np.loadtxt(CUBE.splitlines()[:8], usecols=(1, 2, 3))
    vertex_type = [("x", "f8"), ("y", "f8"), ("z", "f8")] + ([("corner", "f4")] if corner is not None else [])
    vertices = np.zeros(8, vertex_type)
    for i, c in enumerate("xyz"):
        vertices[c] = points[:, i]
    if corner is not None:
        vertices["corner"] = corner
    faces = np.zeros(6, [("vertex_indices", "i4", (4,))])
    faces["vertex_indices"] = [[int(v) - 1 for v in line.split()[1:]] for line in CUBE.splitlines()[8:]]
    elements = [PlyElement.describe(vertices, "vertex"), PlyElement.describe(faces, "face")]
    if edges is not None:
        edge = np.array([tuple(e) for e in edges], [("vertex1", "i4"), ("vertex2", "i4"), ("crease", "f4")])
        elements.append(PlyElement.describe(edge, "edge"))
    path = tmp_path / "cube.ply"
    PlyData(elements, text=text).write(str(path))
    return path


@pytest.mark.parametrize("text", [True, False])
def test_ply_edge_creases_and_vertex_corners(tmp_path, text):
    corner = np.zeros(8)
    corner[[2, 5]] = [1.5, 10]
    tags = read_ply(write_ply(tmp_path, edges=[(0, 1, 0.5), (1, 2, 0), (5, 6, 1)], corner=corner, text=text)).tags
    assert tags.crease_edges.tolist() == [[0, 1], [5, 6]] and tags.crease_sharpness.tolist() == [0.5, 1]
    assert tags.corner_vertices.tolist() == [2, 5] and tags.corner_sharpness.tolist() == [1.5, 10]
    assert tags.summary() == "crease (2 edges), corner (2 vertices)"
    # ASCII: a header of 14 lines (with the corner property), then 8 vertices, 6 faces, 3 edges
    assert (tags.crease_lines.tolist() == [29, 31]) if text else tags.crease_lines is None


def test_ply_without_tags_has_none(tmp_path):
    assert read_ply(write_ply(tmp_path)).tags.is_empty()


@pytest.mark.parametrize("edge, message", [((0, 6, 1.0), "crease pair 0 6 is not an edge"),
                                           ((0, 8, 1.0), "crease names vertex 8")])
def test_ply_bad_crease_is_refused_at_its_line(tmp_path, edge, message):
    with pytest.raises(MeshInputError) as caught:
        read_ply(write_ply(tmp_path, edges=[(0, 1, 1.0), edge]))
    assert message in caught.value.message and caught.value.line == 13 + 8 + 6 + 2  # header, vertices, faces, edge 1
