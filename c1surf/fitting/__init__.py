"""Fitting a surface's control points to a triangle scan (``iterate.fit_surface_points``).

Plain arrays in and out: the control mesh is a ``Surface``, the scan (m, 3) points and (t, 3)
triangles. ``options`` the controls, ``footpoints`` the exact projections, ``system`` the sparse
least-squares system, ``solve`` its solvers, ``iterate`` the loop, ``deviation`` the two-sided
distances the command and its report show.
"""
from .deviation import Deviation, signed_scan_to_surface, two_sided_deviation
from .footpoints import Footpoints
from .iterate import FitResult, fit_surface_points, project_scan
from .options import FitOptions

__all__ = ["FitOptions", "FitResult", "Footpoints", "Deviation", "fit_surface_points", "project_scan",
           "two_sided_deviation", "signed_scan_to_surface"]
