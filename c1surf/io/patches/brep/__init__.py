"""Boundary representations of patch sets (solids and shells for STEP and IGES), from c1surf's own adjacency."""
