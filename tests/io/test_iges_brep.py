"""IGES as a B-rep from c1surf's own topology (io/patches/brep/iges_brep.py), read back by Open CASCADE.

Every closed sample mesh, in strips (the default), whole pieces and with ``--no-merge``, is one
valid solid that Open CASCADE's IGES reader builds without any sewing: its
faces, edges and vertices are those of ``topology.brep_topology``, every edge
lies in exactly two faces, and every face evaluates to its patches to 1e-12 of
the bounding-box diagonal. An open mesh is one valid open shell, a rational
surface round-trips, two components are two solids, inward normals still give
an outward solid, and ``check``/``diff``/the c1surf reader take the files as
before. The entity structure is checked by test_iges's independent parser.

Open CASCADE comes from ``cadquery-ocp`` (test extra); without it these tests fail.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from click.testing import CliRunner

from c1surf.api import surface_from_file
from c1surf.cli.main import main
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.bezier import evaluate_patches
from c1surf.evaluation.measure import solid_moments
from c1surf.evaluation.merge import merge_biquadratic
from c1surf.io.patches.merged import cad_patch_set
from c1surf.evaluation.patch_set import surface_patch_set
from c1surf.evaluation.rational import evaluate_rational
from c1surf.io.errors import MeshInputError
from c1surf.io.meshes.obj import read_obj
from c1surf.io.patches.brep.iges_brep import LIST_BLOCK, edge_polygons, iges_brep
from c1surf.io.patches.brep.topology import FACE_PIECE, brep_topology, edge_curves
from c1surf.io.patches.formats import load_patch_set
from c1surf.io.patches.iges import read_patch_set_iges, write_patch_set_iges
from c1surf.io.patches.merged import piece_patches

from conftest import CLOSED_SAMPLES, SAMPLES, grid, ocp_shapes, weighted_cube
from test_iges import _parse_iges

try:
    from OCP.BRep import BRep_Tool
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepGProp import BRepGProp
    from OCP.BRepTools import BRepTools
    from OCP.collections import IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as AncestorMap
    from OCP.GProp import GProp_GProps
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.IGESControl import IGESControl_Reader
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID, TopAbs_VERTEX
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS

    OCP_ERROR = None
except ImportError as exc:  # pragma: no cover
    OCP_ERROR = exc

UV = np.array([0.0, 0.3, 0.77, 1.0])  # per span of a face, its corners included


@pytest.fixture(autouse=True)
def need_ocp():
    if OCP_ERROR is not None:
        pytest.fail(f"Open CASCADE (OCP) is not importable ({OCP_ERROR}): pip install -e '.[test]'", pytrace=False)


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def convert(tmp_path, mesh, *options, name="surface.igs"):
    out = tmp_path / name
    result = run("convert", mesh, "-o", tmp_path / "mesh.ply", "-r", "2", "-q", "--patches", out, *options)
    assert result.exit_code == 0, result.output
    return out


PACKINGS = ["strips", "pieces", "no-merge"]  # the default, --cad-pieces, --no-merge
FLAGS = {"strips": [], "pieces": ["--cad-pieces"], "no-merge": ["--no-merge"]}


def packed(surface, packing: str):
    """The surface's patch set as the IGES writer lays it out for ``packing`` (one of PACKINGS)."""
    patch_set = surface_patch_set(surface)
    if packing == "no-merge":
        return patch_set
    patch_set = dataclasses.replace(patch_set, merged=merge_biquadratic(surface))
    return cad_patch_set(patch_set) if packing == "strips" else patch_set


def expected_patch_set(mesh, packing: str):
    """The patch set convert writes with ``packing``'s flags."""
    return packed(surface_from_file(mesh)[0], packing)


def read_iges(path):
    """Open CASCADE's shape of an IGES file, read without a failure or warning on any entity: (reader, shape)."""
    reader = IGESControl_Reader()
    assert reader.ReadFile(str(path)) == IFSelect_RetDone
    assert reader.WS().ModelCheckList().IsEmpty(False)
    assert reader.TransferRoots()
    return reader, reader.OneShape()


