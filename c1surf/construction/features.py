"""Sharp features as construction input: creases, corners and holes (OpenSubdiv's meaning).

The paper has no sharp features; c1surf's rules (docs/sharp-features.md):

- **hole** face: it gets no patches, but its vertices still shape the
  neighbouring surface (its corners take part in both refinements); its rim is
  a boundary of the surface. Exact: the kept patches are those of the
  untagged mesh, less the hole's.
- **crease** edge of sharpness s and **corner** vertex of sharpness s: the two
  Doo-Sabin steps of A1 pull their new points towards the crease polygon (or
  the corner) by a weight that grows with s (``stencils.creases``); A2 and A3
  are unchanged, so the surface stays G1 everywhere (Theorem 1.3.3 holds for
  any refined points). s = 0 is smooth; s >= 10 ("infinitely sharp" in
  OpenSubdiv) is taken as s = 10, the sharpest G1 crease: a narrow fillet
  (on a cube of side 2 the surface comes within 0.018 of each corner), not a
  C0 crease.
- OpenSubdiv's rules: a vertex on three or more sharp edges is a corner (its
  sharpness the mean of those edges'), a vertex on one sharp edge is a dart
  (smooth).

Sharpness is topology: it changes the weights of the refinement steps, never
reads the points, so the construction stays linear in them and
``Surface.update_points`` and ``Surface.stencil()`` work as without it.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

INFINITELY_SHARP = 10.0
"""OpenSubdiv's sharpness of an infinitely sharp crease; larger values are taken as this."""


def _ints(shape=(0,)) -> np.ndarray:
    return np.zeros(shape, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class SharpFeatures:
    """Creases, corners and holes of an input mesh, in the input's numbering (from 0).

    Attributes
    ----------
    crease_edges : (E, 2) int, vertex pairs (each an edge of the mesh)
    crease_sharpness : (E,) float >= 0 (0 smooth, >= 10 infinitely sharp)
    corner_vertices : (C,) int
    corner_sharpness : (C,) float >= 0
    hole_faces : (H,) int
    vertex_identity : (V,) int or None, the vertex each vertex stands for where several copies of one
        vertex meet along non-manifold edges cut into sheets (``mesh.creases.non_manifold``): the C0
        crease names its crease pieces by these, so the sheets' pieces pair up; None: every vertex itself
    """

    crease_edges: np.ndarray = field(default_factory=lambda: _ints((0, 2)))
    crease_sharpness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    corner_vertices: np.ndarray = field(default_factory=_ints)
    corner_sharpness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    hole_faces: np.ndarray = field(default_factory=_ints)
    vertex_identity: np.ndarray | None = None

    def __post_init__(self):
        for name, kind, shape in (("crease_edges", np.int64, (-1, 2)), ("crease_sharpness", np.float64, (-1,)),
                                  ("corner_vertices", np.int64, (-1,)), ("corner_sharpness", np.float64, (-1,)),
                                  ("hole_faces", np.int64, (-1,))):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=kind).reshape(shape))

    def is_empty(self) -> bool:
        """True when nothing is sharp and nothing is a hole."""
        return not (np.any(self.crease_sharpness > 0) or np.any(self.corner_sharpness > 0) or self.hole_faces.size)

    def check(self, n_vertices: int, n_faces: int) -> "SharpFeatures":
        """Raise ValueError for an index out of range, a mismatched count or a sharpness that is not a number >= 0."""
        if len(self.crease_edges) != len(self.crease_sharpness):
            raise ValueError(f"{len(self.crease_edges)} crease edges but {len(self.crease_sharpness)} sharpness values")
        if len(self.corner_vertices) != len(self.corner_sharpness):
            raise ValueError(f"{len(self.corner_vertices)} corners but {len(self.corner_sharpness)} sharpness values")
        for what, values, count in (("crease vertex", self.crease_edges, n_vertices),
                                    ("corner vertex", self.corner_vertices, n_vertices),
                                    ("hole face", self.hole_faces, n_faces)):
            bad = values[(values < 0) | (values >= count)]
            if bad.size:
                raise ValueError(f"{what} {int(bad.flat[0])} is not in 0..{count - 1}")
        if self.vertex_identity is not None and len(self.vertex_identity) != n_vertices:
            raise ValueError(f"{len(self.vertex_identity)} vertex identities for {n_vertices} vertices")
        for what, values in (("crease", self.crease_sharpness), ("corner", self.corner_sharpness)):
            if not np.all(np.isfinite(values) & (values >= 0)):
                raise ValueError(f"{what} sharpness must be a number >= 0 (0 smooth, 10 or more infinitely sharp)")
        return self

    def merged(self, other: "SharpFeatures") -> "SharpFeatures":
        """Both sets together (an edge or corner named twice keeps its largest sharpness)."""
        return SharpFeatures(np.concatenate([self.crease_edges, other.crease_edges]),
                             np.concatenate([self.crease_sharpness, other.crease_sharpness]),
                             np.concatenate([self.corner_vertices, other.corner_vertices]),
                             np.concatenate([self.corner_sharpness, other.corner_sharpness]),
                             np.unique(np.concatenate([self.hole_faces, other.hole_faces])),
                             self.vertex_identity if self.vertex_identity is not None else other.vertex_identity)


