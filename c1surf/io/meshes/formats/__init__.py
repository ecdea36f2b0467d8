"""Readers of the mesh formats beyond OBJ and PLY: STL (``stl``) and OFF (``off``), listed in ``io.registry``."""
