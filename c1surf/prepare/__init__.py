"""Input preparation: from a mesh as read to the construction's input (``pipeline.prepare_mesh``), on plain arrays.

Below ``io`` (which only turns bytes into a MeshFile and back, and never imports this package) and above the
construction. ``options.InputOptions`` says what to read besides the polygons and how to repair; ``notes``
words what was changed. The command line reaches it only through ``c1surf.api.load_surface``.
"""