def count(shape, kind) -> int:
    return len(ocp_shapes(shape, kind))


def edge_face_uses(shape) -> np.ndarray:
    """(edges,) int: how many faces (with repetition: a seam counts twice) each distinct edge lies in."""
    ancestors = AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
    return np.array([ancestors.FindFromIndex(i).Size() for i in range(1, ancestors.Extent() + 1)])


def face_values(patch_set, topology, f: int) -> tuple[np.ndarray, np.ndarray]:
    """c1surf's face ``f`` on UV x UV of every unit span: ((spans, 2) span origins, (spans, 4, 4, 3) points)."""
    index = int(topology.face_index[f])
    if topology.face_kind[f] == FACE_PIECE:
        piece = patch_set.merged[index]
        nets, weights = piece_patches(piece)
        m, n = piece.patches.shape
        origins = np.array([(a, b) for a in range(m) for b in range(n)], dtype=float)
    else:
        first = 0
        for k, g in enumerate(patch_set.groups):
            if first <= index < first + len(g):
                nets = np.asarray(g[index - first : index - first + 1])
                weights = None if patch_set.weights is None else np.asarray(patch_set.weights[k][index - first : index - first + 1])
                break
            first += len(g)
        origins = np.zeros((1, 2))
    if weights is None:
        return origins, evaluate_patches(nets, UV, UV)
    return origins, evaluate_rational(nets, weights, UV, UV)[0][..., :3]


def assert_faces_are_the_patches(shape, patch_set, topology) -> float:
    """Every Open CASCADE face (in shell order) is c1surf's face of that number: domain and values; the worst gap."""
    points = np.concatenate([g.reshape(-1, 3) for g in patch_set.groups])
    diagonal = float(np.linalg.norm(points.max(0) - points.min(0)))
    faces = [TopoDS.Face(f) for f in ocp_shapes(shape, TopAbs_FACE)]
    assert len(faces) == topology.n_faces
    worst = 0.0
    for f, face in enumerate(faces):
        m, n = topology.face_size[f]
        assert BRepTools.UVBounds_s(face) == pytest.approx((0.0, m, 0.0, n), abs=1e-12)
        geom = BRep_Tool.Surface_s(face)
        origins, want = face_values(patch_set, topology, f)
        got = np.array([[[[p.X(), p.Y(), p.Z()] for p in (geom.Value(a + u, b + v) for v in UV)] for u in UV]
                        for a, b in origins.tolist()])
        worst = max(worst, float(np.abs(got - want).max()) / diagonal)
    assert worst <= 1e-12, worst
    return worst


def signed_volume(patch_set) -> float:
    return solid_moments(patch_set.groups, patch_set.weights)[0]


def occ_volume(shape) -> float:
    """Open CASCADE's volume of the shape (adaptive integration, to 1e-10 relative)."""
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, 1e-10)
    return props.Mass()


# ----------------------------------------------------------------------------
# closed meshes: one valid solid


@pytest.mark.parametrize("packing", PACKINGS)
@pytest.mark.parametrize("name", CLOSED_SAMPLES)
def test_closed_sample_mesh_is_one_valid_solid_sewn_by_c1surf(tmp_path, name, packing):
    mesh = SAMPLES / name
    path = convert(tmp_path, mesh, *FLAGS[packing])
    patch_set = expected_patch_set(mesh, packing)
    topology = iges_brep(patch_set, brep_topology(patch_set).n_faces).topology  # maximal edges
    reader, shape = read_iges(path)
    assert reader.NbRootsForTransfer() == 1  # the solid
    assert count(shape, TopAbs_SOLID) == 1 and count(shape, TopAbs_SHELL) == 1
    assert BRepCheck_Analyzer(shape).IsValid()
    assert BRep_Tool.IsClosed_s(TopoDS.Shell(ocp_shapes(shape, TopAbs_SHELL)[0]))
    # the reader shares what the file shares: faces, edges and vertices exactly as c1surf's topology says
    assert count(shape, TopAbs_FACE) == topology.n_faces
    uses = edge_face_uses(shape)
    assert uses.size == topology.n_edges and np.all(uses == 2)  # every edge in exactly two faces (a seam: twice in one)
    vertices = AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_VERTEX, TopAbs_EDGE, vertices)
    assert vertices.Extent() == len(topology.vertex_points)
    assert_faces_are_the_patches(shape, patch_set, topology)
    # the solid is outward: Open CASCADE's volume is c1surf's
    assert occ_volume(shape) == pytest.approx(signed_volume(patch_set), rel=1e-8)


