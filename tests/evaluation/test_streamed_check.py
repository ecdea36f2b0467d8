"""``check`` and ``measure`` by blocks of patches give the in-memory results bit for bit.

The smoothness check and the mass properties read patches through ``evaluation.stream.patches`` (arrays,
memory-mapped NPZ members, or a streamed Surface's ``PatchSource``), a block at a time. Every value is
computed patch by patch or side by side; across blocks only maxima are taken (the smoothness report) or the
per-patch integrals are kept whole and summed as before (the mass properties), so the reports are equal
exactly, whatever the block: compared with ``==`` on every float here, with blocks of 1, 3 and 7 patches.

The geometric matcher's clustering (``mesh.points.clusters``: grid-cell hashes) is compared with the k-d tree's
connected components it replaced, on points placed at a cell's faces and corners.
"""
from __future__ import annotations

import numpy as np
import pytest

from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.adjacency import adjacency_from_geometry
from c1surf.evaluation.measure import mass_properties
from c1surf.evaluation.patch_set import surface_patch_set
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.evaluation.stream.patches import ArrayPatches, SourcePatches
from c1surf.io.meshes.obj import read_obj
from c1surf.io.patches.formats import load_patch_set, write_patch_set
from c1surf.mesh.points.clusters import CELL_TOLERANCES, cluster_points

from conftest import SAMPLES, shared_mesh, weighted_cube

SAMPLE_NAMES = sorted(p.stem for p in SAMPLES.glob("*.obj"))
TINY = (1, 3, 7)


def _lazy_and_whole(path, **options):
    """(the Surface built in memory, the same mesh's Surface with lazy patches: its PatchSource)."""
    mesh = read_obj(path)
    build = lambda lazy: Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(**options),
                                 lazy_patches=lazy)
    return build(False), build(True)


def _assert_same_smoothness(whole, *others):
    for other in others:
        assert other == whole  # a frozen dataclass: every count, float and the worst pair, exactly


def _assert_same_mass(whole, *others):
    for other in others:
        assert (other.area, other.area_error, other.closed, other.reason, other.volume, other.note) == (
            whole.area, whole.area_error, whole.closed, whole.reason, whole.volume, whole.note)
        for name in ("centroid", "inertia"):
            a, b = getattr(whole, name), getattr(other, name)
            assert (a is None and b is None) or np.array_equal(a, b)


@pytest.mark.parametrize("name", SAMPLE_NAMES)
def test_check_and_measure_by_blocks_equal_the_whole_surface_on_every_sample_mesh(name):
    surface, lazy = _lazy_and_whole(SAMPLES / f"{name}.obj")
    patch_set = surface_patch_set(surface)
    groups, adjacency = patch_set.groups, patch_set.adjacency
    whole = measure_smoothness(groups, samples=7)
    assert whole.shared_edges > 0 and whole.is_g1(1e-9, 1e-9)
    source = SourcePatches(lazy.patch_source())
    _assert_same_smoothness(whole, *(measure_smoothness(ArrayPatches(groups), samples=7, block=b) for b in TINY),
                            measure_smoothness(source, samples=7, block=5))
    mass = mass_properties(groups, adjacency.edges, adjacency.reversed)
    _assert_same_mass(mass, *(mass_properties(ArrayPatches(groups), adjacency.edges, adjacency.reversed, block=b)
                              for b in TINY), mass_properties(source, adjacency.edges, adjacency.reversed, block=5))


@pytest.mark.parametrize("name", ["cube", "high_valence", "twisted"])
def test_compiled_measure_by_blocks_equals_the_whole_surface(monkeypatch, name):
    """The compiled integrals (``evaluation.compiled.kernels``, from ``measure.COMPILED_FROM`` patches on: here from 0),
    by blocks and from a streamed Surface, equal the in-memory ones with ``==`` too."""
    from c1surf.evaluation import measure

    monkeypatch.setattr(measure, "COMPILED_FROM", 0)
    surface, lazy = _lazy_and_whole(SAMPLES / f"{name}.obj")
    patch_set = surface_patch_set(surface)
    groups, adjacency = patch_set.groups, patch_set.adjacency
    assert measure.compiled_loops(ArrayPatches(groups))
    mass = mass_properties(groups, adjacency.edges, adjacency.reversed)
    source = SourcePatches(lazy.patch_source())
    _assert_same_mass(mass, *(mass_properties(ArrayPatches(groups), adjacency.edges, adjacency.reversed, block=b)
                              for b in TINY), mass_properties(source, adjacency.edges, adjacency.reversed, block=5))
    monkeypatch.setattr(measure, "COMPILED_FROM", 10**9)
    numpy = mass_properties(groups, adjacency.edges, adjacency.reversed)
    assert abs(numpy.area - mass.area) <= 1e-14 * mass.area and abs(numpy.volume - mass.volume) <= 1e-14 * mass.volume


