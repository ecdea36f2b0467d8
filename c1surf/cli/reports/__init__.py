"""Commands that report on an input: ``inspect`` (what c1surf sees and will do, before converting), ``measure``
(area, volume, centroid, inertia) and ``diff`` (two patch files or meshes)."""
