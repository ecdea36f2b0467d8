"""Two-sided deviation between a fitted surface and its scan.

Scan to surface: the distance of every scan vertex to its footpoint on the exact patches
(``footpoints``). Surface to scan: the distance of every tessellation vertex of the surface to the
closest point of the scan's triangles, exact: a k-d tree of the triangles' centroids, by classes of
triangle size, finds every triangle that can be nearer than the nearest scan vertex
(``closest_on_triangles``), and the point-triangle distance is computed in closed form
(``point_triangle_closest``, the Voronoi regions of a triangle's vertices, edges and face).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..evaluation.tessellate import tessellate
from ..parallel import thread_count
from .footpoints import patch_set

__all__ = ["Deviation", "distance_stats", "two_sided_deviation", "surface_to_scan", "beyond_boundary",
           "signed_scan_to_surface", "closest_on_triangles",
           "point_triangle_closest", "bounding_diagonal"]


def bounding_diagonal(points: np.ndarray) -> float:
    """The length of the bounding box's diagonal of (n, 3) points."""
    points = np.asarray(points, dtype=np.float64)
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def distance_stats(distance: np.ndarray, diagonal: float) -> dict:
    """"max", "rms", "p99" of (n,) distances and the same over ``diagonal`` ("relative_max", ...)."""
    distance = np.asarray(distance, dtype=np.float64)
    stats = {"max": float(distance.max()), "rms": float(np.sqrt(np.mean(distance * distance))),
             "p99": float(np.percentile(distance, 99))}
    for key in ("max", "rms", "p99"):
        stats[f"relative_{key}"] = stats[key] / diagonal if diagonal > 0 else 0.0
    return stats


@dataclass(frozen=True)
class Deviation:
    """Both directions of the distance between a surface and a scan.

    scan_to_surface : (m,) float, per scan vertex (for the deviation PLY and picture)
    surface_to_scan : (n,) float, per tessellation vertex of the surface
    diagonal : float, the scan's bounding-box diagonal
    scan_stats, surface_stats : dict, ``distance_stats`` of each; the surface's only where the scan has data
        (its vertices over the scan's holes left out: ``over_holes``)
    over_holes : (n,) bool, the surface's vertices whose nearest scan point is on the scan's boundary and
        beyond it (an open scan: the surface past its rims or across its holes); all False for a closed scan
    """

    scan_to_surface: np.ndarray
    surface_to_scan: np.ndarray
    diagonal: float
    scan_stats: dict
    surface_stats: dict
    over_holes: np.ndarray | None = None

    @property
    def over_holes_fraction(self) -> float:
        """The share of the surface's (tessellation) vertices over the scan's holes or past its rims."""
        return float(np.mean(self.over_holes)) if self.over_holes is not None and self.over_holes.size else 0.0


def two_sided_deviation(surface, scan_points, scan_triangles, footpoints, resolution: int = 4) -> Deviation:
    """Deviation of ``surface`` from a scan whose vertices project to ``footpoints`` (``FitResult.footpoints``).

    Parameters
    ----------
    surface : Surface; scan_points : (m, 3) float; scan_triangles : (t, 3) int
    footpoints : Footpoints of the scan's vertices on ``surface``
    resolution : int >= 2, tessellation samples per patch side of the surface-to-scan direction
    """
    diagonal = bounding_diagonal(scan_points)
    mesh = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, resolution)
    back, closest = closest_on_triangles(mesh.points[:, :3], scan_points, scan_triangles)
    holes = beyond_boundary(closest, back, scan_points, scan_triangles, diagonal)
    kept = back[~holes] if (~holes).any() else back
    return Deviation(footpoints.distance, back, diagonal, distance_stats(footpoints.distance, diagonal),
                     distance_stats(kept, diagonal), holes)


