"""Fidelity beside speed: how far each tool's surface lies from the input's vertices, and the volume it encloses.

For an input mesh and a tool: the distance from every input vertex to the
tool's output surface (mean and max, relative to the input's bounding-box
diagonal; ``geometry.MeshDistance``) and the enclosed volume over the input's
(the input's polygons split around their centroids). c1surf's surface is its
tessellation from the command line at a fine resolution, measured at two
resolutions so the table shows how much of the number is tessellation; the
peers' surfaces are their meshes after three levels of subdivision.
"""
from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from .geometry import MeshDistance, diagonal, enclosed_volume, is_closed
from .meshes import centroid_fan, fan_triangles, read_ply, read_polygon_obj
from .peers import PEERS
from .processes import SETTINGS, run_c1surf

class InputMesh:
    """The input's vertices, bounding-box diagonal and (when closed) volume."""

    def __init__(self, path):
        points, sizes, corners = read_polygon_obj(path)
        self.points, self.diagonal = points, diagonal(points)
        closed = is_closed(fan_triangles(sizes, corners))
        self.volume = enclosed_volume(*centroid_fan(points, sizes, corners)) if closed else None

    def measure(self, points: np.ndarray, triangles: np.ndarray) -> dict:
        """Distances from the input's vertices to the mesh (relative to the diagonal) and its volume over the input's."""
        d = MeshDistance(points, triangles)(self.points) / self.diagonal
        volume = None
        if self.volume and is_closed(triangles):
            volume = enclosed_volume(points, triangles) / self.volume
        return {"mean": float(d.mean()), "max": float(d.max()), "volume_ratio": volume,
                "output_vertices": int(len(points)), "output_triangles": int(len(triangles))}


def c1surf_mesh(path, options: list, scratch, timeout: float):
    """(points, triangles, process result) of ``c1surf convert PATH -o out.ply OPTIONS``; (None, None, result) if it failed."""
    target = Path(scratch) / "c1surf-out.ply"
    result = run_c1surf(["convert", path, "-o", target, *options], timeout)
    if not result["ok"]:
        return None, None, result
    points, triangles = read_ply(target)
    target.unlink()
    return points, triangles, result


def fine_resolution(vertices: int, resolution: int, budget: int, cap: int) -> int:
    """The resolution whose tessellation has about ``budget`` vertices, from one with ``vertices`` at ``resolution``."""
    patches = vertices / (resolution - 1) ** 2
    return int(min(cap, max(resolution + 1, math.floor(math.sqrt(budget / patches)) + 1)))


def work_fidelity(job):
    """One tool on one input: c1surf (``options``) at a coarse and a fine resolution, or a peer's subdivision."""
    SETTINGS["root"] = job["root"]
    mesh = InputMesh(job["path"])
    if job["measured"] != "c1surf":
        peer = PEERS[job["measured"]]
        subdivided = peer.subdivide(peer.read(job["path"]), job["levels"])
        return {"levels": job["levels"], **mesh.measure(*peer.arrays(subdivided))}
    out = {}
    with tempfile.TemporaryDirectory(dir=job.get("scratch")) as scratch:
        resolution = job["coarse_resolution"]
        for key in ("coarse", "fine"):
            points, triangles, result = c1surf_mesh(job["path"], job["options"] + ["-r", resolution], scratch,
                                                    job["timeout"])
            if points is None:
                raise RuntimeError(f"c1surf convert -r {resolution}: {result['error']}")
            out[key] = {"resolution": resolution, **mesh.measure(points, triangles)}
            resolution = fine_resolution(len(points), resolution, job["budget"], job["max_resolution"])
            del points, triangles
    return {**out["fine"], "coarse": out["coarse"]}
