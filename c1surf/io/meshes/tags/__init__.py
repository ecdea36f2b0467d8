"""Sharp-feature tags of a mesh file (OpenSubdiv OBJ ``t`` lines, PLY edge creases and vertex corners)."""
