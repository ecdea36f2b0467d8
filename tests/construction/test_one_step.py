"""One Doo-Sabin step for open meshes, C0 creases, corners and darts (issue 40; docs/sharp-features.md, "One
Doo-Sabin step"): R1-R3 hold on the cells the kept patches read after one step, so ``refinements="auto"`` takes
one step on the seven pure-quad kinds of ``one_step_meshes``: four patches a face instead of sixteen, G1 on the
smooth sides and C0 along the tags, measured from the geometry alone."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from c1surf.api import check_surface
from c1surf.construction.refine.doo_sabin import FACE_FROM_FACE, FACE_FROM_VERTEX
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.mesh.errors import TopologyError

from dart_meshes import polar_dart
from one_step_meshes import KINDS, saddle
from test_c0_creases import all_edges, crease_and_smooth


def build(kind, refinements="auto"):
    sizes, corners, points, features = KINDS[kind]()
    return Surface(sizes, corners, points, SurfaceOptions(refinements=refinements, exact_creases=True),
                   features=features), (sizes, corners, points, features)


def boundary_edges(sizes, corners) -> int:
    faces = np.split(corners, np.cumsum(sizes)[:-1])
    edges = np.sort(np.concatenate([np.stack([f, np.roll(f, -1)], axis=1) for f in faces]), axis=1)
    return int((np.unique(edges, axis=0, return_counts=True)[1] == 1).sum())


# crease side pairs found from the geometry (a normal jump above 1e-6 rad somewhere along the side): two per
# tagged edge after one step (four after two); at a dart the piece beside the dart's vertex is its hole's crease
# spoke instead (the roof: 4 edges, 7 + 1)
CREASE_PAIRS = {"sharp cube": 48, "tagged box": 24, "half-sharp roof": 8}


@pytest.mark.parametrize("kind", list(KINDS))
def test_the_seven_kinds_take_one_step(kind):
    surface, (sizes, corners, points, features) = build(kind)
    two, _ = build(kind, 2)
    assert surface.refinements == 1 and surface.topology.two_steps_why is None
    assert surface.n_patches == 4 * sizes.size and two.n_patches == 16 * sizes.size  # target: at most 5 a face
    assert len(surface.bicubic) == len(two.bicubic)  # the same holes, a quarter of the biquadratic patches
    # the certificate (c1surf check's measurement: C0 pieces for their gap, G1 elsewhere)
    report = check_surface(surface)
    assert report.max_normal_jump < 1e-10 and report.relative_gap < 1e-12 and report.unpaired_crease_sides == 0
    assert report.max_crease_gap <= 1e-12 * report.bbox_diagonal
    # independently: sides paired from the geometry alone, both sides sampled at 11 points
    crease_gap, smooth_gap, smooth_jump, crease_pairs, unmatched = crease_and_smooth(surface)
    assert crease_gap <= 1e-12 and smooth_gap <= 1e-12 and smooth_jump < 1e-10
    assert crease_pairs == CREASE_PAIRS.get(kind, 0) == report.crease_edges
    assert unmatched == 2 * boundary_edges(sizes, corners)  # a rim edge: two patch sides, each a boundary


def test_a_crease_curve_lies_on_its_edge_and_the_sharp_cube_is_the_cube():
    surface, _ = build("sharp cube")
    coefficients = np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)])
    assert np.min(np.abs(np.abs(coefficients) - 1.0), axis=1).max() <= 1e-12  # every point on a face plane
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    patch_corners = surface.biquadratic[:, ::2, ::2].reshape(-1, 3)
    assert cKDTree(patch_corners).query(corners)[0].max() <= 1e-12  # the corners are reached


def test_the_tagged_corners_are_interpolated_at_one_step():
    surface, (_, _, points, features) = build("tagged box")
    patch_corners = np.concatenate([surface.biquadratic[:, ::2, ::2].reshape(-1, 3),
                                    surface.bicubic[:, ::3, ::3].reshape(-1, 3)])
    assert cKDTree(patch_corners).query(points[features.corner_vertices])[0].max() <= 1e-12


@pytest.mark.parametrize("refinements", ["auto", 2])
def test_the_rim_is_the_quadratic_b_spline_of_the_boundary_polygon(refinements):
    """On a run of rim vertices in two faces each, the surface's boundary is the uniform quadratic B-spline of the
    boundary polygon a_j (ghost points a' = 2 a - m(a) make the transversal spline pass through a_j): its Bezier
    pieces are [m_j, a_j, m_j+1] with m_j = (a_j-1 + a_j) / 2, split at Q_j = (a_j-1 + 6 a_j + a_j+1) / 8, one
    half a patch side after one step, a quarter after two. The interior is noisy: the rim does not see it."""
    sizes, corners, points, _ = saddle(6, 4)
    surface = Surface(sizes, corners, points, SurfaceOptions(refinements=refinements))
    assert surface.refinements == (1 if refinements == "auto" else 2)
    run = points[1:6]  # the bottom row without its corners (in one face each): a_1..a_5
    a_prev, a, a_next = run[:-2], run[1:-1], run[2:]
    m, q = (a_prev + a) / 2, (a_prev + 6 * a + a_next) / 8
    pieces = [np.stack([m, (m + a) / 2, q], axis=1), np.stack([q, (a + (a + a_next) / 2) / 2, (a + a_next) / 2], axis=1)]
    if surface.refinements == 2:  # each half split again at its middle (de Casteljau)
        pieces = [part for p in pieces for part in _halves(p)]
    sides = np.concatenate([surface.biquadratic[:, 0, :], surface.biquadratic[:, 2, :],
                            surface.biquadratic[:, :, 0], surface.biquadratic[:, :, 2]])
    sides = np.concatenate([sides, sides[:, ::-1]]).reshape(len(sides) * 2, -1)
    tree = cKDTree(sides)
    for p in pieces:
        distance, _ = tree.query(p.reshape(len(p), -1))
        assert distance.max() <= 1e-12, distance.max()


def _halves(piece):
    """A quadratic Bezier piece (k, 3, d) split at its middle: two pieces."""
    p0, p1, p2 = piece[:, 0], piece[:, 1], piece[:, 2]
    l1, r1 = (p0 + p1) / 2, (p1 + p2) / 2
    mid = (l1 + r1) / 2
    return [np.stack([p0, l1, mid], axis=1), np.stack([mid, r1, p2], axis=1)]


def strip(length=3):
    """A strip one quad wide: its four corners lie in one face each (valence 3 with their two ghost quads), and
    the two corners at each end are joined by an edge."""
    at = lambda i, j: i + j * (length + 1)
    faces = [[at(i, 0), at(i + 1, 0), at(i + 1, 1), at(i, 1)] for i in range(length)]
    points = np.array([(i, j, 0.1 * i * j) for j in range(2) for i in range(length + 1)], dtype=float)
    return np.full(length, 4), np.concatenate(faces), points


def test_where_one_step_cannot_work_auto_takes_two_and_one_is_refused():
    # two corners in one face each, joined by an edge: their 3-sided cells are one edge apart after one step (R2)
    sizes, corners, points = strip()
    surface = Surface(sizes, corners, points, SurfaceOptions(refinements="auto"))
    assert surface.refinements == 2 and "R2" in surface.topology.two_steps_why
    with pytest.raises(TopologyError, match="one refinement step is not enough: .*R2"):
        Surface(sizes, corners, points, SurfaceOptions(refinements=1))
    # a dart whose faces are triangles: the dart's cell shares corners with the triangles' cells (R3)
    points, sizes, corners, features, _ = polar_dart([2, 2, 2, 1, 1])
    surface = Surface(sizes, corners, points, SurfaceOptions(refinements="auto", exact_creases=True), features=features)
    assert surface.refinements == 2 and "R3" in surface.topology.two_steps_why
    # no step keeps the patches of a real face only: refused for an open mesh
    sizes, corners, points, _ = saddle()
    with pytest.raises(TopologyError, match="no refinement is not enough"):
        Surface(sizes, corners, points, SurfaceOptions(refinements=0))


@pytest.mark.parametrize("n", [3, 4, 5, 6])
def test_darts_of_any_valence_among_quads_take_one_step(n):
    points, sizes, corners, features, _ = polar_dart([2] * n, seed=n)
    surface = Surface(sizes, corners, points, SurfaceOptions(refinements="auto", exact_creases=True), features=features)
    assert surface.refinements == 1 and surface.n_patches == 4 * sizes.size
    crease_gap, smooth_gap, smooth_jump, crease_pairs, _ = crease_and_smooth(surface)
    assert crease_gap <= 1e-12 and smooth_gap <= 1e-12 and smooth_jump < 1e-10
    assert crease_pairs == 2 * 3  # two pieces per crease edge (3 rings), the one at the dart its hole's spoke


@pytest.mark.parametrize("kind", ["torus with a window", "tagged box", "half-sharp roof"])
@pytest.mark.parametrize("refinements", ["auto", 2])
@pytest.mark.parametrize("rational", [False, True])
def test_update_points_equals_a_fresh_construction_bit_for_bit(kind, refinements, rational):
    sizes, corners, points, features = KINDS[kind]()
    rng = np.random.default_rng(5)
    weights = 1 + 0.5 * rng.random(len(points)) if rational else None
    options = SurfaceOptions(refinements=refinements, exact_creases=True)
    moved = points + 0.05 * rng.standard_normal(points.shape)
    surface = Surface(sizes, corners, points, options, features=features, weights=weights)
    surface.update_points(moved)
    fresh = Surface(sizes, corners, moved, options, features=features, weights=weights)
    assert np.array_equal(surface.biquadratic, fresh.biquadratic) and np.array_equal(surface.bicubic, fresh.bicubic)
    surface.update_points(moved)  # and again, after the stages readied their faster forms
    assert np.array_equal(surface.biquadratic, fresh.biquadratic) and np.array_equal(surface.bicubic, fresh.bicubic)
    stacked = np.concatenate([fresh.biquadratic.reshape(-1, 3), fresh.bicubic.reshape(-1, 3)])
    if not rational:
        assert np.abs(surface.stencil() @ moved - stacked).max() <= 1e-13 * np.abs(stacked).max()


def test_one_step_patch_sources_name_the_real_faces():
    surface, (sizes, _, _, _) = build("saddle grid")
    kind, index, _ = surface.patch_sources()
    # a biquadratic patch comes from its face (four a face), a bicubic one from its vertex (a corner's 3-sided cell)
    from_face = kind == FACE_FROM_FACE
    assert np.array_equal(from_face, np.arange(surface.n_patches) < len(surface.biquadratic))
    expected = np.full(sizes.size, 4)
    expected[[0, 4, 15, 19]] = 3  # the corner faces of the 5 x 4 grid
    assert np.array_equal(np.bincount(index[from_face], minlength=sizes.size), expected)
    assert np.all(kind[~from_face] == FACE_FROM_VERTEX) and sorted(index[~from_face]) == [0, 5, 24, 29]


def test_every_edge_of_the_kinds_is_read_once():
    # sanity of the builders: pure quads, each edge in one or two faces
    for kind, make in KINDS.items():
        sizes, corners, _, _ = make()
        assert np.all(sizes == 4) and len(all_edges(sizes, corners)) > 0, kind


def write_obj(path, sizes, corners, points, features=None):
    """An OBJ file of the mesh, infinitely sharp creases as OpenSubdiv's ``t crease`` lines."""
    faces = np.split(corners, np.cumsum(sizes)[:-1])
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in points] + ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    if features is not None:
        lines += [f"t crease 2/1/0 {a} {b} 10" for a, b in features.crease_edges]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("kind", ["saddle grid", "half-sharp roof"])
