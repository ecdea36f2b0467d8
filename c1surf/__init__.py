"""c1surf: G1 Bezier surfaces from polygon meshes (J. Peters)."""
__version__ = "0.1.0"
