"""Fitting a G1 surface to a dense scan: the control mesh, the least-squares fit, the deviation.

Plain arrays in and out: the scan is (m, 3) points and (t, 3) triangles. ``control_mesh`` (a quad remesh of the
scan) with ``cleanup`` (the remesher's faults) and ``local_refine``; ``options`` the fit's controls,
``footpoints`` the exact projections, ``system`` the sparse least-squares system, ``solve`` its solvers,
``iterate`` the loop, ``deviation`` the two-sided distances; ``scan_fit`` the whole workflow of ``c1surf fit``.
"""
from .deviation import Deviation, signed_scan_to_surface, two_sided_deviation
from .footpoints import Footpoints
from .iterate import FitResult, fit_surface_points, project_scan
from .options import FitOptions

__all__ = ["FitOptions", "FitResult", "Footpoints", "Deviation", "fit_surface_points", "project_scan",
           "two_sided_deviation", "signed_scan_to_surface"]