@dataclass(frozen=True)
class CoarseSharpness:
    """Sharpness on the coarse mesh the refinement starts from (repaired, ghosted).

    halfedge : (H,) float, sharpness of the edge of every half-edge (both half-edges of an edge alike)
    vertex : (V,) float, corner sharpness of every vertex (tagged corners, and vertices on
        three or more sharp edges), 0 elsewhere
    """

    halfedge: np.ndarray
    vertex: np.ndarray


def coarse_sharpness(mesh, vertex_source: np.ndarray, features: SharpFeatures) -> CoarseSharpness | None:
    """Map input creases and corners onto the half-edges and vertices of the coarse mesh.

    Parameters
    ----------
    mesh : HalfEdgeMesh, the coarse mesh (repaired; ghost vertices, numbered after
        ``vertex_source.size``, match no input vertex)
    vertex_source : (V',) int, input vertex of every repaired vertex
    features : SharpFeatures

    Returns
    -------
    CoarseSharpness, or None when no crease or corner is sharp.
    """
    if not (np.any(features.crease_sharpness > 0) or np.any(features.corner_sharpness > 0)):
        return None
    n_input = int(max(vertex_source.max(initial=-1), features.crease_edges.max(initial=-1),
                      features.corner_vertices.max(initial=-1))) + 1
    source = np.full(mesh.n_vertices, -1, dtype=np.int64)
    source[: vertex_source.size] = vertex_source
    a, b = source[mesh.origin], source[mesh.dest]
    keys = np.where((a >= 0) & (b >= 0), np.minimum(a, b) * n_input + np.maximum(a, b), -1)
    tagged = np.minimum(*features.crease_edges.T) * n_input + np.maximum(*features.crease_edges.T)
    sharp = np.minimum(features.crease_sharpness, INFINITELY_SHARP)
    order = np.argsort(tagged)  # an edge tagged twice keeps its largest sharpness
    unique_keys, first = np.unique(tagged[order], return_index=True)
    largest = np.maximum.reduceat(sharp[order], first) if first.size else np.zeros(0)
    slot = np.clip(np.searchsorted(unique_keys, keys), 0, max(unique_keys.size - 1, 0))
    found = (keys >= 0) & (unique_keys.size > 0) & (unique_keys[slot] == keys) if unique_keys.size else np.zeros(keys.size, bool)
    halfedge = np.where(found, largest[slot] if largest.size else 0.0, 0.0)
    return CoarseSharpness(halfedge, _corner_sharpness(mesh, source, halfedge, features, n_input))


def _corner_sharpness(mesh, source: np.ndarray, halfedge: np.ndarray, features: SharpFeatures, n_input: int) -> np.ndarray:
    """(V,) float: tagged corners, and vertices on three or more sharp edges (the mean of theirs)."""
    # each undirected edge once: the half-edge with a twin only from its smaller index, boundary ones always
    once = (mesh.twin < 0) | (np.arange(mesh.n_halfedges) < mesh.twin)
    sharp = once & (halfedge > 0)
    ends = np.concatenate([mesh.origin[sharp], mesh.dest[sharp]])
    values = np.tile(halfedge[sharp], 2)
    count = np.bincount(ends, minlength=mesh.n_vertices)
    total = np.bincount(ends, weights=values, minlength=mesh.n_vertices)
    vertex = np.where(count >= 3, total / np.maximum(count, 1), 0.0)
    tagged = np.zeros(n_input)  # per input vertex
    np.maximum.at(tagged, features.corner_vertices, np.minimum(features.corner_sharpness, INFINITELY_SHARP))
    real = source >= 0
    vertex[real] = np.maximum(vertex[real], tagged[source[real]])
    return vertex


__all__ = ["SharpFeatures", "CoarseSharpness", "coarse_sharpness", "INFINITELY_SHARP"]
