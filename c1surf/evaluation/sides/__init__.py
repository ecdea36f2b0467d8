"""Patch sides: which sides of a patch set are one edge, from the geometry alone (``matching``)."""