def test_a_piece_closing_on_itself_has_seams(tmp_path):
    """The torus in whole pieces packs into one face whose loop uses its two seam edges (closed runs, one vertex)
    twice each, as Open CASCADE's own tori do; still one valid solid."""
    path = convert(tmp_path, SAMPLES / "torus.obj", "--cad-pieces")
    patch_set = expected_patch_set(SAMPLES / "torus.obj", "pieces")
    topology = iges_brep(patch_set, 1).topology
    assert (topology.n_faces, topology.n_edges, len(topology.vertex_points)) == (1, 2, 1)
    assert np.array_equal(np.bincount(topology.loop_edge), [2, 2]) and np.all(topology.edge_vertices == 0)
    _, shape = read_iges(path)
    assert BRepCheck_Analyzer(shape).IsValid() and count(shape, TopAbs_SOLID) == 1
    assert np.all(edge_face_uses(shape) == 2)


# ----------------------------------------------------------------------------
# open, rational, several components, inward normals


@pytest.mark.parametrize("packing", PACKINGS)
def test_open_grid_is_one_valid_open_shell(tmp_path, packing):
    surface = Surface(*grid(4, lambda x, y: 0.1 * x * y), SurfaceOptions())
    patch_set = packed(surface, packing)
    topology = iges_brep(patch_set, brep_topology(patch_set).n_faces).topology
    path = tmp_path / "grid.igs"
    write_patch_set_iges(path, patch_set, strips=packing == "strips")  # cutting strips again changes nothing
    entities = _parse_iges(path.read_bytes())["entities"]
    shells = [e for e in entities if e["type"] == 514]
    assert [(e["form"], e["status"]) for e in shells] == [(2, "00000000")]  # open shell (form 2), the root
    assert not any(e["type"] == 186 for e in entities)
    reader, shape = read_iges(path)
    assert reader.NbRootsForTransfer() == 1
    assert count(shape, TopAbs_SOLID) == 0 and count(shape, TopAbs_SHELL) == 1
    assert not BRep_Tool.IsClosed_s(TopoDS.Shell(ocp_shapes(shape, TopAbs_SHELL)[0]))
    assert BRepCheck_Analyzer(shape).IsValid()
    # boundary edges in one face, the others in two, as many of each as the topology has
    assert np.array_equal(np.sort(edge_face_uses(shape)), np.sort(topology.edge_uses))
    assert set(topology.edge_uses.tolist()) == {1, 2}
    assert_faces_are_the_patches(shape, patch_set, topology)


@pytest.mark.parametrize("packing", PACKINGS)
def test_rational_surface_round_trips(tmp_path, packing):
    mesh = weighted_cube(tmp_path, True)
    path = convert(tmp_path, mesh, *FLAGS[packing])
    patch_set = expected_patch_set(mesh, packing)
    assert patch_set.weights is not None
    topology = iges_brep(patch_set, brep_topology(patch_set).n_faces).topology
    _, shape = read_iges(path)
    assert count(shape, TopAbs_SOLID) == 1 and BRepCheck_Analyzer(shape).IsValid()
    assert np.all(edge_face_uses(shape) == 2) and edge_face_uses(shape).size == topology.n_edges
    faces = [TopoDS.Face(f) for f in ocp_shapes(shape, TopAbs_FACE)]
    assert any(BRep_Tool.Surface_s(f).IsURational() for f in faces)
    assert_faces_are_the_patches(shape, patch_set, topology)
    assert occ_volume(shape) == pytest.approx(signed_volume(patch_set), rel=1e-8)
    # and c1surf reads its patches and weights back exactly
    back = read_patch_set_iges(path)
    if packing == "no-merge":
        assert all(np.array_equal(a, b) for a, b in zip(back.groups, patch_set.groups))
        assert all(np.array_equal(a, b) for a, b in zip(back.weights, patch_set.weights))


