"""Whether a control mesh covers its scan: nothing dropped, nothing spanned, checked on the geometry (issue 39).

Counts can agree by accident: a remesh that drops a horn and closes a hole elsewhere has the scan's components,
Euler characteristic and rims. So before the fit the control mesh is held against the scan itself:

- **Coverage.** Every scan vertex lies within about one local control edge of the control mesh (its polygons
  cut into triangle fans). The local control edge at a scan vertex is the longest edge of the ``NEAR_FACES`` control
  faces whose centroids are nearest the closest point. A vertex farther than ``FAR_EDGES`` (one edge) is *far*:
  the decimation redoes its region finer (``decimated_quads``); one farther than ``LOST_EDGES`` is *lost*: the
  control mesh has nothing there. A remesh that follows the scan cuts corners by less: measured on the 22 scans of
  ``../shared/scans`` at the defaults, Instant Meshes' remeshes that keep the counts reach 0.44-1.24 edges
  (mountain's rim 1.24, goathead 1.23, koala 1.19), the decimated ones 0.24-0.89; a dropped part leaves its
  vertices its own size away: 3.1-41 edges where Instant Meshes dropped pieces (scorpion 3.1, human_man 3.4,
  penguin 6.8, lionstatue 9.9, sword 41).
- **Rims.** Every rim (boundary loop) of the scan is matched, one to one, by a rim of the control mesh of about its
  length and position: lengths within a factor ``RIM_LENGTH`` (plus two local edges), centroids within a quarter of
  the scan rim's length plus two local edges. A scan rim no control rim matches was spanned (a hole filled over) or
  lost; a control rim no scan rim matches is a hole the scan does not have.

``uncovered_area``: the scan's area left uncovered, the triangles with a lost corner (what a candidate that loses
something loses; ``control_mesh`` keeps the one that loses least when none keeps everything).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Coverage", "mesh_coverage", "rim_loops", "FAR_EDGES", "LOST_EDGES"]

FAR_EDGES = 1.0  # a scan vertex farther than this many local control edges from the control mesh is far
LOST_EDGES = 1.5  # and farther than this, lost (module docstring)
NEAR_FACES = 4  # the control faces whose longest edge is the local control edge
RIM_LENGTH = 2.0  # a control rim matches a scan rim when their lengths are within this factor (plus two local edges)


@dataclass
class Coverage:
    """How a control mesh covers its scan (module docstring).

    far : (m,) bool, the scan vertices farther than ``FAR_EDGES`` local control edges from the control mesh
    ratio : (m,) float, each scan vertex's distance over its local control edge
    uncovered_area : float, the area of the scan triangles with a lost corner (farther than ``LOST_EDGES``)
    lost_rims, extra_rims : list of (centre (3,), length) of the scan rims no control rim matches, and of the
        control rims no scan rim matches
    """

    far: np.ndarray
    ratio: np.ndarray
    uncovered_area: float
    lost_rims: list = field(default_factory=list)
    extra_rims: list = field(default_factory=list)

    @property
    def lost(self) -> np.ndarray:
        """(m,) bool: the scan vertices farther than ``LOST_EDGES`` local control edges: nothing there."""
        return self.ratio > LOST_EDGES

    @property
    def ok(self) -> bool:
        """Nothing lost, nothing spanned: no lost vertex, every rim matched."""
        return not self.lost.any() and not self.lost_rims and not self.extra_rims

    def as_dict(self) -> dict:
        """The report's ``coverage``: the largest distance in local control edges, the far and lost vertices, the
        area left uncovered and the rims unmatched."""
        return {"max_edges": float(self.ratio.max(initial=0.0)), "far_vertices": int(self.far.sum()),
                "lost_vertices": int(self.lost.sum()), "uncovered_area": self.uncovered_area,
                "lost_rims": len(self.lost_rims), "extra_rims": len(self.extra_rims)}

    def phrases(self, scan_points: np.ndarray, shown: int = 3) -> list:
        """What the control mesh lost or spanned, one phrase each, with coordinates (few)."""
        out = []
        lost = self.lost
        if lost.any():
            where = scan_points[lost]
            worst = scan_points[int(np.argmax(self.ratio))]
            out.append(f"{int(lost.sum())} scan vertices farther than {LOST_EDGES:g} local control edges from it "
                       f"(an area of {self.uncovered_area:.3g}; the farthest, {self.ratio.max():.2g} edges, at "
                       f"{_point(worst)}; the box from {_point(where.min(axis=0))} to {_point(where.max(axis=0))})")
        for words, rims in (("scan rims spanned or lost", self.lost_rims), ("rims the scan does not have", self.extra_rims)):
            if rims:
                listed = "; ".join(f"length {length:.3g} around {_point(centre)}" for centre, length in rims[:shown])
                more = f"; and {len(rims) - shown} more" if len(rims) > shown else ""
                out.append(f"{len(rims)} {words} ({listed}{more})")
        return out


def _point(p) -> str:
    return "(" + ", ".join(f"{c:.4g}" for c in p) + ")"


def _fans(face_sizes: np.ndarray, face_vertices: np.ndarray) -> np.ndarray:
    """(sum(n - 2), 3) int: every polygon cut into the triangle fan of its first corner."""
    sizes = np.asarray(face_sizes, dtype=np.int64)
    fans = np.maximum(sizes - 2, 0)
    first = np.repeat(np.cumsum(sizes) - sizes, fans)
    j = 1 + np.arange(first.size) - np.repeat(np.cumsum(fans) - fans, fans)
    return np.asarray(face_vertices, dtype=np.int64)[np.stack([first, first + j, first + j + 1], axis=1)]


def _face_scales(face_sizes, face_vertices, points):
    """(F, 3) centroids and (F,) longest edges of a polygon mesh."""
    from .cleanup import edge_keys

    sizes = np.asarray(face_sizes, dtype=np.int64)
    a, b, _, face = edge_keys(sizes, face_vertices, points.shape[0])
    longest = np.zeros(sizes.size)
    np.maximum.at(longest, face, np.linalg.norm(points[a] - points[b], axis=1))
    centre = np.zeros((sizes.size, 3))
    np.add.at(centre, face, points[a])
    return centre / sizes[:, None], longest


def rim_loops(face_sizes, face_vertices, points):
    """The boundary loops of a polygon mesh: (k, 3) length-weighted centres and (k,) lengths (edges in one face,
    grouped by their connected components)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from .cleanup import edge_keys

    n = points.shape[0]
    a, b, key, _ = edge_keys(np.asarray(face_sizes), face_vertices, n)
    unique, first, counts = np.unique(key, return_index=True, return_counts=True)
    rim = first[counts == 1]
    if rim.size == 0:
        return np.zeros((0, 3)), np.zeros(0)
    a, b = a[rim], b[rim]
    graph = coo_matrix((np.ones(rim.size), (a, b)), shape=(n, n))
    label = connected_components(graph, directed=False)[1][a]
    loops, label = np.unique(label, return_inverse=True)
    length = np.linalg.norm(points[a] - points[b], axis=1)
    total = np.bincount(label, weights=length, minlength=loops.size)
    middle = 0.5 * (points[a] + points[b]) * length[:, None]
    centre = np.stack([np.bincount(label, weights=middle[:, k], minlength=loops.size) for k in range(3)], axis=1)
    return centre / np.maximum(total, 1e-300)[:, None], total


