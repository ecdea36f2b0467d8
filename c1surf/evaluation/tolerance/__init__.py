"""Tessellation to a chordal tolerance (``--tolerance T``): per-patch resolutions, crack-free.

``resolution`` (the bound and the segment counts), ``triangulate`` (one template per
interior and side counts), ``tessellation`` (plan, welded numbering, evaluation),
``chordal`` (the measured error, for uniform tessellations too), ``curvature``
(per-vertex curvature for ``--curvature``).
"""
from .chordal import measured_chordal_error
from .tessellation import ToleranceTessellation, TolerancePlan, plan_tolerance, tessellate_plan, tessellate_to_tolerance

__all__ = ["ToleranceTessellation", "TolerancePlan", "plan_tolerance", "tessellate_plan", "tessellate_to_tolerance",
           "measured_chordal_error"]