def write_obj(path, points, faces) -> None:
    path.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in np.asarray(points, float).tolist())
                    + "".join("f " + " ".join(str(v + 1) for v in f) + "\n" for f in faces))
    return path


def cube_faces():
    mesh = read_obj(SAMPLES / "cube.obj")
    offsets = mesh.face_offsets()
    return mesh.points, [mesh.face_vertices[a:b].tolist() for a, b in zip(offsets[:-1], offsets[1:])]


def test_two_components_are_two_solids_in_one_group(tmp_path):
    points, faces = cube_faces()
    shifted = [[v + len(points) for v in f] for f in faces]
    mesh = write_obj(tmp_path / "two.obj", np.r_[points, points + [5.0, 0.0, 0.0]], faces + shifted)
    path = convert(tmp_path, mesh)
    entities = _parse_iges(path.read_bytes())["entities"]
    assert [e["type"] for e in entities].count(186) == 2 and [e["type"] for e in entities].count(514) == 2
    group = [e for e in entities if e["type"] == 402]
    assert len(group) == 1 and group[0]["form"] == 7 and group[0]["params"][0] == "2"
    reader, shape = read_iges(path)
    assert reader.NbRootsForTransfer() == 1  # the group
    assert count(shape, TopAbs_SOLID) == 2 and BRepCheck_Analyzer(shape).IsValid()
    assert occ_volume(shape) == pytest.approx(signed_volume(expected_patch_set(mesh, True)), rel=1e-8)


def test_inward_normals_still_give_an_outward_solid(tmp_path):
    points, faces = cube_faces()
    mesh = write_obj(tmp_path / "inward.obj", points, [f[::-1] for f in faces])
    patch_set = expected_patch_set(mesh, True)
    assert signed_volume(patch_set) < 0  # the patch normals point into the solid
    path = convert(tmp_path, mesh)
    solid = next(e for e in _parse_iges(path.read_bytes())["entities"] if e["type"] == 186)
    assert solid["params"][1:] == ["0", "0"]  # shell orientation flag 0: reversed; no void shells
    _, shape = read_iges(path)
    assert BRepCheck_Analyzer(shape).IsValid()
    assert occ_volume(shape) == pytest.approx(-signed_volume(patch_set), rel=1e-8)


# ----------------------------------------------------------------------------
# the file: entity structure, other layouts, c1surf's reader, check and diff


