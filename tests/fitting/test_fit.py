"""The fitting core (c1surf.fitting): exact recovery, monotone deviation, distances, G1 of the result."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from c1surf.construction.surface import Surface
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.evaluation.tessellate import tessellate
from c1surf.fitting.deviation import closest_on_triangles, signed_scan_to_surface, surface_to_scan, two_sided_deviation
from c1surf.fitting.iterate import fit_surface_points, project_scan
from c1surf.fitting.options import FitOptions
from c1surf.io.meshes.obj import read_obj

from conftest import SAMPLES


def _control(name: str):
    mesh = read_obj(str(SAMPLES / name))
    return mesh.face_sizes, mesh.face_vertices, mesh.points


def _size(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def _sphere_scan(points: np.ndarray, subdivisions: int = 3):
    """An icosphere around the control mesh's centre, of about its size: (points, triangles)."""
    sphere = trimesh.creation.icosphere(subdivisions)
    centre = (points.max(axis=0) + points.min(axis=0)) / 2
    return centre + 0.45 * _size(points) * sphere.vertices, np.asarray(sphere.faces)


@pytest.mark.parametrize("name", ["cube.obj", "dodecahedron.obj"])
def test_recovers_the_control_points_of_a_sampled_surface(name):
    """A scan sampled on a surface's own patches, fitted from a perturbed start without fairness,
    gives back its control points to 1e-8 of the model's size."""
    sizes, vertices, truth = _control(name)
    exact = Surface(sizes, vertices, truth)
    scan = tessellate([exact.biquadratic, exact.bicubic], exact.refined, exact.frames, 8)
    size = _size(truth)
    start = truth + np.random.default_rng(7).normal(scale=0.02 * size, size=truth.shape)
    surface = Surface(sizes, vertices, start)
    options = FitOptions(plane=1.0, point=0.0, fairness=0.0, max_iterations=12, stop=0.0)
    result = fit_surface_points(surface, scan.points, scan.triangles, options)
    assert result.history[0]["rms"] > 1e-3 * size  # the start is really off
    assert np.abs(result.points - truth).max() <= 1e-8 * size
    assert np.allclose(surface.points, result.points)  # the surface is left on the fitted points


def test_with_fairness_the_deviation_falls_in_every_round():
    sizes, vertices, points = _control("cube.obj")
    scan_points, scan_triangles = _sphere_scan(points)
    surface = Surface(sizes, vertices, points)
    rounds = 6  # the closest fit's rounds: without the fairness continuation, whose rounds move away from the scan
    result = fit_surface_points(surface, scan_points, scan_triangles,
                                FitOptions(max_iterations=rounds, stop=0.0, fairness_growth=0.0))
    assert result.stopped == "max_iterations" and result.iterations == rounds  # no round was undone
    rms = [h["rms"] for h in result.history]
    assert all(b < a for a, b in zip(rms, rms[1:]))
    assert rms[-1] < 0.1 * rms[0]


def test_progress_is_called_once_a_round():
    sizes, vertices, points = _control("cube.obj")
    scan_points, scan_triangles = _sphere_scan(points, 2)
    calls = []
    fit_surface_points(Surface(sizes, vertices, points), scan_points, scan_triangles,
                       FitOptions(max_iterations=3, stop=0.0, fairness_growth=0.0), progress=lambda *a: calls.append(a))
    assert calls == [("fitting", 1, 3)] * 3


def test_the_fitted_surface_is_g1():
    sizes, vertices, points = _control("cube.obj")
    scan_points, scan_triangles = _sphere_scan(points)
    surface = Surface(sizes, vertices, points)
    fit_surface_points(surface, scan_points, scan_triangles, FitOptions(max_iterations=4))
    report = measure_smoothness([surface.biquadratic, surface.bicubic], samples=11, crease_sides=surface.crease_sides)
    assert report.shared_edges > 0 and report.boundary_edges == 0
    assert report.max_normal_jump < 1e-9 and report.max_gap < 1e-12


def test_distances_agree_with_trimesh():
    """Scan to surface (Newton footpoints) against trimesh's closest points on a fine tessellation of the
    surface (within its chordal error); surface to scan against trimesh's closest points on the scan."""
    sizes, vertices, points = _control("cube.obj")
    scan_points, scan_triangles = _sphere_scan(points, 2)
    surface = Surface(sizes, vertices, points)
    result = fit_surface_points(surface, scan_points, scan_triangles, FitOptions(max_iterations=2))
    feet = project_scan(surface, scan_points, FitOptions())
    assert np.allclose(feet.distance, result.footpoints.distance, rtol=0, atol=1e-12 * _size(points))
    fine = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 48)
    _, reference, _ = trimesh.proximity.closest_point(trimesh.Trimesh(fine.points, fine.triangles, process=False),
                                                      scan_points)
    chord = 1e-4 * _size(points)  # 48 samples a side on patches of a tenth of the size
    assert np.abs(feet.distance - reference).max() < chord
    nearest_sample = cKDTree(fine.points).query(scan_points)[0]  # samples lie on the surface: never nearer
    assert np.all(feet.distance <= nearest_sample + 1e-12 * _size(points))
    back = surface_to_scan(surface, scan_points, scan_triangles, 4)
    coarse = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 4)
    _, expected, _ = trimesh.proximity.closest_point(trimesh.Trimesh(scan_points, scan_triangles, process=False),
                                                     coarse.points)
    assert np.allclose(back, expected, rtol=0, atol=1e-12 * _size(points))
    deviation = two_sided_deviation(surface, scan_points, scan_triangles, feet, 4)
    diagonal = _size(scan_points)
    assert deviation.scan_stats["max"] == pytest.approx(feet.distance.max(), abs=0)
    assert deviation.scan_stats["relative_rms"] == pytest.approx(np.sqrt(np.mean(feet.distance ** 2)) / diagonal)
    assert deviation.surface_stats["p99"] == pytest.approx(np.percentile(expected, 99), rel=1e-9)


