"""Area, volume, centroid and inertia (evaluation.measure): exact cases, scaling laws, independent checks.

- the unit cube as six flat biquadratic patches (polynomial and rational): area 6, volume 1,
  centroid (1/2, 1/2, 1/2), inertia Id / 6 about the centroid;
- a rational sphere patch: its analytic area;
- on sample surfaces: scaling by s (area s^2, volume s^3, inertia s^5), translation and rotation;
- area and volume against a fine tessellation (converging), and against Open CASCADE
  (BRepGProp) on the STEP solid c1surf writes, to 1e-9 relative;
- closedness from the adjacency: open, inconsistently oriented and inward-facing surfaces.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from c1surf.evaluation import measure
from c1surf.evaluation.adjacency import adjacency_from_geometry
from c1surf.evaluation.measure import closed_surface, gauss_rule, mass_properties, solid_moments, surface_area
from c1surf.evaluation.patch_set import surface_patch_set
from c1surf.evaluation.tessellate import tessellate_patches

from conftest import SAMPLES, grid, ocp_shapes, rational_sphere_patch, read_step, surface_of

OCP_SAMPLES = ["cube", "tetrahedron", "twisted", "torus", "double_torus", "hexagon_all_six_valent", "triangular_prism"]
UNIT_CUBE_INERTIA = np.eye(3) / 6.0  # (1/12)(1 + 1) about the centre, unit density


def unit_cube_patches() -> np.ndarray:
    """(6, 3, 3, 3): the faces of [0, 1]^3 as flat biquadratic patches, x_u x x_v pointing out."""
    t = np.linspace(0.0, 1.0, 3)
    u, v = np.meshgrid(t, t, indexing="ij")
    faces = []
    for axis in range(3):
        a, b = (axis + 1) % 3, (axis + 2) % 3  # e_a x e_b = e_axis
        for side, (first, second) in ((0.0, (b, a)), (1.0, (a, b))):
            p = np.zeros((3, 3, 3))
            p[..., axis], p[..., first], p[..., second] = side, u, v
            faces.append(p)
    return np.stack(faces)


def measured(groups, weights=None, adjacency=None):
    adjacency = adjacency or adjacency_from_geometry(groups, 1e-9)
    return mass_properties(groups, adjacency.edges, adjacency.reversed, weights)


def sample_patch_set(name):
    return surface_patch_set(surface_of(SAMPLES / f"{name}.obj"))


def test_gauss_rule_integrates_its_degree_exactly():
    for points in (1, 3, 5, 8):
        for subdivisions in (1, 3):
            t, w = gauss_rule(points, subdivisions)
            for degree in range(2 * points):
                assert w @ t**degree == pytest.approx(1.0 / (degree + 1), rel=1e-14, abs=1e-15)


def test_unit_cube_of_flat_biquadratic_patches():
    result = measured([unit_cube_patches()])
    assert result.closed and result.reason is None and result.note is None
    assert result.area == pytest.approx(6.0, rel=1e-14)
    assert result.volume == pytest.approx(1.0, rel=1e-14)
    np.testing.assert_allclose(result.centroid, 0.5, rtol=1e-14)
    np.testing.assert_allclose(result.inertia, UNIT_CUBE_INERTIA, atol=1e-14)


def test_unit_cube_as_bicubic_patches_and_rational_patches():
    from c1surf.evaluation.bezier import raise_degree

    cube = unit_cube_patches()
    adjacency = adjacency_from_geometry([cube], 1e-9)
    cubic = measured([raise_degree(cube, 3, 3)])
    # tensor-product weights reparametrize each face monotonically: the same square, the same solid
    a, b = np.array([1.0, 2.5, 0.7]), np.array([0.5, 1.0, 3.0])
    weights = np.broadcast_to(np.outer(a, b), (6, 3, 3)).copy()
    rational = measured([cube], [weights], adjacency)
    for result in (cubic, rational):
        assert result.closed
        assert result.area == pytest.approx(6.0, rel=1e-12)
        assert result.volume == pytest.approx(1.0, rel=1e-12)
        np.testing.assert_allclose(result.centroid, 0.5, rtol=1e-12)
        np.testing.assert_allclose(result.inertia, UNIT_CUBE_INERTIA, atol=1e-12)


def test_rational_sphere_patch_has_its_analytic_area():
    radius = 1.7
    h = rational_sphere_patch(radius, np.array([0.3, -1.0, 2.0]))
    points, weights = h[..., :3] / h[..., 3:], h[..., 3]
    area, error = surface_area([points[None]], [weights[None]])
    exact = radius**2 * (np.pi / 2) * np.sqrt(2.0)  # 90 degrees of longitude, latitude -45..45
    assert area == pytest.approx(exact, rel=1e-12)
    assert error < 1e-12 * exact


@pytest.mark.parametrize("name", ["twisted", "double_torus"])
def test_scaling_translation_and_rotation(name):
    ps = sample_patch_set(name)
    base = measured(ps.groups, adjacency=ps.adjacency)
    s, shift = 2.5, np.array([10.0, -3.0, 7.0])
    scaled = measured([g * s for g in ps.groups], adjacency=ps.adjacency)
    assert scaled.area == pytest.approx(s**2 * base.area, rel=1e-12)
    assert scaled.volume == pytest.approx(s**3 * base.volume, rel=1e-12)
    np.testing.assert_allclose(scaled.centroid, s * base.centroid, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(scaled.inertia, s**5 * base.inertia, rtol=1e-11, atol=1e-11 * s**5)
    moved = measured([g + shift for g in ps.groups], adjacency=ps.adjacency)
    assert moved.area == pytest.approx(base.area, rel=1e-12)
    assert moved.volume == pytest.approx(base.volume, rel=1e-12)
    np.testing.assert_allclose(moved.centroid, base.centroid + shift, rtol=1e-12)
    np.testing.assert_allclose(moved.inertia, base.inertia, rtol=1e-11, atol=1e-11)
    turn = Rotation.from_euler("xyz", [0.3, -1.1, 2.0]).as_matrix()
    turned = measured([g @ turn.T for g in ps.groups], adjacency=ps.adjacency)
    assert turned.volume == pytest.approx(base.volume, rel=1e-12)
    np.testing.assert_allclose(turned.centroid, turn @ base.centroid, atol=1e-12)
    np.testing.assert_allclose(turned.inertia, turn @ base.inertia @ turn.T, atol=1e-11 * np.abs(base.inertia).max())


def tessellated_area_and_volume(ps, resolution):
    tess = tessellate_patches(ps.groups, ps.adjacency, resolution)
    a, b, c = (tess.points[tess.triangles[:, k], :3] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    return area, volume


@pytest.mark.parametrize("name", ["cube", "twisted", "high_valence"])
def test_area_and_volume_against_a_fine_tessellation(name):
    ps = sample_patch_set(name)
    exact = measured(ps.groups, adjacency=ps.adjacency)
    sampled = np.array([tessellated_area_and_volume(ps, n) for n in (9, 17, 33, 65)])  # (4, 2): area, volume
    errors = np.abs(sampled - [exact.area, exact.volume]) / [exact.area, exact.volume]
    # second order: each halving of the triangle size divides the error by about 4
    assert np.all(errors[1:] < 0.35 * errors[:-1])
    assert errors[-1].max() < 1e-4
    # and Richardson's extrapolation of the last two lands far closer still
    extrapolated = sampled[-1] + (sampled[-1] - sampled[-2]) / 3
    assert np.all(np.abs(extrapolated - [exact.area, exact.volume]) < 1e-5 * np.array([exact.area, exact.volume]))


def test_area_quadrature_converged_on_a_nearly_singular_corner(monkeypatch):
    """high_valence: the bicubic patches' parametrization nearly degenerates at the centre of a 12-gon."""
    ps = sample_patch_set("high_valence")
    area, error = surface_area(ps.groups)
    monkeypatch.setattr(measure, "MAX_SUBDIVISIONS", 256)
    finer, _ = surface_area(ps.groups)
    assert abs(area - finer) < 1e-11 * finer
    assert error < 1e-9 * area