def _match_rims(scan_rims, control_rims, edge_at):
    """(lost, extra): the scan rims and control rims left unmatched by a greedy one-to-one matching, nearest
    first (module docstring); ``edge_at(points)`` gives the local control edge at points."""
    (scan_centre, scan_length), (control_centre, control_length) = scan_rims, control_rims
    if scan_length.size == 0 or control_length.size == 0:
        return (list(zip(scan_centre, scan_length)), list(zip(control_centre, control_length)))
    edge = edge_at(scan_centre)
    gap = np.linalg.norm(scan_centre[:, None] - control_centre[None], axis=2)
    fits = ((gap <= 0.25 * scan_length[:, None] + 2 * edge[:, None])
            & (control_length[None] <= RIM_LENGTH * scan_length[:, None] + 2 * edge[:, None])
            & (control_length[None] >= scan_length[:, None] / RIM_LENGTH - 2 * edge[:, None]))
    pairs = np.argwhere(fits)
    pairs = pairs[np.argsort(gap[fits], kind="stable")]
    used_scan = np.zeros(scan_length.size, dtype=bool)
    used_control = np.zeros(control_length.size, dtype=bool)
    for i, j in pairs:  # the few rims
        if not used_scan[i] and not used_control[j]:
            used_scan[i] = used_control[j] = True
    return ([(scan_centre[i], scan_length[i]) for i in np.flatnonzero(~used_scan)],
            [(control_centre[j], control_length[j]) for j in np.flatnonzero(~used_control)])


def mesh_coverage(scan_points, scan_triangles, face_sizes, face_vertices, points, rims: bool = True) -> Coverage:
    """How the control mesh (``face_sizes``, ``face_vertices``, ``points`` (V, 3)) covers the scan (``scan_points``
    (m, 3), ``scan_triangles`` (t, 3)): the module docstring's two checks (the rims' with ``rims``)."""
    from scipy.spatial import cKDTree

    from ..deviation import closest_on_triangles

    scan_points = np.asarray(scan_points, dtype=np.float64)
    points = np.asarray(points, dtype=np.float64)
    distance, closest = closest_on_triangles(scan_points, points, _fans(face_sizes, face_vertices))
    centre, longest = _face_scales(face_sizes, face_vertices, points)
    tree = cKDTree(centre)
    k = min(NEAR_FACES, centre.shape[0])

    def edge_at(query):
        nearest = tree.query(query, k=k)[1].reshape(len(query), -1)
        return longest[nearest].max(axis=1)

    ratio = distance / np.maximum(edge_at(closest), 1e-300)
    far = ratio > FAR_EDGES
    corners = scan_points[scan_triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    uncovered = float(area[(ratio > LOST_EDGES)[scan_triangles].any(axis=1)].sum())
    if not rims:
        return Coverage(far, ratio, uncovered)
    lost, extra = _match_rims(rim_loops(np.full(len(scan_triangles), 3), np.ravel(scan_triangles), scan_points),
                              rim_loops(face_sizes, face_vertices, points), edge_at)
    return Coverage(far, ratio, uncovered, lost, extra)
