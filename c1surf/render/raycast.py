"""Images of a patch surface with exact per-pixel curvature.

Each patch is sampled on its own n x n grid (no welding: rendering does not need
it; patches that share an edge parametrize it identically, so the grids meet).
A ray per pixel hits that triangle mesh (Embree through ``embreex`` when
installed); the hit triangle gives the patch and, by barycentric interpolation
of its corners' parameters, an approximate (u, v), which Newton steps on
``x(u, v) = o + t d`` move onto the exact patch. Curvature, normal and position
are then evaluated at that exact (patch, u, v).

Images are dicts of (H, W) float arrays named like the EXR channels:
``kmax K H k1 k2 Z N.X N.Y N.Z P.X P.Y P.Z patch u v`` (``patch`` = -1 and the
others 0 on the background, except ``Z`` = +inf there).
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..evaluation.bezier import bernstein_basis
from .camera import Camera
from ..evaluation.curvature import curvature_from_derivatives, patch_columns, patch_derivatives, patch_tangents

CURVATURE_NAMES = ("kmax", "K", "H", "k1", "k2")
SIGNED = {"kmax": False, "K": True, "H": True, "k1": True, "k2": True}
GEOMETRY_NAMES = ("Z", "N.X", "N.Y", "N.Z", "P.X", "P.Y", "P.Z", "patch", "u", "v")
RAY_CHUNK = 1 << 16
EVAL_CHUNK = 1 << 17


def _report(progress, label, advance, total):
    if progress is not None:
        progress(label, advance, total)


# -- tessellation for rendering ---------------------------------------------------------


def grid_triangles(n: int) -> np.ndarray:
    """(2 (n-1)^2, 3) int: triangles of an n x n grid numbered i * n + j, i along u,
    counter-clockwise seen against the normal u x v."""
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    b, c, d = a + n, a + n + 1, a + 1
    return np.stack([np.stack([a, b, c], 1), np.stack([a, c, d], 1)], axis=1).reshape(-1, 3)


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

    @property
    def triangle_patch(self) -> np.ndarray:
        return np.arange(self.triangles.shape[0]) // self.per_patch


def default_resolution(n_patches: int, target_triangles: int = 600_000, largest: int = 8) -> int:
    """Grid size per patch keeping the mesh under about ``target_triangles`` triangles
    (at least 2: two triangles per patch). The mesh only finds the patch and a start
    (u, v) for the Newton steps, so a coarse one suffices; building the ray-tracing
    structure costs about 2 s per million triangles."""
    if n_patches <= 0:
        return 2
    n = int(np.floor(np.sqrt(target_triangles / (2.0 * n_patches)))) + 1
    return int(np.clip(n, 2, largest))


def euclidean(points: np.ndarray) -> np.ndarray:
    """(..., 3): the points themselves, or homogeneous (x w, y w, z w, w) divided by w."""
    if points.shape[-1] == 4:
        return points[..., :3] / points[..., 3:4]
    return points[..., :3]


def patch_grid_mesh(groups, resolution: int) -> PatchGridMesh:
    """Sample every patch of ``groups`` (list of (p, d+1, d+1, dim)) on an n x n grid."""
    n = int(resolution)
    t = np.linspace(0.0, 1.0, n)
    blocks = []
    for group in groups:
        if group.shape[0] == 0:
            continue
        b = bernstein_basis(group.shape[1] - 1, t)
        c = bernstein_basis(group.shape[2] - 1, t)
        p, dim = group.shape[0], group.shape[3]
        along_v = np.matmul(c, group)  # (p, du+1, n, dim)
        grid = np.matmul(b, along_v.reshape(p, group.shape[1], n * dim)).reshape(p, n, n, dim)
        blocks.append(euclidean(grid).reshape(-1, 3))
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


def newton_on_rays(group, index, u, v, origins, directions, steps: int = 8, columns=None, tolerance: float = 1e-9):
    """Newton steps on ``x(u, v) = o + t d``, one patch per ray, until the parameter step
    is below ``tolerance`` (at most ``steps`` steps).

    The patch polynomials are used a little beyond [0, 1] (clamped to [-0.5, 1.5]),
    so a ray that meets the surface on a neighbouring patch ends outside the unit
    square, on the side where that neighbour is.

    Parameters
    ----------
    group : (p, d+1, d+1, dim) float; index : (m,) int, the patch of each ray
    u, v : (m,) float, start values; origins, directions : (m, 3)
    columns : ``curvature.patch_columns(group)`` to reuse, or None

    Returns
    -------
    u, v : (m,) float after the steps
    start_distance : (m,) float, distance of the start point from its ray
    """
    u, v = np.array(u, dtype=np.float64), np.array(v, dtype=np.float64)
    x, xu, xv = patch_tangents(group, u, v, index=index, columns=columns)
    start = _ray_distance(x, origins, directions)
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
        x, xu, xv = patch_tangents(group, u[active], v[active], index=index[active], columns=columns)
    return u, v, start


class SideNeighbours:
    """The patch across each side of each patch, found from the geometry: two sides match
    when their boundary curves have the same mid point (and end points, maybe reversed).
    Sides: 0: u = 0, 1: u = 1, 2: v = 0, 3: v = 1 (the other parameter runs along)."""

    def __init__(self, groups):
        from scipy.spatial import cKDTree

        mids, starts = [], []
        for group in groups:
            half = bernstein_basis(group.shape[1] - 1, np.array([0.5]))[0]
            half_v = bernstein_basis(group.shape[2] - 1, np.array([0.5]))[0]
            sides = ((group[:, 0], half_v), (group[:, -1], half_v), (group[:, :, 0], half), (group[:, :, -1], half))
            mids.append(np.stack([euclidean(np.einsum("i,pid->pd", w, c)) for c, w in sides], axis=1).reshape(-1, 3))
            starts.append(np.stack([euclidean(c[:, 0]) for c, _ in sides], axis=1).reshape(-1, 3))
        self.mids = np.concatenate(mids)
        self.starts = np.concatenate(starts)
        self.tolerance = 1e-7 * max(float(np.ptp(self.mids, axis=0).max()), 1e-300)
        self.tree = cKDTree(self.mids, balanced_tree=False, compact_nodes=False)

    def across(self, patch: np.ndarray, side: np.ndarray):
        """(q, side_q, reversed) for each (patch, side); q = -1 where no patch is across."""
        key = patch * 4 + side
        dist, idx = self.tree.query(self.mids[key], k=3)
        other = np.where(idx[:, 0] != key, idx[:, 0], idx[:, 1])
        gap = np.where(idx[:, 0] != key, dist[:, 0], dist[:, 1])
        other = np.where(gap <= self.tolerance, other, -1)
        safe = np.maximum(other, 0)
        flipped = np.linalg.norm(self.starts[key] - self.starts[safe], axis=1) > self.tolerance
        return np.where(other >= 0, other // 4, -1), np.where(other >= 0, other % 4, -1), flipped


def _hop(neighbours: SideNeighbours, patch, u, v):
    """Move (patch, u, v) that lie outside the unit square to the patch across the side they
    crossed, at the matching parameters; those with no neighbour are clamped instead.

    Returns
    -------
    patch, u, v : (m,) updated; moved : (m,) bool
    """
    below_u, above_u, below_v, above_v = -u, u - 1, -v, v - 1
    excess = np.stack([below_u, above_u, below_v, above_v], axis=1)
    side = np.argmax(excess, axis=1)
    along = np.where(side < 2, v, u)
    depth = np.clip(excess[np.arange(side.size), side], 0.0, 0.5)
    q, side_q, flipped = neighbours.across(patch, side)
    moved = q >= 0
    t = np.clip(np.where(flipped, 1.0 - along, along), 0.0, 1.0)
    nu = np.select([side_q == 0, side_q == 1], [depth, 1.0 - depth], t)
    nv = np.select([side_q == 2, side_q == 3], [depth, 1.0 - depth], t)
    return (np.where(moved, q, patch), np.where(moved, nu, np.clip(u, 0, 1)),
            np.where(moved, nv, np.clip(v, 0, 1)), moved)


def locate_on_rays(groups, patch, u, v, origins, directions, steps: int = 8, hops: int = 2, progress=None,
                   columns=None):
    """Exact (patch, u, v) where each ray meets the surface, from approximate ones.

    Newton steps on the start patch; a ray whose solution leaves the patch moves to the
    patch across that side (``SideNeighbours``) and continues there, at most ``hops``
    times. Callers should keep the start values where this did not bring the point
    closer to the ray (a ray that grazes the silhouette may miss the exact surface).

    Returns
    -------
    patch : (m,) int; u, v : (m,) float in [0, 1]
    start_distance : (m,) float, distance of the start point from its ray
    """
    offsets = np.concatenate([[0], np.cumsum([g.shape[0] for g in groups])])
    if columns is None:
        columns = [patch_columns(g) if g.shape[0] else None for g in groups]
    patch, u, v = np.array(patch, dtype=np.int64), np.array(u, dtype=np.float64), np.array(v, dtype=np.float64)
    start_distance = np.zeros(patch.size)
    todo = np.arange(patch.size)
    neighbours = None
    for round_ in range(hops + 1):
        for k, group in enumerate(groups):
            which = todo[(patch[todo] >= offsets[k]) & (patch[todo] < offsets[k + 1])]
            for lo in range(0, which.size, EVAL_CHUNK):
                idx = which[lo : lo + EVAL_CHUNK]
                u[idx], v[idx], d0 = newton_on_rays(group, patch[idx] - offsets[k], u[idx], v[idx], origins[idx],
                                                    directions[idx], steps, columns[k])
                if round_ == 0:
                    start_distance[idx] = d0
                    _report(progress, "finding the exact hits", idx.size, patch.size)
        eps = 1e-12
        out = (u[todo] < -eps) | (u[todo] > 1 + eps) | (v[todo] < -eps) | (v[todo] > 1 + eps)
        todo = todo[out]
        if todo.size == 0 or round_ == hops:
            break
        if neighbours is None:
            neighbours = SideNeighbours(groups)
        patch[todo], u[todo], v[todo], moved = _hop(neighbours, patch[todo], u[todo], v[todo])
        todo = todo[moved]
    return patch, np.clip(u, 0.0, 1.0), np.clip(v, 0.0, 1.0), start_distance


# -- images -----------------------------------------------------------------------------


@dataclass
class Image:
    """Per-pixel buffers (dict of (H, W) float arrays), the camera, and how they were made."""

    channels: dict
    camera: Camera | None
    info: dict = field(default_factory=dict)
    view_directions: np.ndarray | None = None  # (H, W, 3) unit ray direction at each surface pixel

    @property
    def mask(self) -> np.ndarray:
        return self.channels["patch"] >= 0

    @property
    def shape(self) -> tuple:
        return self.channels["patch"].shape


def _empty_channels(shape) -> dict:
    out = {name: np.zeros(shape) for name in CURVATURE_NAMES + GEOMETRY_NAMES}
    out["patch"][:] = -1
    out["Z"][:] = np.inf
    return out


def evaluate_samples(groups, patch, u, v, progress=None, label: str = "evaluating curvature", columns=None):
    """Curvature and geometry at samples (patch, u, v); ``columns``: the groups'
    ``curvature.patch_columns`` if already made.

    Returns
    -------
    dict of (m,) arrays: patch, u, v, kmax, K, H, k1, k2, and (m, 3) point, normal
    """
    patch = np.asarray(patch, dtype=np.int64)
    m = patch.size
    out = {name: np.full(m, np.nan) for name in CURVATURE_NAMES}
    out["patch"] = patch
    out["u"], out["v"] = np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64)
    out["point"], out["normal"] = np.full((m, 3), np.nan), np.full((m, 3), np.nan)
    start = 0
    for k, group in enumerate(groups):
        which = np.flatnonzero((patch >= start) & (patch < start + group.shape[0]))
        cols = columns[k] if columns is not None else (patch_columns(group) if which.size else None)
        for lo in range(0, which.size, EVAL_CHUNK):
            idx = which[lo : lo + EVAL_CHUNK]
            d = patch_derivatives(group, out["u"][idx], out["v"][idx], index=patch[idx] - start, columns=cols)
            c = curvature_from_derivatives(*d)
            for name in CURVATURE_NAMES:
                out[name][idx] = c[name]
            out["point"][idx], out["normal"][idx] = c.point, c.normal
            _report(progress, label, idx.size, m)
        start += group.shape[0]
    return out


def _fill(channels, flat_index, values, camera):
    """Write per-sample ``values`` into the image buffers at raveled pixel ``flat_index``."""
    for name in CURVATURE_NAMES + ("u", "v"):
        channels[name].reshape(-1)[flat_index] = values[name]
    for k, axis in enumerate("XYZ"):
        channels[f"N.{axis}"].reshape(-1)[flat_index] = values["normal"][:, k]
        channels[f"P.{axis}"].reshape(-1)[flat_index] = values["point"][:, k]
    if camera is not None:
        channels["Z"].reshape(-1)[flat_index] = camera.depth(values["point"])
    else:
        channels["Z"].reshape(-1)[flat_index] = 0.0


def render(groups, camera: Camera, resolution: int | None = None, newton_steps: int = 8, progress=None,
           mesh: PatchGridMesh | None = None) -> Image:
    """Ray-cast the surface: exact (patch, u, v), curvature, normal and depth per pixel.

    Parameters
    ----------
    groups : list of (p, d+1, d+1, dim) patch arrays (global patch index runs through
        them in order); dim 4 = homogeneous (rational)
    camera : Camera
    resolution : samples per patch side of the ray-casting mesh (default: about 2M
        triangles in all)
    newton_steps : at most this many Newton steps from the tessellation hit onto the exact
        patch (per patch visited; they stop when converged); 0 keeps the tessellation's (u, v)
    progress : callable(label, advance, total) or None
    mesh : ``patch_grid_mesh(groups, n)`` if already made (e.g. to frame the camera)

    Returns
    -------
    Image
    """
    n_patches = sum(g.shape[0] for g in groups)
    if n_patches == 0:
        raise ValueError("no patches to render")
    n = mesh.resolution if mesh is not None else resolution or default_resolution(n_patches)
    clock = [time.perf_counter()]

    def lap():
        clock.append(time.perf_counter())
        return round(clock[-1] - clock[-2], 4)

    _report(progress, "building the ray tracer", 0, 1)
    if mesh is None:
        mesh = patch_grid_mesh(groups, n)
    caster = RayCaster(mesh.points, mesh.triangles)
    _report(progress, "building the ray tracer", 1, 1)
    seconds = {"tessellate": lap()}
    h, w = camera.height, camera.width
    channels = _empty_channels((h, w))
    pixel, tri_all, b1_all, b2_all, o_all, d_all = [], [], [], [], [], []
    rows_per_chunk = max(1, RAY_CHUNK // w)
    for r0 in range(0, h, rows_per_chunk):
        rows = slice(r0, min(h, r0 + rows_per_chunk))
        origins, dirs = camera.rays(rows)
        tri, b1, b2, _ = caster.cast(origins, dirs)
        hit = np.flatnonzero(tri >= 0)
        pixel.append(r0 * w + hit)
        tri_all.append(tri[hit])
        b1_all.append(b1[hit])
        b2_all.append(b2[hit])
        o_all.append(origins[hit])
        d_all.append(dirs[hit])
        _report(progress, "casting rays", origins.shape[0], h * w)
    seconds["cast"] = lap()
    pixel = np.concatenate(pixel)
    tri = np.concatenate(tri_all)
    b1, b2 = np.concatenate(b1_all), np.concatenate(b2_all)
    origins, dirs = np.concatenate(o_all), np.concatenate(d_all)
    patch = tri // mesh.per_patch
    corners = mesh.corner_uv[tri % mesh.per_patch]  # (m, 3, 2)
    uv = (1.0 - b1 - b2)[:, None] * corners[:, 0] + b1[:, None] * corners[:, 1] + b2[:, None] * corners[:, 2]
    u, v = np.clip(uv[:, 0], 0, 1), np.clip(uv[:, 1], 0, 1)
    columns = [patch_columns(g) if g.shape[0] else None for g in groups]
    if newton_steps > 0:
        patch0, u0, v0 = patch, u, v
        patch, u, v, before = locate_on_rays(groups, patch, u, v, origins, dirs, newton_steps, progress=progress,
                                             columns=columns)
    seconds["locate"] = lap()
    values = evaluate_samples(groups, patch, u, v, progress, columns=columns)
    if newton_steps > 0:
        # Keep the tessellation's (patch, u, v) where the exact search did not get closer
        # to the ray (rays grazing the silhouette may miss the exact surface).
        worse = np.flatnonzero(_ray_distance(values["point"], origins, dirs) > before * (1 + 1e-9) + 1e-300)
        if worse.size:
            redo = evaluate_samples(groups, patch0[worse], u0[worse], v0[worse], columns=columns)
            for name, array in values.items():
                array[worse] = redo[name]
            patch = values["patch"]
    channels["patch"].reshape(-1)[pixel] = patch
    _fill(channels, pixel, values, camera)
    view = np.zeros((h * w, 3))
    view[pixel] = dirs
    seconds["evaluate"] = lap()
    info = {"engine": caster.engine, "resolution": n, "triangles": int(mesh.triangles.shape[0]), "patches": n_patches,
            "hits": int(pixel.size), "seconds": seconds}
    return Image(channels, camera, info, view.reshape(h, w, 3))


def atlas_layout(n_patches: int, tile: int, columns: int | None = None) -> tuple[int, int]:
    """(rows, columns) of tiles for ``n_patches`` (about square)."""
    cols = columns or max(1, int(np.ceil(np.sqrt(max(n_patches, 1)))))
    return max(1, int(np.ceil(n_patches / cols))), cols


def default_tile(n_patches: int, budget: int = 4_000_000, largest: int = 32) -> int:
    """Largest tile size (pixels per patch side) keeping the atlas under ``budget`` pixels."""
    return int(np.clip(np.floor(np.sqrt(budget / max(n_patches, 1))), 2, largest))


def render_atlas(groups, tile: int | None = None, camera: Camera | None = None, columns: int | None = None,
                 progress=None) -> Image:
    """Parameter-space image: patch k is a tile x tile square, u to the right, v up.

    Tile k is at row k // columns, column k % columns; pixel centres sample
    u = (c + 0.5) / tile, v = 1 - (r + 0.5) / tile. ``Z`` is the depth seen from
    ``camera`` (0 without one).
    """
    n_patches = sum(g.shape[0] for g in groups)
    tile = tile or default_tile(n_patches)
    rows, cols = atlas_layout(n_patches, tile, columns)
    h, w = rows * tile, cols * tile
    channels = _empty_channels((h, w))
    i, j = np.divmod(np.arange(h * w), w)
    patch = (i // tile) * cols + (j // tile)
    inside = np.flatnonzero(patch < n_patches)
    r, c = i[inside] % tile, j[inside] % tile
    u = (c + 0.5) / tile
    v = 1.0 - (r + 0.5) / tile
    values = evaluate_samples(groups, patch[inside], u, v, progress=progress)
    channels["patch"].reshape(-1)[inside] = patch[inside]
    _fill(channels, inside, values, camera)
    view = np.zeros((h * w, 3))
    if camera is not None:
        if camera.projection == "perspective":
            rel = values["point"] - camera.eye
            view[inside] = rel / np.linalg.norm(rel, axis=1, keepdims=True)
        else:
            view[inside] = camera.forward
    info = {"tile": tile, "rows": rows, "columns": cols, "patches": n_patches}
    return Image(channels, camera, info, view.reshape(h, w, 3))


# -- shading and reflection lines ---------------------------------------------------------


def normals_of(image: Image) -> np.ndarray:
    return np.stack([image.channels[f"N.{a}"] for a in "XYZ"], axis=-1)


def headlight(image: Image, ambient: float = 0.3) -> np.ndarray:
    """(H, W) diffuse shading from a light at the eye: ambient + (1 - ambient) |n . d|."""
    d = image.view_directions
    if d is None or not np.any(d):
        return np.ones(image.shape)
    lam = np.abs(np.einsum("hwd,hwd->hw", normals_of(image), d))
    return ambient + (1.0 - ambient) * np.nan_to_num(lam)


def reflection_phase(image: Image, axis=None) -> np.ndarray:
    """(H, W) angle in (-pi, pi] of the reflected view ray about the light-line ``axis``.

    The light is a set of parallel lines at infinity along ``axis`` (default: the
    camera's up vector), so the stripes ``sin(N phase)`` are the reflection lines of
    that environment; they are continuous where the normal is (G1) and break where
    it jumps. NaN on the background.
    """
    cam = image.camera
    axis = np.asarray(axis if axis is not None else cam.up, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    e1 = np.cross(cam.forward, axis)
    if np.linalg.norm(e1) < 1e-9:
        e1 = cam.right
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    d = image.view_directions
    n = normals_of(image)
    r = d - 2.0 * np.einsum("hwd,hwd->hw", d, n)[..., None] * n
    phase = np.arctan2(r @ e1, r @ e2)
    return np.where(image.mask, phase, np.nan)


def wrap(angle):
    """Angles into [-pi, pi)."""
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def stripes(phase: np.ndarray, count: int = 12) -> np.ndarray:
    """(H, W) stripe intensity in [0, 1] from ``phase``: ``count`` black and white pairs per
    turn, antialiased by the phase change between neighbouring pixels. NaN stays NaN."""
    p = count * phase
    s = np.sin(p)
    gx = np.zeros_like(p)
    gy = np.zeros_like(p)
    dx = np.abs(wrap(p[:, 1:] - p[:, :-1]))
    dy = np.abs(wrap(p[1:, :] - p[:-1, :]))
    gx[:, :-1] = np.nan_to_num(dx)
    gy[:-1, :] = np.nan_to_num(dy)
    # sin(p) changes by about g per pixel near an edge of a stripe: a ramp one pixel wide,
    # and grey where the stripes are finer than the pixels.
    g = np.maximum(np.hypot(gx, gy), 1e-6)
    return np.clip(0.5 + 0.5 * s / g, 0.0, 1.0)


def edge_discontinuity(values: np.ndarray, patch: np.ndarray, angular: bool = True):
    """Jumps of an image field across patch edges, with the smooth trend removed.

    For four pixels in a row (or column) a b | c d with a, b on one patch and c, d on
    another, the jump is ``|(c - b) - ((b - a) + (d - c)) / 2|``: about zero where the
    field is continuous and differentiable along the line, of the order of a pixel times
    the change of slope where only its derivative jumps (a G1 surface's reflection lines
    have such kinks), and the size of the break where the field itself jumps (normals
    that jump across an edge). The same statistic for four pixels on one patch is
    returned for scale.

    Returns
    -------
    across : (k,) float, one value per edge crossing
    within : (l,) float, one value per run of four pixels on one patch
    """
    across, within = [], []
    for f, p in ((values, patch), (values.T, patch.T)):
        a, b, c, d = f[:, :-3], f[:, 1:-2], f[:, 2:-1], f[:, 3:]
        pa, pb, pc, pd = p[:, :-3], p[:, 1:-2], p[:, 2:-1], p[:, 3:]
        on = (pa >= 0) & (pd >= 0) & (pb >= 0) & (pc >= 0)
        on &= np.isfinite(a) & np.isfinite(b) & np.isfinite(c) & np.isfinite(d)
        step = wrap if angular else (lambda x: x)
        jump = np.abs(step(c - b) - 0.5 * (step(b - a) + step(d - c)))
        across.append(jump[on & (pa == pb) & (pc == pd) & (pb != pc)])
        within.append(jump[on & (pa == pb) & (pb == pc) & (pc == pd)])
    return np.concatenate(across), np.concatenate(within)