@pytest.mark.parametrize("name", ["cube", "high_valence", "twisted", "torus", "octahedron"])
def test_compiled_check_by_blocks_equals_the_whole_surface_and_the_numpy_check(monkeypatch, name):
    """The compiled check (``evaluation.compiled.kernels``: side keys, shortest side, side frames and jumps; from
    ``measure.COMPILED_FROM`` patches on, here from 0) by blocks and from a streamed Surface equals the in-memory
    one with ``==``; against the numpy check: the same pairs, boundary and counts and bounding box (``==``), the
    gap and the normal jump at the same samples to rounding (1e-15 of the diagonal, 1e-13 rad)."""
    from c1surf.evaluation import measure

    surface, lazy = _lazy_and_whole(SAMPLES / f"{name}.obj")
    groups = surface_patch_set(surface).groups
    numpy = measure_smoothness(groups, samples=7)
    monkeypatch.setattr(measure, "COMPILED_FROM", 0)
    whole = measure_smoothness(groups, samples=7)
    _assert_same_smoothness(whole, *(measure_smoothness(ArrayPatches(groups), samples=7, block=b) for b in TINY),
                            measure_smoothness(SourcePatches(lazy.patch_source()), samples=7, block=5))
    for field in ("shared_edges", "boundary_edges", "overshared_edges", "bbox_diagonal", "crease_edges",
                  "unpaired_crease_sides"):
        assert getattr(whole, field) == getattr(numpy, field)
    assert abs(whole.max_gap - numpy.max_gap) <= 1e-15 * whole.bbox_diagonal
    assert abs(whole.max_normal_jump - numpy.max_normal_jump) <= 1e-13
    assert whole.is_g1(1e-9, 1e-9)


@pytest.mark.parametrize("name", ["catmark_single_crease", "catmark_fan"])
def test_compiled_check_of_crease_pieces(monkeypatch, name):
    """Listed crease pieces (and non-manifold sheets) through the compiled check: the counts of the numpy check,
    the crease gap to rounding, by blocks equal."""
    from c1surf.api import surface_from_file
    from c1surf.evaluation import measure

    surface, _ = surface_from_file(shared_mesh(f"opensubdiv/{name}.obj"), exact_creases=True)
    patch_set = surface_patch_set(surface)
    numpy = measure_smoothness(patch_set.groups, crease_sides=patch_set.crease_sides)
    monkeypatch.setattr(measure, "COMPILED_FROM", 0)
    whole = measure_smoothness(patch_set.groups, crease_sides=patch_set.crease_sides)
    _assert_same_smoothness(whole, *(measure_smoothness(ArrayPatches(patch_set.groups), block=b,
                                                        crease_sides=patch_set.crease_sides) for b in TINY))
    for field in ("shared_edges", "boundary_edges", "overshared_edges", "crease_edges", "unpaired_crease_sides"):
        assert getattr(whole, field) == getattr(numpy, field)
    assert abs(whole.max_crease_gap - numpy.max_crease_gap) <= 1e-15 * whole.bbox_diagonal
    assert whole.is_g1(1e-9, 1e-9)


def test_a_rational_surface_by_blocks(tmp_path):
    from c1surf.api import surface_from_file

    surface, _ = surface_from_file(weighted_cube(tmp_path, rational=True))
    patch_set = surface_patch_set(surface)
    assert patch_set.weights is not None
    groups, weights, adjacency = patch_set.groups, patch_set.weights, patch_set.adjacency
    whole = measure_smoothness(groups, weights=weights)
    assert whole.shared_edges == 2 * surface.n_patches and whole.is_g1(1e-9, 1e-9)
    _assert_same_smoothness(whole, *(measure_smoothness(ArrayPatches(groups, weights), block=b) for b in TINY))
    mass = mass_properties(groups, adjacency.edges, adjacency.reversed, weights)
    assert mass.closed and mass.volume > 0
    _assert_same_mass(mass, *(mass_properties(ArrayPatches(groups, weights), adjacency.edges, adjacency.reversed,
                                              block=b) for b in (3, 7)))


@pytest.mark.parametrize("name", ["catmark_single_crease", "catmark_cube_creases2"])
def test_listed_crease_sides_by_blocks(name):
    from c1surf.api import surface_from_file

    surface, _ = surface_from_file(shared_mesh(f"opensubdiv/{name}.obj"), exact_creases=True)
    patch_set = surface_patch_set(surface)
    crease = patch_set.crease_sides
    assert crease is not None and len(crease)
    whole = measure_smoothness(patch_set.groups, crease_sides=crease)
    assert whole.crease_edges == len(crease) and whole.unpaired_crease_sides == 0 and whole.is_g1(1e-9, 1e-9)
    _assert_same_smoothness(whole, *(measure_smoothness(ArrayPatches(patch_set.groups), crease_sides=crease,
                                                        block=b) for b in TINY))


