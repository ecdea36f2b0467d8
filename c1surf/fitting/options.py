"""The controls of the fit: weights of the least-squares terms, iterations, stop rule."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["FitOptions", "SOLVERS", "FAIRNESS_TERMS"]

SOLVERS = ("auto", "cholesky", "superlu", "cg")
FAIRNESS_TERMS = ("thin-plate", "umbrella")


@dataclass(frozen=True)
class FitOptions:
    """How ``iterate.fit_surface_points`` moves the control points.

    The energy minimised at fixed footpoints (``system``) is, with X the (V, 3) control points,
    r_i = x(patch_i, u_i, v_i) - p_i the residual of scan vertex i and n_i its unit normal,

        E(X) = plane / m sum_i (n_i . r_i)^2 + point / m sum_i |r_i|^2 + fairness / V sum_v |(L X)_v|^2

    with L the umbrella Laplacian of the control mesh ((L X)_v = X_v minus the mean of its neighbours), or, with
    ``fairness_term="thin-plate"``, fairness / P times the thin-plate energy of the P patches (``thin_plate``:
    the exact integral of |S_uu|^2 + 2 |S_uv|^2 + |S_vv|^2 over each patch, weighted by the mean patch area over
    the patch's own).
    Dividing by m and V makes the weights independent of the number of scan vertices and of control
    points; every term is a squared length, so the minimiser scales with the model (multiply the scan
    and the control mesh by s and the fitted points are multiplied by s).

    plane : float >= 0, weight of the point-to-plane term (1, as the prototype)
    point : float >= 0, weight of the point-to-point term: the point-to-plane term alone leaves the
        control points free to slide along the surface. 0.01, not the prototype's 0.1: the footpoints lag
        one round behind, so this term drags the surface tangentially and slows the convergence
        (spot with its own 180-face control mesh, 10 rounds: scan-to-surface RMS 6.8e-4 of the diagonal
        at 0.01, 8.3e-4 at 0.1; on a surface's own samples 0.1 converges linearly, 0 quadratically)
    fairness : float >= 0, weight of the umbrella term. The umbrella operator is dimensionless (its
        large eigenvalues are O(1) on any mesh), so against the data term's stiffness of about 1 per
        control point a weight of 1e-3 barely moves the control points the scan pins, and holds those
        it leaves (nearly) free, where folds and bulges between samples start. Measured on spot's scan
        (11,533 vertices; RMS / max of the diagonal, scan to surface, then surface to scan):
        own control mesh (188 vertices, 2,928 patches): 0: 6.6e-4 / 2.3e-3 RMS, surface-to-scan max
        3.0e-2 (bulges); 1e-3: 6.8e-4, surface-to-scan max 6.3e-3; 1e-2: 1.0e-3 (the term shrinks a
        coarse control mesh); that mesh split into 732 quads: 1e-3: 1.7e-4, surface-to-scan max
        1.4e-2 (four samples a patch); 1e-2: 2.1e-4, surface-to-scan max 3.2e-3. Raise it where the
        scan has few samples per patch. 0: pure least squares (exact recovery of a surface's own
        control points, ``tests/fitting``). The default 3e-3 (was 1e-3) is measured on the default remesh
        of the small faceted scans (about 3,000 control faces, one a scan vertex, samples added on the
        facets by ``scan_fit.fitting_samples``; RMS / p99 / max scan to surface, max surface to scan):
        goathead 1e-3: 1.8e-4 / 6.0e-4 / 1.2e-3, 3.3e-3; 3e-3: 2.1e-4 / 6.3e-4 / 1.5e-3, 3.0e-3; 1e-2:
        2.6e-4 / 8.2e-4 / 1.7e-3, 2.9e-3; koala 1e-3: 1.8e-4 / 6.3e-4 / 1.8e-3, 4.0e-3; 3e-3: 2.1e-4 /
        7.4e-4 / 1.9e-3, 3.8e-3; wingnut 1e-3 and 3e-3: 1.5e-4 and 1.7e-4 RMS, 2.1e-3 either way; spot
        with its own control mesh: 6.8e-4 at 1e-3, 7.7e-4 at 3e-3
    fairness_term : "umbrella" (the default) or "thin-plate". Measured (bench/fairness.py, issue 34) at the same
        scan-to-surface RMS the two give the same rho (the ripple of mean curvature) within 5 %: goathead umbrella
        1e-2: RMS 2.73e-4, rho 2.71; thin-plate 1e-2: 2.67e-4, 2.73; wingnut umbrella 3e-2: 2.09e-4, 5.45;
        thin-plate 3e-2: 2.04e-4, 5.63; koala umbrella 1e-2: 2.79e-4, 2.17; thin-plate 1e-2: 3.06e-4, 2.12 (max
        3.9e-3 against 2.8e-3). On a sphere fitted with a cube split twice the thin-plate term gives rho 0.11
        against the umbrella's 0.085 (the hole patches' parametrisation is not uniform, their energy is not
        all shape). So the umbrella stays; the thin-plate term is the surface's own measure, for callers that
        want it
    fairness_growth : float >= 0, the continuation that makes the fit the smoothest surface within a tolerance
        rather than the closest one: once the rounds at ``fairness`` end, the weight is multiplied by 3 at a time
        (at most 100 times, two rounds at each) while the scan's own vertices stay within max(1 +
        fairness_growth times the closest fit's RMS, p99 and max, ``smooth_within``'s bounds); the first weight
        past them is undone. The relative bound is the noise's: on a noisy scan the distance is the noise's, and
        a smoother surface costs it little (a sphere with noise of 1e-3 of the diagonal: the weight grows 9
        times, rho within 2 % of the noiseless fit's, ``tests/fitting/test_fairness.py``). 0: the closest fit
    smooth_within : float in [0, 1), the scan-to-surface RMS (relative to the diagonal) the continuation may
        reach on a clean scan, with p99 4 and max 12 times it (2.5e-4: RMS 2.5e-4, p99 1e-3, max 3e-3, inside
        issue 34's targets)
    max_within : float in [0, 1), a cap on the continuation's bound of the largest distance, relative to the
        diagonal (0: none); ``scan_fit`` sets it to ``--tolerance``, so the smoother surface never leaves the
        tolerance the control mesh was grown for
    rim : float >= 0, the point-to-point weight of an open scan's rim vertices (those on an edge of one
        triangle), instead of ``point``: the point-to-plane term cannot move the surface's boundary along the
        surface, so without it the fitted surface stops short of the scan's rims (docs/fit.md, open scans)
    max_iterations : int >= 1, rounds of footpoints + solve
    stop : float >= 0, stop when the scan-to-surface RMS improves by less than this fraction in a round
        (1e-2: spot's rounds 7-10 with its own control mesh gain 0.2-0.9 % each, 1.5 % together)
    candidates : int >= 1, patches tried per scan vertex (those of its nearest start samples)
    newton_steps : int >= 1, Newton steps per footpoint projection
    start_resolution : int >= 1, samples per patch side of the start grid of the projections
    solver : "auto" (= "cg": conjugate gradients warm-started at the current points, the fastest measured,
        ``solve``), "cg", "cholesky" (needs ``cholespy``) or "superlu"
    """

    plane: float = 1.0
    point: float = 0.01
    fairness: float = 3e-3
    fairness_term: str = "umbrella"
    fairness_growth: float = 0.1
    smooth_within: float = 2.8e-4
    max_within: float = 0.0
    rim: float = 1.0
    max_iterations: int = 10
    stop: float = 1e-2
    candidates: int = 3
    newton_steps: int = 8
    start_resolution: int = 4
    solver: str = "auto"

    def check(self) -> "FitOptions":
        """Raise ValueError for a value the fit cannot take; else return self."""
        for name in ("plane", "point", "fairness", "stop", "rim"):
            value = getattr(self, name)
            if not (value >= 0 and value < float("inf")):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if self.plane + self.point <= 0:
            raise ValueError("plane + point must be > 0: without a data term nothing is fitted")
        for name, low in (("max_iterations", 1), ("candidates", 1), ("newton_steps", 1), ("start_resolution", 1)):
            value = getattr(self, name)
            if int(value) != value or value < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
        if self.fairness_term not in FAIRNESS_TERMS:
            raise ValueError(f"fairness_term must be one of {FAIRNESS_TERMS}, got {self.fairness_term!r}")
        if not (0 <= self.fairness_growth < float("inf")):
            raise ValueError(f"fairness_growth must be a finite number >= 0, got {self.fairness_growth!r}")
        if not (0 <= self.max_within < 1):
            raise ValueError(f"max_within is a fraction of the bounding-box diagonal in [0, 1), got {self.max_within!r}")
        if not (0 <= self.smooth_within < 1):
            raise ValueError(f"smooth_within is a fraction of the bounding-box diagonal in [0, 1), got "
                             f"{self.smooth_within!r}")
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {SOLVERS}, got {self.solver!r}")
        return self