def test_streamed_and_in_memory_conversions_at_one_step_are_equal(monkeypatch, tmp_path, kind):
    from click.testing import CliRunner

    from c1surf.cli.main import main

    mesh = tmp_path / "mesh.obj"
    write_obj(mesh, *KINDS[kind]())
    files = {}
    for stream in ("1", "0"):
        monkeypatch.setenv("C1SURF_STREAM", stream)
        out, patches = tmp_path / f"s{stream}.ply", tmp_path / f"s{stream}.npz"
        result = CliRunner().invoke(main, ["convert", str(mesh), "-o", str(out), "--patches", str(patches),
                                           "--refinements", "auto", "-q"])
        assert result.exit_code == 0, result.output
        files[stream] = (out.read_bytes(), patches.read_bytes())
        with np.load(patches) as data:
            assert all(np.isfinite(data[key]).all() for key in data.files if data[key].dtype.kind == "f")
    assert files["1"] == files["0"]


def test_one_step_refused_in_one_line(tmp_path):
    from click.testing import CliRunner

    from c1surf.cli.main import main

    mesh = tmp_path / "strip.obj"
    write_obj(mesh, *strip())
    result = CliRunner().invoke(main, ["convert", str(mesh), "-o", str(tmp_path / "x.ply"), "--refinements", "1"])
    assert result.exit_code == 1 and not (tmp_path / "x.ply").exists()
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("c1surf: error:") and "one refinement step is not enough" in lines[0]
    result = CliRunner().invoke(main, ["convert", str(mesh), "-o", str(tmp_path / "x.ply"), "--refinements", "auto"])
    assert result.exit_code == 0 and "two Doo-Sabin steps" in result.output and "R2" in result.output