def test_non_manifold_sheets_by_blocks():
    from c1surf.api import surface_from_file

    # edges of more than two faces cut into sheets meeting along one crease: pieces measured side against side
    surface, _ = surface_from_file(shared_mesh("opensubdiv/catmark_fan.obj"), exact_creases=True)
    patch_set = surface_patch_set(surface)
    whole = measure_smoothness(patch_set.groups, crease_sides=patch_set.crease_sides)
    assert whole.crease_edges == len(patch_set.crease_sides) > 0 and whole.overshared_edges == 0
    assert whole.unpaired_crease_sides == 0 and whole.is_g1(1e-9, 1e-9)
    _assert_same_smoothness(whole, *(measure_smoothness(ArrayPatches(patch_set.groups), block=b,
                                                        crease_sides=patch_set.crease_sides) for b in TINY))


@pytest.mark.parametrize("suffix", [".json", ".npz", ".igs", ".step"])
def test_patch_files_of_each_format_by_blocks(tmp_path, suffix):
    if suffix == ".step":
        pytest.importorskip("OCP")
    surface, _ = _lazy_and_whole(SAMPLES / "cube.obj")
    path = tmp_path / f"cube{suffix}"
    write_patch_set(path, surface_patch_set(surface))
    patch_set = load_patch_set(path)
    adjacency = patch_set.welding()
    bend = np.radians(1.0)  # IGES and STEP list no crease sides: the bent edges' path (none on the cube)
    whole = measure_smoothness(patch_set.groups, weights=patch_set.weights, crease_angle=bend)
    assert whole.shared_edges == 2 * patch_set.n_patches and whole.is_g1(1e-9, 1e-9)
    reader = ArrayPatches(patch_set.groups, patch_set.weights)
    _assert_same_smoothness(whole, *(measure_smoothness(reader, crease_angle=bend, block=b) for b in TINY))
    mass = mass_properties(patch_set.groups, adjacency.edges, adjacency.reversed, patch_set.weights)
    assert mass.closed
    _assert_same_mass(mass, *(mass_properties(reader, adjacency.edges, adjacency.reversed, block=b) for b in (3, 7)))


def test_bent_edges_as_creases_by_blocks():
    # a surface with a kink: the cube's patches with one patch's inner rows pulled out (its four sides bend)
    surface, _ = _lazy_and_whole(SAMPLES / "cube.obj")
    groups = [g.copy() for g in surface_patch_set(surface).groups]
    groups[-1][5, 1:-1, 1:-1] *= 1.3
    whole = measure_smoothness(groups, crease_angle=np.radians(0.5))
    assert whole.crease_edges >= 4 and whole.max_crease_gap <= 1e-15
    kinked = measure_smoothness(groups)
    assert kinked.max_normal_jump > np.radians(0.5) and kinked.crease_edges == 0
    _assert_same_smoothness(whole, *(measure_smoothness(ArrayPatches(groups), crease_angle=np.radians(0.5), block=b)
                                     for b in TINY))
    _assert_same_smoothness(kinked, *(measure_smoothness(ArrayPatches(groups), block=b) for b in TINY))


