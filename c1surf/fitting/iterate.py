"""The fit: footpoints and least-squares solves in turn until the deviation stops improving.

Each round projects the scan's vertices onto the exact patches (``footpoints``), builds the
normal equations at those footpoints (``system``), solves them (``solve``) and moves the control
points with ``Surface.update_points``: only the points change, the construction stays that of
the paper, so every fitted surface is G1 (C0 on exact creases) by construction.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..construction.surface import Surface
from .deviation import distance_stats
from .footpoints import Footpoints, patch_set, project_points
from .options import FitOptions
from .solve import available_solver, solve
from .system import basis_rows, normal_equations, umbrella_laplacian, vertex_normals

__all__ = ["FitResult", "fit_surface_points", "control_edges", "project_scan"]


@dataclass
class FitResult:
    """What ``fit_surface_points`` returns.

    points : (V, 3) float, the fitted control points (the surface is ``surface.update_points(points)``:
        ``fit_surface_points`` leaves the surface there)
    history : list of dict, one per projection: "iteration" (0 = the start), scan-to-surface
        "rms", "p99", "max" (absolute) and "relative_*" (over the scan's bounding-box diagonal),
        "seconds" (that round's, its projection included)
    footpoints : Footpoints of the scan's vertices on the fitted surface
    timings : dict, seconds per stage summed over the rounds: "footpoints", "system", "solve", "update"
    solver : str, the solver used
    stopped : str, why the loop ended ("converged", "max_iterations", "worse": the last round
        did not improve and was undone)
    """

    points: np.ndarray
    history: list
    footpoints: Footpoints
    timings: dict = field(default_factory=dict)
    solver: str = ""
    stopped: str = ""

    @property
    def iterations(self) -> int:
        """Solves kept."""
        return len(self.history) - 1


def control_edges(surface: Surface) -> np.ndarray:
    """(k, 2) int: the edges of the surface's control mesh in its input numbering (ghost vertices left out)."""
    t = surface.topology
    mesh = t.input
    a, b = mesh.origin, mesh.origin[mesh.next]
    real = (a < t.vertex_source.size) & (b < t.vertex_source.size)
    return np.stack([t.vertex_source[a[real]], t.vertex_source[b[real]]], axis=1)


def sample_point_weights(triangles: np.ndarray, n_samples: int, options: FitOptions):
    """The point-to-point weight of every sample: ``options.rim`` on the scan's rims (vertices of an edge of one
    triangle: an open scan's boundary and holes), ``options.point`` elsewhere; a float when the scan is closed."""
    edges = np.sort(np.asarray(triangles, dtype=np.int64)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    rim = unique[counts == 1].ravel()
    if rim.size == 0:
        return options.point
    weights = np.full(n_samples, float(options.point))
    weights[rim] = options.rim
    return weights


def project_scan(surface: Surface, scan_points: np.ndarray, options: FitOptions,
                 start: Footpoints | None = None) -> Footpoints:
    """The footpoints of ``scan_points`` on ``surface``'s exact patches (``footpoints.project_points``;
    ``start``: the previous round's, where the Newton steps begin)."""
    patches = patch_set(surface.biquadratic, surface.bicubic, options.start_resolution)
    return project_points(patches, scan_points, options.candidates, options.newton_steps, start)


def fit_surface_points(surface: Surface, scan_points, scan_triangles, options: FitOptions | None = None,
                       progress=None) -> FitResult:
    """Fit the control points of ``surface`` to a triangle scan; the connectivity and construction stay.

    Parameters
    ----------
    surface : Surface, polynomial (not rational), d = 3; its current points are the start
    scan_points : (m, 3) float, the scan's vertices (the samples)
    scan_triangles : (t, 3) int, the scan's triangles (their area-weighted vertex normals are the
        point-to-plane normals)
    options : FitOptions
    progress : callable(label, amount, total) or None, called once per round

    Returns
    -------
    FitResult; ``surface`` is left on the fitted points

    Long: the checks of the inputs, then one loop whose rounds (footpoints, system, solve, update, stop rule)
    share the timings and the undo of a worse round.
    """
    options = (options or FitOptions()).check()
    if surface.rational:
        raise ValueError("fitting a rational surface is not supported: its patches are not linear in the points")
    samples = np.asarray(scan_points, dtype=np.float64)
    if samples.ndim != 2 or samples.shape[1] != 3 or samples.shape[0] == 0:
        raise ValueError(f"expected scan points of shape (m, 3), got {samples.shape}")
    if surface.points.shape[1] != 3:
        raise ValueError(f"fitting needs a surface of 3D points, this one carries {surface.points.shape[1]} columns")
    triangles = np.asarray(scan_triangles)
    if triangles.ndim != 2 or triangles.shape[1] != 3 or triangles.size == 0:
        raise ValueError(f"expected scan triangles of shape (t, 3), got {triangles.shape}")
    if triangles.min() < 0 or triangles.max() >= samples.shape[0]:
        raise ValueError("a scan triangle refers to a vertex that does not exist")
    diagonal = float(np.linalg.norm(samples.max(axis=0) - samples.min(axis=0)))
    normals = vertex_normals(samples, triangles)
    point_weights = sample_point_weights(triangles, samples.shape[0], options)
    n_vertices = surface.n_input_vertices
    laplacian = umbrella_laplacian(control_edges(surface), n_vertices)
    method = available_solver(options.solver)
    timings = {"footpoints": 0.0, "system": 0.0, "solve": 0.0, "update": 0.0}

    def clock(name, start):
        timings[name] += time.perf_counter() - start
        return time.perf_counter()

    start = time.perf_counter()
    current = np.array(surface.points[:, :3], dtype=np.float64)
    feet = project_scan(surface, samples, options)
    start = clock("footpoints", start)
    history = [dict(iteration=0, **distance_stats(feet.distance, diagonal), seconds=sum(timings.values()))]
    stopped = "max_iterations"
    for iteration in range(1, options.max_iterations + 1):
        round_start = sum(timings.values())
        A = basis_rows(feet, surface.quad_frames.shape[0], surface.stencil().shape[0]) @ surface.stencil()
        N, b = normal_equations(A.tocsr(), samples, normals, laplacian, current, options.plane, point_weights,
                                options.fairness)
        start = clock("system", start)
        points = solve(N, b, current.ravel(), method).reshape(n_vertices, 3)
        if not np.all(np.isfinite(points)) and method != "superlu":  # a factorisation that broke down
            method = "superlu"
            points = solve(N, b, current.ravel(), method).reshape(n_vertices, 3)
        if not np.all(np.isfinite(points)):
            raise ValueError("the fitting system is singular: no finite control points solve it")
        start = clock("solve", start)
        surface.update_points(points)
        start = clock("update", start)
        new_feet = project_scan(surface, samples, options, feet)
        start = clock("footpoints", start)
        stats = distance_stats(new_feet.distance, diagonal)
        previous = history[-1]["rms"]
        if progress is not None:
            progress("fitting", 1, options.max_iterations)
        if stats["rms"] > previous:  # worse: undo the round
            surface.update_points(current)
            stopped = "worse"
            break
        history.append(dict(iteration=iteration, **stats, seconds=sum(timings.values()) - round_start))
        current, feet = points, new_feet
        if previous - stats["rms"] <= options.stop * previous:
            stopped = "converged"
            break
    return FitResult(current, history, feet, timings, method, stopped)
