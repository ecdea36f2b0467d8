"""Ray casting: which patch, and where on it, each pixel's ray meets the surface.

Each patch is sampled on its own n x n grid (no welding: rendering does not need
it; patches that share an edge parametrize it identically, so the grids meet).
A ray per pixel hits that triangle mesh (Embree through ``embreex`` when
installed); the hit triangle gives the patch and, by barycentric interpolation
of its corners' parameters, an approximate (u, v), which Newton steps on
``x(u, v) = o + t d`` move onto the exact patch. A ray whose solution leaves
its patch continues on the patch across that side (``PatchAdjacency``: the
stored one, or one matched from the geometry).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..evaluation.adjacency import PatchAdjacency
from ..evaluation.bezier import bernstein_basis, evaluate_grid
from ..evaluation.curvature import PatchSampler
from ..evaluation.rational import dehomogenize, homogeneous
from ..evaluation.tessellate import grid_triangles
from .camera import Camera

RAY_CHUNK = 1 << 16  # rays cast at once
EVAL_CHUNK = 1 << 17  # samples evaluated at once


def report(progress, label: str, advance: int, total: int) -> None:
    """Call ``progress(label, advance, total)`` unless it is None."""
    if progress is not None:
        progress(label, advance, total)


# -- the mesh the rays hit first ------------------------------------------------------------


@dataclass(frozen=True)
class PatchGridMesh:
    """Every patch on its own n x n grid, patches in global order.

    points : (P n^2, 3) float; triangles : (P L, 3) int with L = 2 (n-1)^2 triangles per
    patch, so triangle t lies on patch t // L; corner_uv : (L, 3, 2) (u, v) of the
    corners of local triangle t % L.
    """

    points: np.ndarray
    triangles: np.ndarray
    corner_uv: np.ndarray
    resolution: int

    @property
    def per_patch(self) -> int:
        return self.corner_uv.shape[0]


def default_resolution(n_patches: int, target_triangles: int = 600_000, largest: int = 8) -> int:
    """Grid size per patch keeping the mesh under about ``target_triangles`` triangles
    (at least 2: two triangles per patch). The mesh only finds the patch and a start
    (u, v) for the Newton steps, so a coarse one suffices; building the ray-tracing
    structure costs about 2 s per million triangles."""
    if n_patches <= 0:
        return 2
    n = int(np.floor(np.sqrt(target_triangles / (2.0 * n_patches)))) + 1
    return int(np.clip(n, 2, largest))


def patch_grid_mesh(groups, resolution: int, weights=None) -> PatchGridMesh:
    """Sample every patch on an n x n grid of parameters.

    Parameters
    ----------
    groups : list of (p_k, du+1, dv+1, d) float, x, y, z first
    resolution : int >= 2, samples per patch side
    weights : None or a list parallel to ``groups`` of (p_k, du+1, dv+1) float (rational, A2a)

    Returns
    -------
    PatchGridMesh
    """
    n = int(resolution)
    t = np.linspace(0.0, 1.0, n)
    blocks = []
    for k, group in enumerate(groups):
        if len(group) == 0:
            continue
        bu, bv = bernstein_basis(group.shape[1] - 1, t), bernstein_basis(group.shape[2] - 1, t)
        xyz = group[..., :3]
        if weights is None:
            blocks.append(evaluate_grid(xyz, bu, bv).reshape(-1, 3))
        else:
            blocks.append(dehomogenize(evaluate_grid(homogeneous(xyz, weights[k]), bu, bv))[0].reshape(-1, 3))
    points = np.concatenate(blocks) if blocks else np.zeros((0, 3))
    local = grid_triangles(n)
    n_patches = points.shape[0] // (n * n)
    triangles = (local[None, :, :] + (np.arange(n_patches) * n * n)[:, None, None]).reshape(-1, 3)
    i, j = np.divmod(local, n)
    corner_uv = np.stack([t[i], t[j]], axis=-1)
    return PatchGridMesh(points, triangles, corner_uv, n)


# -- rays -------------------------------------------------------------------------------


class RayCaster:
    """Closest hits of rays on a triangle mesh: Embree (``embreex``) when available,
    else trimesh's pure-numpy intersector (much slower; a warning says so)."""

    def __init__(self, points: np.ndarray, triangles: np.ndarray):
        self.points = np.asarray(points, dtype=np.float64)
        self.triangles = np.asarray(triangles)
        try:
            from embreex import rtcore_scene
            from embreex.mesh_construction import TriangleMesh
        except ImportError:
            self.engine = "trimesh"
            warnings.warn("embreex is not installed: ray casting falls back to trimesh's slow numpy "
                          "intersector (pip install embreex)", RuntimeWarning, stacklevel=2)
            import trimesh
            from trimesh.ray.ray_triangle import RayMeshIntersector

            mesh = trimesh.Trimesh(self.points, self.triangles, process=False, validate=False)
            self._intersector = RayMeshIntersector(mesh)
            return
        self.engine = "embree"
        # Embree works in float32: shift and scale to the unit box for precision.
        lo = self.points.min(axis=0) if self.points.size else np.zeros(3)
        extent = float(np.ptp(self.points, axis=0).max()) if self.points.size else 1.0
        self._origin, self._scale = lo, 1.0 / extent if extent > 0 else 1.0
        self._scene = rtcore_scene.EmbreeScene(robust=True)
        TriangleMesh(scene=self._scene, vertices=((self.points - lo) * self._scale).astype(np.float32),
                     indices=self.triangles.astype(np.int32))
        # Embree builds its hierarchy at the first query: do it now, so it is timed here.
        self._scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))

    def cast(self, origins: np.ndarray, directions: np.ndarray):
        """Closest hit of each ray.

        Parameters
        ----------
        origins, directions : (m, 3) float, directions of unit length

        Returns
        -------
        triangle : (m,) int, -1 for a miss
        b1, b2 : (m,) float, barycentric weights of corners 1 and 2 (corner 0 gets the rest)
        t : (m,) float, distance along the ray (inf for a miss)
        """
        m = origins.shape[0]
        if self.engine == "embree":
            o = ((origins - self._origin) * self._scale).astype(np.float32)
            res = self._scene.run(o, directions.astype(np.float32), output=1)
            tri = res["primID"].astype(np.int64)
            hit = (res["geomID"].astype(np.int64) == 0) & (tri >= 0)
            tri = np.where(hit, tri, -1)
            t = np.where(hit, res["tfar"].astype(np.float64) / self._scale, np.inf)
            return tri, res["u"].astype(np.float64), res["v"].astype(np.float64), t
        from trimesh.triangles import points_to_barycentric

        tri = np.full(m, -1, dtype=np.int64)
        b1, b2, t = np.zeros(m), np.zeros(m), np.full(m, np.inf)
        index_tri, index_ray, locations = self._intersector.intersects_id(
            origins, directions, multiple_hits=False, return_locations=True)
        if len(index_ray):
            bary = points_to_barycentric(self.points[self.triangles[index_tri]], locations)
            tri[index_ray] = index_tri
            b1[index_ray], b2[index_ray] = bary[:, 1], bary[:, 2]
            t[index_ray] = np.einsum("md,md->m", locations - origins[index_ray], directions[index_ray])
        return tri, b1, b2, t