def ocp_properties(path):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_SOLID

    shape = read_step(path)
    assert len(ocp_shapes(shape, TopAbs_SOLID)) == 1
    volume, surface = GProp_GProps(), GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, volume, 1e-13)  # adaptive, to this relative accuracy
    BRepGProp.SurfaceProperties_s(shape, surface, 1e-13)
    c, m = volume.CentreOfMass(), volume.MatrixOfInertia()
    inertia = np.array([[m.Value(i, j) for j in (1, 2, 3)] for i in (1, 2, 3)])  # about the centre of mass
    return surface.Mass(), volume.Mass(), np.array([c.X(), c.Y(), c.Z()]), inertia


@pytest.mark.parametrize("name", OCP_SAMPLES)
def test_against_open_cascade_on_the_step_solid(tmp_path, name):
    from c1surf.io.patches.step import write_patch_set_step

    ps = sample_patch_set(name)
    write_patch_set_step(tmp_path / "surface.step", ps)
    area, volume, centroid, inertia = ocp_properties(tmp_path / "surface.step")
    ours = measured(ps.groups, adjacency=ps.adjacency)
    diagonal = float(np.linalg.norm(np.ptp(np.concatenate([g.reshape(-1, 3) for g in ps.groups]), axis=0)))
    assert abs(ours.area - area) <= 1e-9 * area
    assert abs(ours.volume - volume) <= 1e-9 * volume
    assert np.abs(ours.centroid - centroid).max() <= 1e-9 * diagonal
    assert np.abs(ours.inertia - inertia).max() <= 1e-9 * np.abs(inertia).max()


