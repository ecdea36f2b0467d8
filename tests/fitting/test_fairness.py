"""The fit's fairness (issue 34): noise on the scan does not become ripple of the fitted surface."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.curvature import PatchSampler
from c1surf.fitting.iterate import fit_surface_points
from c1surf.fitting.options import FitOptions
from c1surf.io.meshes.obj import read_obj

from conftest import SAMPLES

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
from fit import median_edge, sampler_ripple  # noqa: E402  (bench/fit.py's rho, the bench's shape column)
from fit_core import quad_split  # noqa: E402


def _sphere_fit(noise: float, options: FitOptions):
    """(rho, relative RMS, FitResult) of the fit of a cube split twice into quads (96 faces, 384 patches) to an icosphere
    (2,562 vertices) whose vertices are moved along the radius by Gaussian noise of ``noise`` x its diagonal."""
    mesh = read_obj(str(SAMPLES / "cube.obj"))
    points, sizes, corners = mesh.points, mesh.face_sizes, mesh.face_vertices
    for _ in range(2):
        points, sizes, corners = quad_split(points, sizes, corners)
    points = points - (points.max(axis=0) + points.min(axis=0)) / 2
    sphere = trimesh.creation.icosphere(4)
    unit = np.asarray(sphere.vertices)
    radius = 0.85 * float(np.linalg.norm(points, axis=1).mean())
    diagonal = 2 * np.sqrt(3) * radius
    scan = radius * unit + np.random.default_rng(1).normal(scale=noise * diagonal, size=len(unit))[:, None] * unit
    surface = Surface(sizes, corners, points, SurfaceOptions(refinements="auto"))
    result = fit_surface_points(surface, scan, np.asarray(sphere.faces), options)
    rho = sampler_ripple(PatchSampler([surface.biquadratic, surface.bicubic]),
                         0.5 * median_edge(sizes, corners, result.points))
    return rho, result.history[-1]["relative_rms"], result


def test_noise_does_not_ripple_the_fit():
    """Noise of 1e-3 of the diagonal: rho of the fitted surface within 10 % of the noiseless fit's, at the default
    fairness; the noisy fit stays at the noise's level from the scan (it is not flattened away)."""
    options = FitOptions()
    clean_rho, clean_rms, _ = _sphere_fit(0.0, options)
    noisy_rho, noisy_rms, noisy = _sphere_fit(1e-3, options)
    assert clean_rms < 5e-4 and noisy_rms < 1.5e-3
    assert abs(noisy_rho - clean_rho) <= 0.1 * clean_rho, (clean_rho, noisy_rho)
    assert noisy.fairness > options.fairness  # the continuation smoothed the noise away
    closest_rho = _sphere_fit(1e-3, FitOptions(fairness_growth=0.0))[0]  # the closest fit keeps more of the noise
    assert noisy_rho < 0.95 * closest_rho, (noisy_rho, closest_rho)


def test_the_continuation_stays_within_its_bounds():
    """The grown fairness keeps the scan within 1.1 times the closest fit's distances or within smooth_within's
    bounds, and within max_within when it is set (then the weight grows less)."""
    closest = _sphere_fit(0.0, FitOptions(fairness_growth=0.0))[2].history[-1]
    free = _sphere_fit(0.0, FitOptions())[2]
    capped = _sphere_fit(0.0, FitOptions(max_within=1.05 * closest["relative_max"]))[2]
    smooth = FitOptions().smooth_within
    for result, cap in ((free, None), (capped, 1.05 * closest["relative_max"])):
        last = result.history[-1]
        assert last["relative_rms"] <= max(1.1 * closest["relative_rms"], smooth) * (1 + 1e-12)
        assert last["relative_p99"] <= max(1.1 * closest["relative_p99"], 3.5 * smooth) * (1 + 1e-12)
        assert last["relative_max"] <= min(max(1.1 * closest["relative_max"], 10.5 * smooth), cap or 1.0) * (1 + 1e-12)
    assert free.fairness > FitOptions().fairness and capped.fairness <= free.fairness
