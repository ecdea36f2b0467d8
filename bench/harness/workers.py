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
    from c1surf import memory as runtime

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

    try:  # what an API user calls (at N = 2 it numbers the corners only); imported before any clock runs
        from c1surf.api import tessellate_surface
    except ImportError:  # a checkout from before the API module
        tessellate_surface = None

    clock = Clock()
    mesh = clock.step("read", read_mesh, job["path"])
    surface = clock.step("build", Surface, mesh.face_sizes, mesh.face_vertices, mesh.points)

    def tessellate():
        if tessellate_surface is not None:
            return tessellate_surface(surface, job.get("resolution", 2))
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
    """The numpy limits of a tessellation at N = 8 of bicubic patches, two ways (what each counts is in its name):

    "positions only": one dense product of the basis and coefficient-major coefficients, nothing else;
    "all outputs": what a tessellation writes for every sample, unwelded: its position and unit normal
    (one product with the bases of the values and both derivatives, then cross product and norm) and the
    triangles of the patch grid (a template shifted per patch), into arrays of the output's layout
    (points (V, 3), normals (V, 3), int32 triangles (T, 3)), by blocks of patches as c1surf works.
    """
    from c1surf import memory as runtime

    runtime.tune_allocator()  # the same allocator setting as the c1surf workers
    patches, n = job["patches"], 8
    rng = np.random.default_rng(0)
    value, du, dv = _bicubic_bases(n)
    coefficients = rng.standard_normal((16, 3 * patches))  # coefficient-major: one GEMM
    positions = _best_of(job.get("repeats", 3), lambda: value @ coefficients)  # fresh output, like any evaluation
    del coefficients
    patch_major = rng.standard_normal((patches, 16, 3))
    outputs = _best_of(job.get("repeats", 3), lambda: _all_outputs(patch_major, value, du, dv, n))
    samples = patches * n * n
    result = {"patches": patches, "resolution": n, "samples": samples}
    for key, times in (("positions only", positions), ("all outputs", outputs)):
        result[key] = {"seconds": statistics.median(times), "samples_per_second": samples / statistics.median(times),
                       "best_samples_per_second": samples / min(times)}
    result.update(result["positions only"], counts="positions only")  # the version-2 fields: the positions' limit
    return result


def _bicubic_bases(n: int):
    """(n n, 16) float each: the bicubic Bernstein basis at the n x n grid, and its u and v derivatives."""
    from scipy.special import comb

    t = np.linspace(0.0, 1.0, n)
    b = comb(3, np.arange(4)) * t[:, None] ** np.arange(4) * (1 - t[:, None]) ** (3 - np.arange(4))
    lower = comb(2, np.arange(3)) * t[:, None] ** np.arange(3) * (1 - t[:, None]) ** (2 - np.arange(3))
    db = 3 * (np.pad(lower, ((0, 0), (1, 0))) - np.pad(lower, ((0, 0), (0, 1))))  # d/dt of the cubic basis
    grid = lambda x, y: np.einsum("ai,bj->abij", x, y).reshape(n * n, 16)
    return grid(b, b), grid(db, b), grid(b, db)


def _best_of(repeats: int, run) -> list:
    """Seconds of ``repeats`` calls of ``run`` after a first one (which touches the output's pages)."""
    times = []
    for _ in range(repeats + 1):
        start = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - start)
        del out
    return times[1:]


def _all_outputs(coefficients: np.ndarray, value, du, dv, n: int, block: int = 4096):
    """(points (P n n, 3), normals (P n n, 3), triangles (2 P (n-1)^2, 3) int32) of (P, 16, 3) bicubic patches."""
    p, m = coefficients.shape[0], n * n
    stacked = np.concatenate([value, du, dv]).T.copy()  # (16, 3 m)
    points, normals = np.empty((p * m, 3)), np.empty((p * m, 3))
    q = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)).ravel()
    template = np.concatenate([np.stack([q, q + 1, q + n + 1], -1), np.stack([q, q + n + 1, q + n], -1)]).astype(np.int32)
    triangles = np.empty((p * template.shape[0], 3), dtype=np.int32)
    for a in range(0, p, block):
        z = min(a + block, p)
        rows = (coefficients[a:z].transpose(0, 2, 1).reshape(-1, 16) @ stacked).reshape(z - a, 3, 3, m)
        points[a * m : z * m].reshape(z - a, m, 3)[:] = rows[:, :, 0].transpose(0, 2, 1)
        u, v = rows[:, :, 1], rows[:, :, 2]  # (b, 3, m)
        cross = np.stack([u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1], u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
                          u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]], axis=-1)  # (b, m, 3)
        cross /= np.sqrt(np.einsum("...i,...i->...", cross, cross))[..., None]
        normals[a * m : z * m] = cross.reshape(-1, 3)
        shift = (np.arange(a, z, dtype=np.int32) * m)[:, None, None]
        triangles[a * template.shape[0] : z * template.shape[0]].reshape(z - a, -1, 3)[:] = template + shift
    return points, normals, triangles