def test_entities_reference_each_other_as_iges_5_3_says(tmp_path):
    """Independent of Open CASCADE: every pointer names an entity of the right type, loops close in model
    and parameter space, and edge curves end exactly at their vertices."""
    for name, packing in (("cube", "strips"), ("cube", "pieces"), ("cube", "no-merge"), ("torus", "strips"),
                          ("torus", "pieces")):
        options = FLAGS[packing]
        patch_set = expected_patch_set(SAMPLES / f"{name}.obj", packing)
        topology = iges_brep(patch_set, brep_topology(patch_set).n_faces).topology
        entities = _parse_iges(convert(tmp_path, SAMPLES / f"{name}.obj", *options).read_bytes())["entities"]
        by_seq = {e["seq"]: e for e in entities}
        ints = lambda e: [int(t) for t in e["params"]]  # noqa: E731
        reals = lambda e: [float(t.replace("D", "E")) for t in e["params"]]  # noqa: E731
        kinds = {t: [e for e in entities if e["type"] == t] for t in (128, 126, 502, 504, 508, 510, 514, 186, 402)}
        assert len(kinds[128]) == len(kinds[510]) == len(kinds[508]) == topology.n_faces and not kinds[402]
        assert all(e["status"] == "00010000" for t in (128, 502, 504, 508, 510, 514) for e in kinds[t])
        assert [(e["form"], e["status"]) for e in kinds[186] + kinds[514]] == [(0, "00000000"), (1, "00010000")]
        vertices = {e["seq"]: np.array(reals(e)[1:]).reshape(-1, 3) for e in kinds[502]}
        size = float(np.ptp(topology.vertex_points, axis=0).max())
        assert sum(len(v) for v in vertices.values()) == len(topology.vertex_points)
        assert all(int(e["params"][0]) <= LIST_BLOCK for e in kinds[502] + kinds[504])
        edges = {}  # (list, index) -> (curve entity, start point, end point)
        for e in kinds[504]:
            p = ints(e)
            for i in range(p[0]):
                curve, svp, sv, tvp, tv = p[1 + 5 * i : 6 + 5 * i]
                edges[e["seq"], i + 1] = (by_seq[curve], vertices[svp][sv - 1], vertices[tvp][tv - 1])
        assert len(edges) == topology.n_edges
        for curve, start, end in edges.values():
            assert curve["type"] == 126 and curve["status"] == "00010000"
            k, d = int(curve["params"][0]), int(curve["params"][1])
            first = 6 + (k + d + 2) + (k + 1)  # after K, M, PROP1-4, the knots and the weights
            poles = np.array(reals(curve)[first : first + 3 * (k + 1)]).reshape(-1, 3)
            # at its vertices: those are corner coefficients of one patch each, and the patches meeting
            # there agree to round-off (the construction's G0), so to round-off
            assert max(np.abs(poles[0] - start).max(), np.abs(poles[-1] - end).max()) <= 1e-15 * size
        shell = ints(kinds[514][0])
        assert shell[0] == topology.n_faces and set(shell[2::2]) == {1}
        pcurves = set()
        for f, seq in enumerate(shell[1::2]):
            face = ints(by_seq[seq])
            assert by_seq[face[0]]["type"] == 128 and face[1:3] == [1, 1]  # its surface, one loop, the outer one
            loop = ints(by_seq[face[3]])
            ends, uv = [], []
            for i in range(loop[0]):
                kind, lst, index, forward, n_curves, iso, pcurve = loop[1 + 7 * i : 8 + 7 * i]
                assert (kind, n_curves, iso) == (0, 1, 1) and by_seq[pcurve]["status"] == "00010500"
                _, start, end = edges[lst, index]
                ends.append((start, end) if forward else (end, start))
                q = reals(by_seq[pcurve])  # degree 1: knots 0 0 1 1, weights 1 1, then (u, v, 0) twice
                uv.append((q[12:14], q[15:17]))
                pcurves.add(pcurve)
            for (_, end), (start, _) in zip(ends, ends[1:] + ends[:1]):
                assert np.array_equal(end, start)  # the loop closes in model space ...
            for (_, end), (start, _) in zip(uv, uv[1:] + uv[:1]):
                assert end == start  # ... and in the face's parameter space
        assert len(pcurves) == len(kinds[126]) - topology.n_edges  # every pcurve used, shared where equal
        if packing == "no-merge":
            assert len(pcurves) == 4  # one per side of the unit square


