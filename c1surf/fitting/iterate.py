"""The fit: footpoints and least-squares solves in turn until the deviation stops improving.

Each round projects the scan's vertices onto the exact patches (``footpoints``), builds the
normal equations at those footpoints (``system``), solves them (``solve``) and moves the control
points with ``Surface.update_points``: only the points change, the construction stays that of
the paper, so every fitted surface is G1 (C0 on exact creases) by construction.

After the rounds of the closest fit, the fairness weight grows (``FitOptions.fairness_growth``) while the scan's
own vertices stay within bounds (``growth_bounds``): the fit returns the smoothest surface within the tolerance
rather than the closest one (docs/fit.md, fairness).
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
from .thin_plate import patch_weights, thin_plate_matrix

__all__ = ["FitResult", "fit_surface_points", "control_edges", "project_scan", "fairness_form", "growth_bounds"]


# the fairness continuation (``FitOptions.fairness_growth``): the weight is multiplied by GROWTH_STEP at a time, up
# to GROWTH_CAP times ``FitOptions.fairness``, with at most GROWTH_ROUNDS rounds at each weight (4 instead of 2: fish
# and spot 5 and 2 rounds more, rho and RMS within 3 % and 7 %; docs/fit.md)
GROWTH_STEP, GROWTH_CAP, GROWTH_ROUNDS = 3.0, 100.0, 2


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
    stopped : str, why the rounds of the closest fit ended ("converged", "max_iterations", "worse": the last
        round did not improve and was undone)
    fairness : float, the fairness weight of the result (``FitOptions.fairness`` times the growth it kept)
    """

    points: np.ndarray
    history: list
    footpoints: Footpoints
    timings: dict = field(default_factory=dict)
    solver: str = ""
    stopped: str = ""
    fairness: float = 0.0

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


def fairness_form(surface: Surface, options: FitOptions):
    """(V, V) csr_matrix, the fairness term of the normal equations with its weight: ``fairness / P`` times the
    thin-plate form of the surface's P patches (``thin_plate.thin_plate_matrix``, each patch weighted by the mean
    patch area over its own at the current points) or ``fairness / V`` times L^T L, L the umbrella Laplacian of
    the control mesh (``options.fairness_term``)."""
    n_vertices = surface.n_input_vertices
    if options.fairness_term == "umbrella":
        laplacian = umbrella_laplacian(control_edges(surface), n_vertices)
        return ((options.fairness / n_vertices) * (laplacian.T @ laplacian)).tocsr()
    biquadratic, bicubic = surface.biquadratic, surface.bicubic
    n_quad, n_cubic = biquadratic.shape[0], bicubic.shape[0]
    n_patches = n_quad + n_cubic
    weights = patch_weights(biquadratic, bicubic)
    K = thin_plate_matrix(surface.stencil(), n_quad, n_cubic, weights)
    return ((options.fairness / max(n_patches, 1)) * K).tocsr()


def growth_bounds(closest: dict, diagonal: float, options: FitOptions) -> dict:
    """{"rms", "p99", "max": bound}: the distances (absolute) a fit with a grown fairness may reach: each the
    closest fit's times 1 + ``options.fairness_growth`` (a noisy scan: the noise, not the surface, makes the
    distance), or the accuracy ``options.smooth_within`` asks for (RMS; p99 3.5 and max 10.5 times it: 2.8e-4,
    9.8e-4, 2.94e-3 of the diagonal at the default, inside issue 34's targets 3e-4, 1e-3, 3e-3), whichever is
    larger; the largest distance at most ``options.max_within`` (relative) when that is set."""
    grow = 1.0 + options.fairness_growth
    tolerance = options.smooth_within * diagonal
    bounds = {key: max(grow * closest[key], factor * tolerance) for key, factor in (("rms", 1.0), ("p99", 3.5),
                                                                                    ("max", 10.5))}
    if options.max_within > 0:  # never past the largest distance asked for (--tolerance)
        bounds["max"] = min(bounds["max"], options.max_within * diagonal)
    return bounds


def project_scan(surface: Surface, scan_points: np.ndarray, options: FitOptions,
                 start: Footpoints | None = None) -> Footpoints:
    """The footpoints of ``scan_points`` on ``surface``'s exact patches (``footpoints.project_points``;
    ``start``: the previous round's, where the Newton steps begin)."""
    patches = patch_set(surface.biquadratic, surface.bicubic, options.start_resolution)
    return project_points(patches, scan_points, options.candidates, options.newton_steps, start)


