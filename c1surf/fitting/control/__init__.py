"""The control mesh a scan is fitted with: Instant Meshes' quad remesh or the scan decimated with its topology
kept (``control_mesh``, ``decimated_quads``), the cleanup of what the construction would refuse (``cleanup``), and
the next face count for a tolerance (``local_refine``)."""
