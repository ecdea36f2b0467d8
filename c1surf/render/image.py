"""Images of a patch surface with exact per-pixel curvature: a camera's view, or an atlas of the patches.

Images are dicts of (H, W) float arrays named like the EXR channels:
``kmax K H k1 k2 Z N.X N.Y N.Z P.X P.Y P.Z patch u v`` (``patch`` = -1 and the
others 0 on the background, except ``Z`` = +inf there). Curvature, normal and
position are evaluated at each pixel's exact (patch, u, v) (``raycast``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..evaluation.curvature import CURVATURE_NAMES, Curvature, PatchSampler
from ..evaluation.patch_set import PatchSet
from .camera import Camera
from .raycast import (EVAL_CHUNK, PatchGridMesh, RayCaster, cast_camera_rays, default_resolution, locate_on_rays,
                      patch_grid_mesh, ray_distance, report)

GEOMETRY_NAMES = ("Z", "N.X", "N.Y", "N.Z", "P.X", "P.Y", "P.Z", "patch", "u", "v")


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


def _fill(channels: dict, pixel: np.ndarray, patch, u, v, values: Curvature, camera: Camera | None) -> None:
    """Write the samples (patch, u, v) and their ``values`` into the buffers at raveled ``pixel``."""
    def flat(name):
        return channels[name].reshape(-1)

    for name in CURVATURE_NAMES:
        flat(name)[pixel] = values[name]
    flat("patch")[pixel], flat("u")[pixel], flat("v")[pixel] = patch, u, v
    for k, axis in enumerate("XYZ"):
        flat(f"N.{axis}")[pixel] = values.normal[:, k]
        flat(f"P.{axis}")[pixel] = values.point[:, k]
    flat("Z")[pixel] = camera.depth(values.point) if camera is not None else 0.0


def _evaluate(sampler: PatchSampler, patch, u, v, progress=None) -> Curvature:
    """Curvature at global samples, reported as "evaluating curvature"."""
    def advance(n):
        report(progress, "evaluating curvature", n, np.size(patch))

    return sampler.curvature_at(patch, u, v, EVAL_CHUNK, advance if progress is not None else None)


class _Stopwatch:
    """Seconds spent per phase, rounded to 0.1 ms."""

    def __init__(self):
        self.seconds, self._last = {}, time.perf_counter()

    def lap(self, name: str) -> None:
        now = time.perf_counter()
        self.seconds[name], self._last = round(now - self._last, 4), now


def render(patches: PatchSet, camera: Camera, resolution: int | None = None, newton_steps: int = 8, progress=None,
           mesh: PatchGridMesh | None = None) -> Image:
    """Ray-cast the surface: exact (patch, u, v), curvature, normal and depth per pixel.

    Parameters
    ----------
    patches : PatchSet (groups, rational weights, and the adjacency if known: else the
        geometry gives it, when a ray first leaves its patch)
    camera : Camera
    resolution : samples per patch side of the ray-casting mesh (default: about 600k
        triangles in all)
    newton_steps : at most this many Newton steps from the mesh hit onto the exact
        patch (per patch visited; they stop when converged); 0 keeps the mesh's (u, v)
    progress : callable(label, advance, total) or None
    mesh : ``patch_grid_mesh`` of the patches if already made (e.g. to frame the camera)

    Returns
    -------
    Image
    """
    n_patches = patches.n_patches
    if n_patches == 0:
        raise ValueError("no patches to render")
    watch = _Stopwatch()
    report(progress, "building the ray tracer", 0, 1)
    if mesh is None:
        mesh = patch_grid_mesh(patches.groups, resolution or default_resolution(n_patches), patches.weights)
    caster = RayCaster(mesh.points, mesh.triangles)
    report(progress, "building the ray tracer", 1, 1)
    watch.lap("tessellate")
    hits = cast_camera_rays(caster, mesh, camera, progress)
    watch.lap("cast")
    sampler = PatchSampler(patches.groups, patches.weights)
    patch, u, v, values = _exact_samples(sampler, patches, hits, newton_steps, progress, watch)
    h, w = camera.height, camera.width
    channels = _empty_channels((h, w))
    _fill(channels, hits.pixel, patch, u, v, values, camera)
    view = np.zeros((h * w, 3))
    view[hits.pixel] = hits.directions
    watch.lap("evaluate")
    info = {"engine": caster.engine, "resolution": mesh.resolution, "triangles": int(mesh.triangles.shape[0]),
            "patches": n_patches, "hits": int(hits.pixel.size), "seconds": watch.seconds}
    return Image(channels, camera, info, view.reshape(h, w, 3))


def _exact_samples(sampler: PatchSampler, patches: PatchSet, hits, newton_steps: int, progress, watch: _Stopwatch):
    """(patch, u, v, Curvature) at the exact hits; the mesh's where the exact search did not get
    closer to the ray (rays grazing the silhouette may miss the exact surface)."""
    if newton_steps <= 0:
        watch.lap("locate")
        return hits.patch, hits.u, hits.v, _evaluate(sampler, hits.patch, hits.u, hits.v, progress)
    patch, u, v, before = locate_on_rays(sampler, patches.welding, hits, newton_steps, progress=progress)
    watch.lap("locate")
    values = _evaluate(sampler, patch, u, v, progress)
    worse = np.flatnonzero(ray_distance(values.point, hits.origins, hits.directions) > before * (1 + 1e-9) + 1e-300)
    if worse.size:
        redo = _evaluate(sampler, hits.patch[worse], hits.u[worse], hits.v[worse])
        for name in CURVATURE_NAMES + ("point", "normal"):
            values[name][worse] = redo[name]
        patch[worse], u[worse], v[worse] = hits.patch[worse], hits.u[worse], hits.v[worse]
    return patch, u, v, values


def atlas_layout(n_patches: int, tile: int, columns: int | None = None) -> tuple[int, int]:
    """(rows, columns) of tiles for ``n_patches`` (about square)."""
    cols = columns or max(1, int(np.ceil(np.sqrt(max(n_patches, 1)))))
    return max(1, int(np.ceil(n_patches / cols))), cols


def default_tile(n_patches: int, budget: int = 4_000_000, largest: int = 32) -> int:
    """Largest tile size (pixels per patch side) keeping the atlas under ``budget`` pixels."""
    return int(np.clip(np.floor(np.sqrt(budget / max(n_patches, 1))), 2, largest))


def render_atlas(patches: PatchSet, tile: int | None = None, camera: Camera | None = None, columns: int | None = None,
                 progress=None) -> Image:
    """Parameter-space image: patch k is a tile x tile square, u to the right, v up.

    Tile k is at row k // columns, column k % columns; pixel centres sample
    u = (c + 0.5) / tile, v = 1 - (r + 0.5) / tile. ``Z`` is the depth seen from
    ``camera`` (0 without one).
    """
    n_patches = patches.n_patches
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
    values = _evaluate(PatchSampler(patches.groups, patches.weights), patch[inside], u, v, progress)
    _fill(channels, inside, patch[inside], u, v, values, camera)
    view = np.zeros((h * w, 3))
    if camera is not None:
        if camera.projection == "perspective":
            rel = values.point - camera.eye
            view[inside] = rel / np.linalg.norm(rel, axis=1, keepdims=True)
        else:
            view[inside] = camera.forward
    info = {"tile": tile, "rows": rows, "columns": cols, "patches": n_patches}
    return Image(channels, camera, info, view.reshape(h, w, 3))