def test_open_surface_has_no_volume():
    from c1surf.construction.surface import Surface

    surface = Surface(*grid(3))
    ps = surface_patch_set(surface)
    result = measured(ps.groups, adjacency=ps.adjacency)
    assert not result.closed and result.volume is None and result.centroid is None and result.inertia is None
    assert "open" in result.reason and "boundary" in result.reason
    assert result.area > 0


def test_inconsistent_orientation_and_inward_normals():
    cube = unit_cube_patches()
    flipped = cube.copy()
    flipped[2] = flipped[2, ::-1]  # one face turned inside out
    edges = adjacency_from_geometry([flipped], 1e-9)
    closed, reason = closed_surface(edges.edges, edges.reversed)
    assert not closed and "oriented" in reason
    inward = measured([cube[:, ::-1]])
    assert inward.closed and inward.volume == pytest.approx(1.0) and "point into" in inward.note
    np.testing.assert_allclose(inward.inertia, UNIT_CUBE_INERTIA, atol=1e-14)
    volume, _, _ = solid_moments([cube[:, ::-1]])
    assert volume == pytest.approx(-1.0)


# --- the compiled loops (evaluation.compiled.kernels) and the area's screen (issue 36) -------------------------------------


def _sample_groups(names=("cube", "twisted", "high_valence", "torus")):
    """The biquadratic and bicubic groups of some sample surfaces, concatenated by degree."""
    sets = [sample_patch_set(name) for name in names]
    return [np.concatenate([g for ps in sets for g in ps.groups if g.shape[1] == n]) for n in (3, 4)]


