"""What runs inside a worker process (``run.py --worker``): the peers' whole process, c1surf in memory, the limits.

c1surf's in-memory worker uses the Python API (``Surface``, ``tessellate_patches``,
``Surface.update_points``), which is what API users hold; c1surf's whole-process
numbers come from its command line instead (``processes.run_c1surf``).
"""
from __future__ import annotations

import resource
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from .meshes import torus
from .peers import PEERS

PATCH_STAGES = ("patches",)  # the A2/A3 layouts; every other stage is a refinement operator


def maxrss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class Clock:
    """Seconds and peak memory after each named step of a worker."""

    def __init__(self):
        self.seconds, self.peak = {}, {}

    def step(self, name: str, function, *args, **kwargs):
        start = time.perf_counter()
        value = function(*args, **kwargs)
        self.seconds[name] = time.perf_counter() - start
        self.peak[name] = maxrss_mb()
        return value


def work_peer(job):
    """A peer's whole job: read the OBJ, subdivide ``levels`` times, write a binary PLY ("convert" = the subdivision)."""
    peer, clock = PEERS[job["tool"]], Clock()
    mesh = clock.step("read", peer.read, job["path"])
    mesh = clock.step("convert", peer.subdivide, mesh, job.get("levels", 2))
    points, triangles = peer.arrays(mesh)
    output = {"vertices": int(len(points)), "triangles": int(len(triangles))}
    clock.step("write", peer.write, mesh, job["output"])
    return {"seconds": clock.seconds, "peak_mb_after": clock.peak, "output": output}


def _phases(surface, build: float) -> dict:
    """Split the time of one Surface construction into phases, from its stage list.

    ``Surface.timings`` holds the seconds spent on the topology, on building each
    stage and on applying it. Building the patch stages (A2/A3 layouts) is
    "patches", building the others (refinement operators) "refinement", applying
    all of them "geometry"; the rest of ``build`` counts as topology. A stage not
    applied yet (patches made on demand) counts nothing.
    """
    spent = {"refinement": 0.0, "patches": 0.0, "geometry": 0.0}
    for stage in surface.stages:
        kind = "patches" if stage.name in PATCH_STAGES else "refinement"
        spent[kind] += surface.timings.get(f"build {stage.name}", 0.0)
        spent["geometry"] += surface.timings.get(f"apply {stage.name}", 0.0)
    spent["topology"] = max(0.0, build - sum(spent.values()))
    return spent


def _c1surf_api():
    """The parts of c1surf's Python API the in-memory worker uses (imported after the allocator is tuned)."""
    from c1surf.cli import runtime

    runtime.tune_allocator()  # what the command line does first
    from c1surf.construction.surface import Surface
    from c1surf.evaluation.adjacency import patch_adjacency
    from c1surf.evaluation.tessellate import tessellate_patches

    return Surface, patch_adjacency, tessellate_patches


def work_c1surf(job):
    """c1surf in memory, phase by phase: read, build, N=2 tessellation, binary PLY, then ``update_points``.

    "convert" is build + tessellation: in memory, read and write excluded, like the peers' subdivision call.
    """
    Surface, patch_adjacency, tessellate_patches = _c1surf_api()
    from c1surf.io.meshes.read import read_mesh
    from c1surf.io.meshes.write import write_triangle_mesh

    clock = Clock()
    mesh = clock.step("read", read_mesh, job["path"])
    surface = clock.step("build", Surface, mesh.face_sizes, mesh.face_vertices, mesh.points)

    def tessellate():
        adjacency = patch_adjacency(surface.refined, surface.frames)
        return tessellate_patches([surface.biquadratic, surface.bicubic], adjacency, job.get("resolution", 2))

    tess = clock.step("tessellation", tessellate)
    clock.seconds.update(_phases(surface, clock.seconds["build"]))
    clock.seconds["convert"] = clock.seconds["build"] + clock.seconds["tessellation"]
    output = {"vertices": int(tess.points.shape[0]), "triangles": int(tess.triangles.shape[0]),
              "patches": int(surface.n_patches)}
    with tempfile.TemporaryDirectory(dir=job.get("scratch")) as scratch:
        target = Path(scratch) / "out.ply"
        clock.step("write", write_triangle_mesh, str(target), tess.points, tess.triangles, tess.normals)
    del tess
    rng = np.random.default_rng(1)
    times = []
    for _ in range(job.get("update_repeats", 5)):  # same connectivity, new geometry
        moved = mesh.points * (1.0 + 0.01 * rng.standard_normal((mesh.n_vertices, 1)))
        clock.step("update_points", surface.update_points, moved)
        times.append(clock.seconds["update_points"])
    clock.seconds["update_points"] = statistics.median(times)
    return {"seconds": clock.seconds, "peak_mb_after": clock.peak, "output": output}


def work_throughput(job):
    """c1surf's tessellation at resolution N (default 8) of a quad torus's patches: samples per second."""
    Surface, patch_adjacency, tessellate_patches = _c1surf_api()
    points, sizes, corners = torus(*job["grid"])
    surface = Surface(sizes, corners, points)
    groups = [surface.biquadratic, surface.bicubic]
    n = job.get("resolution", 8)
    adjacency = patch_adjacency(surface.refined, surface.frames)
    times = []
    for _ in range(job.get("repeats", 3)):
        start = time.perf_counter()
        tess = tessellate_patches(groups, adjacency, n)
        times.append(time.perf_counter() - start)
        vertices = int(tess.points.shape[0])
        del tess
    samples = surface.n_patches * n * n
    return {"patches": int(surface.n_patches), "resolution": n, "samples": samples, "welded_vertices": vertices,
            "seconds": statistics.median(times), "samples_per_second": samples / statistics.median(times),
            "best_samples_per_second": samples / min(times)}


def work_limit(job):
    """The numpy limit: bicubic patches on an 8 x 8 grid as one dense product, positions only (no normals, no triangles)."""
    from scipy.special import comb

    from c1surf.cli import runtime

    runtime.tune_allocator()  # the same allocator setting as the c1surf workers
    patches, n = job["patches"], 8
    coefficients = np.random.default_rng(0).standard_normal((16, 3 * patches))  # coefficient-major: one GEMM
    t = np.linspace(0.0, 1.0, n)
    i = np.arange(4)
    b = comb(3, i) * t[:, None] ** i * (1 - t[:, None]) ** (3 - i)
    basis = np.einsum("ai,bj->abij", b, b).reshape(n * n, 16)
    times = []
    for _ in range(job.get("repeats", 3) + 1):
        start = time.perf_counter()
        samples = basis @ coefficients  # fresh output, like any evaluation
        times.append(time.perf_counter() - start)
        del samples
    times = times[1:]  # the first touches the output's pages
    return {"patches": patches, "resolution": n, "samples": patches * n * n, "seconds": statistics.median(times),
            "samples_per_second": patches * n * n / statistics.median(times),
            "best_samples_per_second": patches * n * n / min(times), "counts": "positions only"}

