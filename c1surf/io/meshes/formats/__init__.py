"""Mesh formats beyond OBJ and PLY: the STL (``stl``) and OFF (``off``) readers, listed in ``io.registry``, and the
STL and GLB writers by blocks (``stl_out``, ``glb_out``: the bytes trimesh writes for the whole mesh)."""