@pytest.mark.parametrize("rule", [(None, 1), (None, 2), (3, 1), (12, 1)])
def test_compiled_rules_agree_with_the_numpy_rules_patch_by_patch(rule):
    """``kernels.area_sums`` and ``kernels.moment_sums`` against the numpy integrands on the same nodes: every
    patch's area to 1e-14 relative, its moments to 1e-14 of the largest (rounding of sums in another order)."""
    origin = np.array([0.3, -0.2, 0.1])
    for points in _sample_groups():
        d = points.shape[1] - 1
        nodes = gauss_rule(rule[0] or measure.moment_points(d), rule[1])
        for integrand in (measure.area_integrand, measure.moment_integrand):
            compiled = measure._integrate_fixed(points, None, integrand, origin, nodes, nodes, compiled=True)
            reference = measure._numpy_fixed(points, None, integrand, origin, nodes, nodes)
            assert compiled.shape == reference.shape
            scale = np.abs(reference) if integrand is measure.area_integrand else np.abs(reference).max(axis=0)
            assert np.all(np.abs(compiled - reference) <= 1e-14 * scale + 1e-300)


def test_compiled_patch_values_do_not_depend_on_the_block():
    """A patch's value is its own: the same bits alone, in any slice, and on the thread pool's ranges."""
    points = _sample_groups()[1]
    nodes = gauss_rule(10)
    whole = measure._integrate_fixed(points, None, measure.moment_integrand, np.zeros(3), nodes, nodes, True)
    for size in (1, 5, 130):
        parts = [measure._integrate_fixed(points[a:a + size], None, measure.moment_integrand, np.zeros(3), nodes,
                                          nodes, True) for a in range(0, len(points), size)]
        assert np.array_equal(np.concatenate(parts), whole)


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("name", ["cube", "twisted", "high_valence", "torus", "dodecahedron", "double_torus"])
def test_screened_area_agrees_with_the_subdivided_levels(name, compiled):
    """The area's screen (two Gauss rules, the finer kept where they agree), in numpy and compiled, against the
    levels every patch went through before it (the moment rule, sub-squares doubled until two agree to 1e-13),
    in numpy: to 1e-13 relative on the surface, each patch to 1e-12 of the group's mean area (high_valence's
    nearly singular corners go through those levels in both)."""
    from c1surf.evaluation.stream.patches import ArrayPatches

    groups = sample_patch_set(name).groups
    patches = ArrayPatches(groups)
    total = reference = 0.0
    for k in range(len(patches.counts)):
        screened, error = measure._integrate_group(patches, k, (measure.area_integrand, np.zeros(3), compiled),
                                                   measure.AREA_RTOL, 7)
        levels, _ = measure._integrate_group(patches, k, (lambda *a: measure.area_integrand(*a), np.zeros(3), False),
                                             measure.AREA_RTOL, 7)
        assert np.all(np.abs(screened - levels) <= 1e-12 * np.abs(levels).mean())
        assert np.all(error >= 0)
        total, reference = total + screened.sum(), reference + levels.sum()
    assert abs(total - reference) <= 1e-13 * reference
    if not compiled:
        assert surface_area(groups)[0] == total  # fewer patches than COMPILED_FROM: numpy


def test_the_kernels_run_where_no_cache_folder_can_be_written(monkeypatch):
    """numba refuses ``cache=True`` when no cache folder is writable (a read-only install and home): the kernels
    are then compiled in the process, and give the cached kernels' bits."""
    import importlib.util

    from numba.core import caching

    def refuse(self):
        raise PermissionError("read-only")
    monkeypatch.setattr(caching._CacheLocator, "ensure_cache_path", refuse)
    spec = importlib.util.spec_from_file_location("kernels_without_cache", measure.__file__.replace("measure.py", "compiled/kernels.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.area_sums._cache.__class__.__name__ == "NullCache"
    points = _sample_groups(("cube",))[0]
    t, w = gauss_rule(5)
    bases = [np.ascontiguousarray(b) for b in (measure.bernstein_basis(2, t), measure.bernstein_basis(2, t, 1))] * 2
    out = np.empty(len(points))
    module.area_sums(points, tuple(bases) + (w, w), out)
    assert np.array_equal(out, measure._integrate_fixed(points, None, measure.area_integrand, None, (t, w),
                                                        (t, w), compiled=True)[:, 0])