def beyond_boundary(closest, distance, scan_points, scan_triangles, diagonal: float) -> np.ndarray:
    """(n,) bool: the queries whose ``closest`` point (n, 3) on the scan lies on its boundary (an edge of one
    triangle) while they are off it by more than 1e-6 of the ``diagonal``: past a rim or over a hole, where the
    scan has no data to measure against. All False for a closed scan."""
    triangles = np.asarray(scan_triangles, dtype=np.int64)
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    rim = unique[counts == 1]
    n = closest.shape[0]
    if rim.size == 0 or n == 0:
        return np.zeros(n, dtype=bool)
    a, b = scan_points[rim[:, 0]], scan_points[rim[:, 1]]
    tree = cKDTree(0.5 * (a + b))
    reach = 0.5 * float(np.linalg.norm(b - a, axis=1).max())
    candidates = np.minimum(8, rim.shape[0])
    near = np.full(n, np.inf)
    _, index = tree.query(closest, k=candidates, workers=thread_count())
    index = index.reshape(n, -1)
    for k in range(index.shape[1]):  # a few nearest rim edges each (k <= 8), vectorized over the queries
        e = index[:, k]
        ab = b[e] - a[e]
        t = np.clip(np.einsum("ij,ij->i", closest - a[e], ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
        near = np.minimum(near, np.linalg.norm(closest - (a[e] + t[:, None] * ab), axis=1))
    on_rim = near <= 1e-9 * diagonal + 1e-12 * reach
    return on_rim & (np.asarray(distance) > 1e-6 * diagonal)


def signed_scan_to_surface(surface, scan_points, footpoints) -> np.ndarray:
    """(m,) float: the scan-to-surface distances signed by the side of the surface, positive where the scan
    vertex lies on the side the surface normal x_u x x_v points to (outside for a control mesh
    numbered counter-clockwise from outside): the usual colouring of a deviation map."""
    patches = patch_set(surface.biquadratic, surface.bicubic, 1)
    d = patches.derivatives(footpoints.patch, footpoints.u, footpoints.v, ((1, 0), (0, 1)))
    side = np.einsum("ij,ij->i", np.asarray(scan_points, dtype=np.float64) - footpoints.points,
                     np.cross(d[(1, 0)], d[(0, 1)]))
    return np.where(side < 0, -footpoints.distance, footpoints.distance)


def surface_to_scan(surface, scan_points, scan_triangles, resolution: int = 4) -> np.ndarray:
    """(n,) float: distance of each vertex of the surface's welded tessellation to the scan's triangles."""
    mesh = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, resolution)
    distance, _ = closest_on_triangles(mesh.points[:, :3], scan_points, scan_triangles)
    return distance


def closest_on_triangles(queries, points, triangles, chunk: int = 1 << 15):
    """Exact closest points of ``queries`` on a triangle mesh.

    Parameters
    ----------
    queries : (n, 3) float; points : (V, 3) float; triangles : (t, 3) int

    Returns
    -------
    distance : (n,) float; closest : (n, 3) float

    A triangle whose centroid is farther than d0 + r from a query (d0: its distance to the nearest
    used vertex, r: the triangle's largest centroid-to-corner distance) cannot hold a point nearer
    than that vertex; triangles are grouped by r in powers of two, so one large triangle does not
    widen the search of all.
    """
    queries = np.asarray(queries, dtype=np.float64)
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    corners = points[triangles]  # (t, 3, 3)
    centroid = corners.mean(axis=1)
    radius = np.sqrt(((corners - centroid[:, None]) ** 2).sum(axis=2)).max(axis=1)
    used = np.unique(triangles)
    d0, _ = cKDTree(points[used]).query(queries, workers=thread_count())
    best = np.full(queries.shape[0], np.inf)
    closest = np.zeros_like(queries)
    level = np.floor(np.log2(np.maximum(radius, 1e-300)))
    for value in np.unique(level):
        members = np.nonzero(level == value)[0]
        tree, reach = cKDTree(centroid[members]), float(radius[members].max())
        for a in range(0, queries.shape[0], chunk):
            z = min(a + chunk, queries.shape[0])
            hits = tree.query_ball_point(queries[a:z], d0[a:z] * (1 + 1e-9) + reach)
            counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=z - a)
            if counts.sum() == 0:
                continue
            query = np.repeat(np.arange(a, z), counts)
            tri = members[np.concatenate([np.asarray(h, dtype=np.int64) for h in hits])]
            c = point_triangle_closest(queries[query], corners[tri])
            d = np.sqrt(((c - queries[query]) ** 2).sum(axis=1))
            order = np.lexsort((d, query))
            first = np.ones(order.size, dtype=bool)
            first[1:] = query[order][1:] != query[order][:-1]
            q, pick = query[order[first]], order[first]
            better = d[pick] < best[q]
            best[q[better]] = d[pick[better]]
            closest[q[better]] = c[pick[better]]
    return best, closest


def point_triangle_closest(p: np.ndarray, triangle: np.ndarray) -> np.ndarray:
    """(n, 3) float: the closest point to p[k] of the triangle triangle[k] ((n, 3) and (n, 3, 3)).

    Barycentric regions after Ericson, "Real-Time Collision Detection" 5.1.5: a vertex, an edge or the face.
    """
    a, b, c = triangle[:, 0], triangle[:, 1], triangle[:, 2]
    dot = lambda x, y: np.einsum("ij,ij->i", x, y)  # noqa: E731
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = p - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = p - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        face = a + v[:, None] * ab + w[:, None] * ac
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    out = face
    regions = [  # Ericson's tests from the last to the first: a later one overrides
        (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), b + t_bc[:, None] * (c - b),  # edge bc
        (vb <= 0) & (d2 >= 0) & (d6 <= 0), a + t_ac[:, None] * ac,  # edge ac
        (d6 >= 0) & (d5 <= d6), c,  # vertex c
        (vc <= 0) & (d1 >= 0) & (d3 <= 0), a + t_ab[:, None] * ab,  # edge ab
        (d3 >= 0) & (d4 <= d3), b,  # vertex b
        (d1 <= 0) & (d2 <= 0), a,  # vertex a
    ]
    for k in range(0, len(regions), 2):
        out = np.where(regions[k][:, None], regions[k + 1], out)
    bad = ~np.isfinite(out).all(axis=1)  # degenerate triangle: its nearest corner
    if bad.any():
        tri = triangle[bad]
        k = np.argmin(((tri - p[bad][:, None]) ** 2).sum(axis=2), axis=1)
        out[bad] = tri[np.arange(k.size), k]
    return out