def fit_surface_points(surface: Surface, scan_points, scan_triangles, options: FitOptions | None = None,
                       progress=None, measured: int | None = None) -> FitResult:
    """Fit the control points of ``surface`` to a triangle scan; the connectivity and construction stay.

    Parameters
    ----------
    surface : Surface, polynomial (not rational), d = 3; its current points are the start
    scan_points : (m, 3) float, the scan's vertices (the samples)
    scan_triangles : (t, 3) int, the scan's triangles (their area-weighted vertex normals are the
        point-to-plane normals)
    options : FitOptions
    progress : callable(label, amount, total) or None, called once per round
    measured : int or None, the first ``measured`` scan points are the scan's own vertices (the rest samples added
        between them, ``scan_fit.fitting_samples``): the bounds of the fairness continuation hold on those (None:
        all)

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
    fair = fairness_form(surface, options)
    timings = {"footpoints": 0.0, "system": 0.0, "solve": 0.0, "update": 0.0}
    state = {"method": available_solver(options.solver), "start": time.perf_counter(),
             "current": np.array(surface.points[:, :3], dtype=np.float64)}

    def clock(name):
        now = time.perf_counter()
        timings[name] += now - state["start"]
        state["start"] = now

    def one_round(form):
        """Solve at the current footpoints with the fairness ``form``, move the surface, project again:
        (points, footpoints, stats)."""
        feet, current = state["feet"], state["current"]
        A = basis_rows(feet, surface.quad_frames.shape[0], surface.stencil().shape[0]) @ surface.stencil()
        N, b = normal_equations(A.tocsr(), samples, normals, form, current, options.plane, point_weights)
        clock("system")
        points = solve(N, b, current.ravel(), state["method"]).reshape(n_vertices, 3)
        if not np.all(np.isfinite(points)) and state["method"] != "superlu":  # a factorisation that broke down
            state["method"] = "superlu"
            points = solve(N, b, current.ravel(), "superlu").reshape(n_vertices, 3)
        if not np.all(np.isfinite(points)):
            raise ValueError("the fitting system is singular: no finite control points solve it")
        clock("solve")
        surface.update_points(points)
        clock("update")
        new_feet = project_scan(surface, samples, options, feet)
        clock("footpoints")
        return points, new_feet, distance_stats(new_feet.distance, diagonal)

    def rounds(form, limit: int, undo_worse: bool, beyond=None) -> str:
        """Rounds at the fairness ``form`` until the RMS changes by less than ``options.stop`` (a worse round is
        undone when ``undo_worse``; they stop as soon as ``beyond()`` says so): why they stopped."""
        for _ in range(limit):
            round_start = sum(timings.values())
            points, new_feet, stats = one_round(form)
            previous = history[-1]["rms"]
            if progress is not None:
                progress("fitting", 1, options.max_iterations)
            if undo_worse and stats["rms"] > previous:
                surface.update_points(state["current"])
                return "worse"
            history.append(dict(iteration=len(history), **stats, seconds=sum(timings.values()) - round_start))
            state["current"], state["feet"] = points, new_feet
            if abs(previous - stats["rms"]) <= options.stop * previous:
                return "converged"
            if beyond is not None and beyond():
                return "beyond"
        return "max_iterations"

    kept_samples = slice(0, samples.shape[0] if measured is None else int(measured))

    def measured_stats() -> dict:
        return distance_stats(state["feet"].distance[kept_samples], diagonal)

    state["feet"] = project_scan(surface, samples, options)
    clock("footpoints")
    history = [dict(iteration=0, **distance_stats(state["feet"].distance, diagonal), seconds=sum(timings.values()))]
    stopped = rounds(fair, options.max_iterations, True)
    growth = 1.0  # the fairness grows while the fit stays within the bounds of ``growth_bounds``
    if options.fairness_growth > 0 and options.fairness > 0:
        bounds = growth_bounds(measured_stats(), diagonal, options)

        def beyond() -> bool:  # a larger weight only moves further: stop the rounds at the first one past a bound
            return any(measured_stats()[k] > bound for k, bound in bounds.items())

        while growth * GROWTH_STEP <= GROWTH_CAP * (1 + 1e-9):
            kept = (state["current"], state["feet"], len(history))
            rounds(growth * GROWTH_STEP * fair, GROWTH_ROUNDS, False, beyond)
            if beyond():  # too far from the scan: undo
                state["current"], state["feet"] = kept[:2]
                del history[kept[2]:]
                surface.update_points(state["current"])
                break
            growth *= GROWTH_STEP
    return FitResult(state["current"], history, state["feet"], timings, state["method"], stopped,
                     growth * options.fairness)