@dataclass(frozen=True)
class RayHits:
    """The pixels whose rays hit the ray-casting mesh, and where.

    pixel : (m,) int, raveled pixel index (row-major)
    patch : (m,) int, global patch of the hit triangle
    u, v : (m,) float in [0, 1], the hit's parameters on the mesh (interpolated, not exact)
    origins, directions : (m, 3) float, the rays
    """

    pixel: np.ndarray
    patch: np.ndarray
    u: np.ndarray
    v: np.ndarray
    origins: np.ndarray
    directions: np.ndarray


def cast_camera_rays(caster: RayCaster, mesh: PatchGridMesh, camera: Camera, progress=None) -> RayHits:
    """Cast a ray per pixel of ``camera`` at the mesh, a band of rows at a time."""
    h, w = camera.height, camera.width
    parts = {name: [] for name in ("pixel", "triangle", "b1", "b2", "origins", "directions")}
    rows_per_chunk = max(1, RAY_CHUNK // w)
    for r0 in range(0, h, rows_per_chunk):
        origins, directions = camera.rays(slice(r0, min(h, r0 + rows_per_chunk)))
        triangle, b1, b2, _ = caster.cast(origins, directions)
        hit = np.flatnonzero(triangle >= 0)
        for name, values in zip(parts, (r0 * w + hit, triangle, b1, b2, origins, directions)):
            parts[name].append(values if name == "pixel" else values[hit])
        report(progress, "casting rays", origins.shape[0], h * w)
    pixel, triangle, b1, b2, origins, directions = (np.concatenate(a) for a in parts.values())
    corners = mesh.corner_uv[triangle % mesh.per_patch]  # (m, 3, 2)
    uv = (1.0 - b1 - b2)[:, None] * corners[:, 0] + b1[:, None] * corners[:, 1] + b2[:, None] * corners[:, 2]
    return RayHits(pixel, triangle // mesh.per_patch, np.clip(uv[:, 0], 0, 1), np.clip(uv[:, 1], 0, 1), origins,
                   directions)


# -- Newton steps onto the exact patch ------------------------------------------------------


def _solve3(a, b, c, r):
    """Cramer's rule for [a b c] s = r, row-wise; zero where the matrix is singular."""
    bc = np.cross(b, c)
    det = np.einsum("md,md->m", a, bc)
    scale = np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1) * np.linalg.norm(c, axis=1)
    ok = np.abs(det) > 1e-12 * scale
    det = np.where(ok, det, 1.0)
    s1 = np.einsum("md,md->m", r, bc) / det
    s2 = np.einsum("md,md->m", a, np.cross(r, c)) / det
    s3 = np.einsum("md,md->m", a, np.cross(b, r)) / det
    return np.where(ok, s1, 0.0), np.where(ok, s2, 0.0), np.where(ok, s3, 0.0)


