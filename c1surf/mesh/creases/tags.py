"""The sharp-feature tags a mesh file carries (creases, corners, holes, other tags), as plain arrays.

The readers (``io.meshes``) fill them and check them against the mesh; the input preparation
(``prepare.features``) turns them into the construction's ``SharpFeatures`` and names every tag it does not honour.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["SharpTags"]


def _ints(n: int = 0) -> np.ndarray:
    return np.zeros(n, dtype=np.int64)


@dataclass(eq=False)  # eq on numpy fields would be ambiguous
class SharpTags:
    """Creases, corners, holes and other tags as written in a mesh file (indices from 0).

    Attributes
    ----------
    crease_edges : ndarray, shape (E, 2), int64
        Vertex pairs of the crease edges (an OBJ chain ``t crease k/1/0`` gives k - 1 rows).
    crease_sharpness : ndarray, shape (E,), float64
        Sharpness of each crease edge as written (OpenSubdiv: 0 smooth, >= 10 infinitely sharp).
    crease_lines : ndarray, shape (E,), int64, or None
        1-based line of each crease edge's tag (text files), else None.
    corner_vertices : ndarray, shape (C,), int64
    corner_sharpness : ndarray, shape (C,), float64
    corner_lines : ndarray, shape (C,), int64, or None
    hole_faces : ndarray, shape (H,), int64
        Faces tagged as holes, in file order of the faces.
    hole_lines : ndarray, shape (H,), int64, or None
    interpolate_boundary : int or None
        OpenSubdiv ``interpolateboundary`` mode (0 none, 1 edges and corners, 2 edges only), None when absent.
    other : list of (str, int or None)
        Name and line of every other tag (``creasemethod``, ``vertexedit``, ...), kept by name.
    """

    crease_edges: np.ndarray = field(default_factory=lambda: _ints(0).reshape(0, 2))
    crease_sharpness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    crease_lines: np.ndarray | None = None
    corner_vertices: np.ndarray = field(default_factory=_ints)
    corner_sharpness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    corner_lines: np.ndarray | None = None
    hole_faces: np.ndarray = field(default_factory=_ints)
    hole_lines: np.ndarray | None = None
    interpolate_boundary: int | None = None
    other: list = field(default_factory=list)

    def is_empty(self) -> bool:
        """True when the file carries no tag at all."""
        return not (len(self.crease_edges) or len(self.corner_vertices) or len(self.hole_faces)
                    or self.interpolate_boundary is not None or self.other)

    def summary(self) -> str:
        """Every tag kind read, with counts, e.g. ``crease (12 edges), corner (3 vertices), interpolateboundary 1``.

        Other tags are named, with the number of their lines; "" when there are no tags.
        """
        parts = []
        for name, count, unit in (("crease", len(self.crease_edges), "edge"),
                                  ("corner", len(self.corner_vertices), "vertex"),
                                  ("hole", len(self.hole_faces), "face")):
            if count:
                units = "vertices" if unit == "vertex" and count != 1 else unit + ("s" if count != 1 else "")
                parts.append(f"{name} ({count} {units})")
        if self.interpolate_boundary is not None:
            parts.append(f"interpolateboundary {self.interpolate_boundary}")
        counts: dict[str, int] = {}
        for name, _ in self.other:
            counts[name] = counts.get(name, 0) + 1
        parts.extend(f"{name} ({n} tag{'s' if n != 1 else ''})" for name, n in counts.items())
        return ", ".join(parts)