def test_closest_points_on_random_triangles():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(60, 3))
    triangles = rng.integers(0, 60, size=(80, 3))
    triangles = triangles[(triangles[:, 0] != triangles[:, 1]) & (triangles[:, 1] != triangles[:, 2])
                          & (triangles[:, 0] != triangles[:, 2])]
    queries = rng.normal(size=(500, 3)) * 1.5
    distance, closest = closest_on_triangles(queries, points, triangles)
    _, expected, _ = trimesh.proximity.closest_point(trimesh.Trimesh(points, triangles, process=False), queries)
    assert np.allclose(distance, expected, rtol=0, atol=1e-12)
    assert np.allclose(np.linalg.norm(closest - queries, axis=1), distance, rtol=0, atol=1e-12)


@pytest.mark.parametrize("change", [dict(plane=-1.0), dict(plane=0.0, point=0.0), dict(fairness=float("nan")),
                                    dict(max_iterations=0), dict(candidates=1.5), dict(solver="dense")])
def test_options_refuse_bad_values(change):
    with pytest.raises(ValueError):
        FitOptions(**change).check()


def _dense_fit(monkeypatch, sizes, vertices, points, scan_points, scan_triangles):
    """The fit with every normal-equation solve done by LAPACK on the dense matrix (an independent reference:
    no sparse factorisation, no iteration); also whether a dense solve ran."""
    import c1surf.fitting.iterate as iterate

    solved = []

    def dense(N, b, start, method="auto"):
        solved.append(N.shape[0])
        return np.linalg.solve(N.toarray(), b)

    with monkeypatch.context() as patched:
        patched.setattr(iterate, "solve", dense)
        fitted = fit_surface_points(Surface(sizes, vertices, points), scan_points, scan_triangles,
                                    FitOptions(max_iterations=2, stop=0.0, solver="superlu")).points
    return fitted, solved


@pytest.mark.parametrize("solver", ["cholesky", "superlu", "cg"])
def test_solvers_agree(solver, monkeypatch):
    """Each solver's fit equals the fit whose systems are solved densely by LAPACK (the cube: 26 vertices)."""
    if solver == "cholesky":
        pytest.importorskip("cholespy")
    sizes, vertices, points = _control("cube.obj")
    scan_points, scan_triangles = _sphere_scan(points, 2)
    reference, solved = _dense_fit(monkeypatch, sizes, vertices, points, scan_points, scan_triangles)
    assert solved and max(solved) <= 3 * len(points) and np.abs(reference - points).max() > 1e-3 * _size(points)
    fitted = fit_surface_points(Surface(sizes, vertices, points), scan_points, scan_triangles,
                                FitOptions(max_iterations=2, stop=0.0, solver=solver)).points
    assert np.abs(fitted - reference).max() < 1e-8 * _size(points)


def test_cholesky_without_cholespy_says_what_to_install(monkeypatch):
    import sys

    import scipy.sparse as sp

    from c1surf.fitting.solve import solve

    monkeypatch.setitem(sys.modules, "cholespy", None)  # import cholespy raises ImportError
    N = sp.csr_matrix(np.array([[2.0, 1.0], [1.0, 2.0]]))
    with pytest.raises(ValueError, match=r"^the 'cholesky' solver needs the cholespy package \(pip install cholespy\)$"):
        solve(N, np.ones(2), np.zeros(2), "cholesky")


@pytest.mark.parametrize("scan", [(np.zeros((0, 3)), np.zeros((0, 3), int)), (np.zeros((4, 3)), np.array([[0, 1, 7]])),
                                  (np.zeros((4, 2)), np.array([[0, 1, 2]]))])
def test_bad_scans_are_refused(scan):
    sizes, vertices, points = _control("cube.obj")
    with pytest.raises(ValueError):
        fit_surface_points(Surface(sizes, vertices, points), *scan, FitOptions())


def test_the_fit_follows_a_change_of_scale_and_position():
    """Every term is a squared length and the weights are divided by the counts: scaling and moving the
    scan and the control mesh together scales and moves the fitted points alike."""
    sizes, vertices, points = _control("cube.obj")
    scan_points, scan_triangles = _sphere_scan(points, 2)
    options = FitOptions(max_iterations=3, stop=0.0)
    reference = fit_surface_points(Surface(sizes, vertices, points), scan_points, scan_triangles, options)
    scale, shift = 250.0, np.array([1e3, -40.0, 7.0])
    moved = fit_surface_points(Surface(sizes, vertices, scale * points + shift), scale * scan_points + shift,
                               scan_triangles, options)
    assert np.abs(moved.points - (scale * reference.points + shift)).max() < 1e-9 * scale * _size(points)
    assert [h["relative_rms"] for h in moved.history] == pytest.approx([h["relative_rms"] for h in reference.history],
                                                                        rel=1e-9)


def test_signed_distances_are_positive_outside():
    """A sphere scan around the cube's surface is outside it (positive), one shrunk into it inside (negative)."""
    sizes, vertices, points = _control("cube.obj")
    surface = Surface(sizes, vertices, points)
    for factor, sign in ((1.0, 1.0), (0.1, -1.0)):
        centre = np.zeros(3)
        scan_points, _ = _sphere_scan(points, 1)
        scan_points = centre + factor * (scan_points - centre)
        feet = project_scan(surface, scan_points, FitOptions())
        signed = signed_scan_to_surface(surface, scan_points, feet)
        assert np.array_equal(np.abs(signed), feet.distance)
        assert np.all(sign * signed > 0)