def _ray_distance(x, o, d):
    rel = x - o
    return np.linalg.norm(rel - np.einsum("md,md->m", rel, d)[:, None] * d, axis=1)


def ray_distance(x: np.ndarray, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(m,) distance of points x (m, 3) from the rays (origins, unit directions: (m, 3))."""
    rel = x - origins
    return np.linalg.norm(rel - np.einsum("md,md->m", rel, directions)[:, None] * directions, axis=1)


def newton_on_rays(sampler: PatchSampler, group: int, index, u, v, rays, steps: int = 8, tolerance: float = 1e-9):
    """Newton steps on ``x(u, v) = o + t d``, one patch per ray, until the parameter step
    is below ``tolerance`` (at most ``steps`` steps).

    The patch polynomials are used a little beyond [0, 1] (clamped to [-0.5, 1.5]),
    so a ray that meets the surface on a neighbouring patch ends outside the unit
    square, on the side where that neighbour is.

    Parameters
    ----------
    sampler : PatchSampler of the surface; group : int, the group of every ray's patch
    index : (m,) int, the patch of each ray within the group
    u, v : (m,) float, start values; rays : (origins (m, 3), directions (m, 3))

    Returns
    -------
    u, v : (m,) float after the steps
    start_distance : (m,) float, distance of the start point from its ray
    """
    origins, directions = rays
    u, v = np.array(u, dtype=np.float64), np.array(v, dtype=np.float64)
    x, xu, xv = sampler.tangents(group, index, u, v)
    start = ray_distance(x, origins, directions)
    t = np.einsum("md,md->m", x - origins, directions)
    active = np.arange(u.size)
    for k in range(steps):
        o, d = origins[active], directions[active]
        r = o + t[:, None] * d - x
        du, dv, dt = _solve3(xu, xv, -d, r)
        u[active] = np.clip(u[active] + du, -0.5, 1.5)
        v[active] = np.clip(v[active] + dv, -0.5, 1.5)
        going = np.abs(du) + np.abs(dv) > tolerance
        active, t = active[going], (t + dt)[going]
        if active.size == 0 or k == steps - 1:
            break
        x, xu, xv = sampler.tangents(group, index[active], u[active], v[active])
    return u, v, start


# The lines u = 0, u = 1, v = 0, v = 1 beyond which a parameter leaves the unit square, as
# sides (adjacency.SIDE_CORNERS): 3, 1, 0, 2.
_SIDE_BEYOND = np.array([3, 1, 0, 2])


def _hop(adjacency: PatchAdjacency, across: np.ndarray, patch, u, v):
    """Move (patch, u, v) that lie outside the unit square to the patch across the side they
    crossed, at the matching parameters; those with no neighbour are clamped instead.

    adjacency : PatchAdjacency of the surface; across : its ``neighbours()``, (P, 4, 2)

    Returns
    -------
    patch, u, v : (m,) updated; moved : (m,) bool
    """
    excess = np.stack([-u, u - 1, -v, v - 1], axis=1)
    beyond = np.argmax(excess, axis=1)  # the line crossed farthest (ties: the first)
    side = _SIDE_BEYOND[beyond]
    along = np.where(side % 2 == 1, v, u)  # sides 1 and 3 (u fixed) run along v
    depth = np.clip(excess[np.arange(side.size), beyond], 0.0, 0.5)
    q, side_q = across[patch, side, 0], across[patch, side, 1]
    moved = q >= 0
    # the neighbour runs the other way along the shared edge when exactly one of the two sides is reversed
    flipped = adjacency.reversed[patch, side] != adjacency.reversed[np.maximum(q, 0), np.maximum(side_q, 0)]
    t = np.clip(np.where(flipped, 1.0 - along, along), 0.0, 1.0)
    nu = np.select([side_q == 3, side_q == 1], [depth, 1.0 - depth], t)
    nv = np.select([side_q == 0, side_q == 2], [depth, 1.0 - depth], t)
    return (np.where(moved, q, patch), np.where(moved, nu, np.clip(u, 0, 1)),
            np.where(moved, nv, np.clip(v, 0, 1)), moved)


def locate_on_rays(sampler: PatchSampler, adjacency, hits: RayHits, steps: int = 8, hops: int = 2, progress=None):
    """Exact (patch, u, v) where each ray meets the surface, from the mesh hits.

    Newton steps on the start patch; a ray whose solution leaves the patch moves to the
    patch across that side and continues there, at most ``hops`` times. Callers should
    keep the start values where this did not bring the point closer to the ray (a ray
    that grazes the silhouette may miss the exact surface).

    Parameters
    ----------
    sampler : PatchSampler of the surface
    adjacency : callable () -> PatchAdjacency of the surface, called when a ray first leaves its patch
    hits : RayHits
    steps : int, Newton steps per patch visited; hops : int
    progress : callable(label, advance, total) or None

    Returns
    -------
    patch : (m,) int; u, v : (m,) float in [0, 1]
    start_distance : (m,) float, distance of the start point from its ray
    """
    patch = np.array(hits.patch, dtype=np.int64)
    u, v = np.array(hits.u, dtype=np.float64), np.array(hits.v, dtype=np.float64)
    start_distance = np.zeros(patch.size)
    todo = np.arange(patch.size)
    welding = across = None
    for round_ in range(hops + 1):
        for g, which in sampler.runs(patch[todo], EVAL_CHUNK):
            idx = todo[which]
            u[idx], v[idx], d0 = newton_on_rays(sampler, g, patch[idx] - sampler.offsets[g], u[idx], v[idx],
                                                (hits.origins[idx], hits.directions[idx]), steps)
            if round_ == 0:
                start_distance[idx] = d0
                report(progress, "finding the exact hits", idx.size, patch.size)
        eps = 1e-12
        out = (u[todo] < -eps) | (u[todo] > 1 + eps) | (v[todo] < -eps) | (v[todo] > 1 + eps)
        todo = todo[out]
        if todo.size == 0 or round_ == hops:
            break
        if welding is None:
            welding = adjacency()
            across = welding.neighbours()
        patch[todo], u[todo], v[todo], moved = _hop(welding, across, patch[todo], u[todo], v[todo])
        todo = todo[moved]
    return patch, np.clip(u, 0.0, 1.0), np.clip(v, 0.0, 1.0), start_distance
