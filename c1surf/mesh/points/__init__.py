"""Positions as points: clustering coincident points (``clusters``) and the checks that the coordinates are ones
the construction can take and span a surface (``geometry_checks``)."""