def _tree_labels(points, tolerance):
    """The clustering ``mesh.points.clusters`` replaced: connected components of the k-d tree's pairs."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    return connected_components(graph, directed=False)[1]


@pytest.mark.parametrize("seed", range(6))
def test_cell_clustering_equals_the_k_d_trees_components(seed):
    rng = np.random.default_rng(seed)
    tolerance = 1e-6
    cell = tolerance * CELL_TOLERANCES
    # centres on cell faces, edges and corners (and anywhere), each with a few points within a tolerance,
    # chains of points a bit less than a tolerance apart, and points a bit more than one apart
    centres = np.round(rng.uniform(-3, 3, (300, 3)) * 4) / 4 * cell
    centres[::3] += rng.uniform(-1, 1, (100, 3)) * cell
    points = [centres[:, None, :] + rng.normal(0.0, 0.2 * tolerance, (300, 4, 3))]
    chain = centres[:40, None, :] + np.arange(5)[None, :, None] * np.array([0.95 * tolerance, 0.0, 0.0])
    apart = centres[40:80, None, :] + np.arange(3)[None, :, None] * np.array([0.0, 1.05 * tolerance, 0.0])
    points = np.concatenate([points[0].reshape(-1, 3), chain.reshape(-1, 3), apart.reshape(-1, 3)])
    points = points[rng.permutation(len(points))]
    expected = _tree_labels(points, tolerance)
    assert np.array_equal(cluster_points(points, tolerance), expected)
    assert len(np.unique(expected)) < len(points)  # clusters were found at all


@pytest.mark.parametrize("seed", range(3))
def test_cell_clustering_of_a_crowded_cell_equals_the_k_d_trees_components(seed):
    """A cell holding thousands of points (a corner where thousands of patches meet): its exact duplicates are
    linked to their first equal before the pairwise checks, whose count is quadratic in the cell's points; the
    labels stay those of the k-d tree, also for near (not equal) points and for a crowded cell on a cell face."""
    rng = np.random.default_rng(seed)
    tolerance = 1e-6
    cell = tolerance * CELL_TOLERANCES
    centre, on_face = np.array([0.3, 0.2, 0.1]) * cell, np.array([1.0, 0.5, 0.5]) * cell
    crowd = np.repeat(centre[None], 3000, axis=0)
    crowd[::7] += rng.normal(0.0, 0.2 * tolerance, (len(crowd[::7]), 3))  # near, not equal
    face = np.repeat(on_face[None], 500, axis=0)
    face[1::2] -= [0.5 * tolerance, 0.0, 0.0]  # half just across the face: another cell, one cluster
    apart = centre + np.arange(1, 4)[:, None] * np.array([0.0, 0.0, 3 * tolerance])
    points = np.concatenate([crowd, face, apart, rng.uniform(-2, 2, (200, 3)) * cell])
    points = points[rng.permutation(len(points))]
    expected = _tree_labels(points, tolerance)
    assert np.array_equal(cluster_points(points, tolerance), expected)
    assert len(np.unique(expected)) < len(points) - 3000


def test_cell_clustering_of_exact_duplicates_and_no_tolerance():
    points = np.array([[0.0, 0.0, 0.0], [-0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [1.0, 2.0, 3.0 + 1e-15]])
    assert cluster_points(points, 0.0).tolist() == [0, 0, 1, 1, 2]
    assert cluster_points(points, 1e-12).tolist() == [0, 0, 1, 1, 1]
    assert cluster_points(np.zeros((0, 3)), 1e-9).shape == (0,)


def test_geometric_adjacency_unchanged_by_the_cell_clustering():
    # adjacency_from_geometry (which the clustering serves) against the construction's bookkeeping
    for name in ("torus", "high_valence", "twisted"):
        surface, _ = _lazy_and_whole(SAMPLES / f"{name}.obj")
        patch_set = surface_patch_set(surface)
        assert adjacency_from_geometry(patch_set.groups) == patch_set.adjacency


@pytest.mark.parametrize("tolerance", [1e-4, 5e-4, 2e-3])
def test_compiled_components_label_as_scipy(tolerance):
    """``cluster_points`` with the compiled union-find (``smoothness._compiled_components``, the large check's)
    gives the labels of scipy's connected components of the same pairs, ``==``: points with partners at about a
    tolerance, exact duplicates, a crowded cell (many equal points: the duplicates' path)."""
    from c1surf.evaluation.smoothness import _compiled_components

    rng = np.random.default_rng(3)
    x = rng.random((6000, 3))
    crowd = np.repeat(x[:1], 200, axis=0)
    points = np.concatenate([x, x + rng.normal(scale=tolerance / 2, size=x.shape), x[:1500], crowd])
    assert np.array_equal(cluster_points(points, tolerance, _compiled_components), cluster_points(points, tolerance))


def test_compiled_same_curves_as_numpy():
    """``sides.matching._same_curves`` pair by pair (compiled) and by blocks (numpy): the same answers on side
    points equal, within, and beyond the tolerance, forwards and backwards."""
    from c1surf.evaluation.sides.matching import _same_curves

    rng = np.random.default_rng(4)
    a_points = rng.random((3000, 3, 3))
    shift = rng.choice([0.0, 0.5e-6, 2e-6], size=(3000, 1, 1)) * rng.normal(size=(3000, 1, 3))
    backwards = rng.random(3000) < 0.5
    b_points = np.where(backwards[:, None, None], (a_points + shift)[:, ::-1], a_points + shift)
    points = np.concatenate([a_points, b_points])
    ends = np.zeros((6000, 2), dtype=np.int32)
    ends[3000:, 0] = np.where(backwards, 1, 0)
    a, b = np.arange(3000), np.arange(3000, 6000)
    numpy = _same_curves(points, ends, a, b, 1e-6)
    assert 0 < numpy.sum() < 3000
    assert np.array_equal(_same_curves(points, ends, a, b, 1e-6, compiled=True), numpy)