def test_other_layouts_and_the_reader(tmp_path):
    """--no-group: independent surfaces only; brep=False: the surfaces in a 402 group; the reader reads all
    three to the same bits, passes the B-rep over, and still refuses a free curve."""
    mesh = SAMPLES / "twisted.obj"
    brep = convert(tmp_path, mesh, "--no-merge", name="brep.igs")
    loose = convert(tmp_path, mesh, "--no-merge", "--no-group", name="loose.igs")
    grouped = tmp_path / "grouped.igs"
    patch_set = expected_patch_set(mesh, "no-merge")
    write_patch_set_iges(grouped, patch_set, brep=False)
    types = {p.name: [e["type"] for e in _parse_iges(p.read_bytes())["entities"]] for p in (brep, loose, grouped)}
    assert set(types["loose.igs"]) == {128} and set(types["grouped.igs"]) == {128, 402}
    assert set(types["brep.igs"]) == {128, 126, 502, 504, 508, 510, 514, 186}
    for path in (brep, loose, grouped):
        back = load_patch_set(path)
        assert all(np.array_equal(a, b) for a, b in zip(back.groups, patch_set.groups))
    reader, _ = read_iges(loose)
    assert reader.NbRootsForTransfer() == patch_set.n_patches
    # a 126 that is no part of the B-rep (independent status) is refused, as any free curve
    lines = brep.read_text().splitlines(keepends=True)
    k = next(i for i, line in enumerate(lines) if line[72] == "D" and line.startswith("     126") and line[64:72] == "00010000")
    lines[k] = lines[k][:64] + "00000000" + lines[k][72:]
    free = tmp_path / "free.igs"
    free.write_text("".join(lines))
    with pytest.raises(MeshInputError, match="entity type 126 is not supported"):
        read_patch_set_iges(free)


def test_check_and_diff_take_the_brep_files(tmp_path):
    mesh = SAMPLES / "twisted.obj"
    packed = convert(tmp_path, mesh, name="packed.igs")
    iges = convert(tmp_path, mesh, "--no-merge", "--patches", tmp_path / "s.json", name="s.igs")
    for path in (packed, iges):
        report = run("check", path)
        assert report.exit_code == 0 and "G1: yes" in report.stdout
    result = run("diff", iges, tmp_path / "s.json")
    assert result.exit_code == 0 and result.stdout.startswith("equal within 1e-12"), result.output


@pytest.mark.parametrize("rational", [False, True])
def test_edge_polygons_are_the_topology_edge_curves(tmp_path, rational):
    """The writer's gathered polygons equal topology.edge_curves exactly, edge by edge."""
    for packing in PACKINGS:
        patch_set = expected_patch_set(weighted_cube(tmp_path, rational), packing)
        topology = brep_topology(patch_set)
        points, weights = edge_curves(patch_set, topology)
        seen = np.zeros(topology.n_edges, int)
        for edges, polygons, polygon_weights in edge_polygons(patch_set, topology):
            seen[edges] += 1
            for k, e in enumerate(edges.tolist()):
                assert np.array_equal(polygons[k], points[e])
                assert (polygon_weights is None) == (weights is None)
                if weights is not None:
                    assert np.array_equal(polygon_weights[k], weights[e])
        assert np.all(seen == 1)


def test_surfaces_must_be_the_topology_faces():
    patch_set = expected_patch_set(SAMPLES / "cube.obj", False)
    with pytest.raises(ValueError, match="faces"):
        iges_brep(patch_set, patch_set.n_patches - 1)


def test_reader_reads_any_line_layout_alike(tmp_path):
    """The byte-matrix path (80 columns, LF) and the line-by-line one (CR LF, blank lines) read the same
    patches, and both report a bad record at its line."""
    path = convert(tmp_path, SAMPLES / "cube.obj", "--no-merge")
    want = read_patch_set_iges(path)
    text = path.read_text()
    lines = text.splitlines(keepends=True)
    variants = {"crlf": text.replace("\n", "\r\n"), "blank": "".join(lines[:40] + ["\n"] + lines[40:])}
    for name, content in variants.items():
        other = tmp_path / f"{name}.igs"
        other.write_text(content, newline="")
        back = read_patch_set_iges(other)
        assert all(np.array_equal(a, b) for a, b in zip(back.groups, want.groups)), name
    lines[100] = lines[100][:72] + "X" + lines[100][73:]
    for name, content in (("bad.igs", "".join(lines)), ("bad_crlf.igs", "".join(lines).replace("\n", "\r\n"))):
        (tmp_path / name).write_text(content, newline="")
        with pytest.raises(MeshInputError, match="section letter") as error:
            read_patch_set_iges(tmp_path / name)
        assert f"{name}:101: not an IGES file" in str(error.value)
