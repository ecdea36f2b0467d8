"""Exact (C0) creases on the mesh: the cut into sheets with ghost quads (``sheets``), and the crease
sectors merged first where they have too many faces for it (``sectors``). Integers only."""
