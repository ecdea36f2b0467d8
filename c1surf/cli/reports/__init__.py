"""Report commands: ``measure`` (area, volume, centroid, inertia) and ``diff`` (two patch files or meshes)."""
