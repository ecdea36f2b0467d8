"""``--tolerance`` against uniform resolution: triangles for the same measured chordal error.

Only run when the c1surf being measured has the option (``c1surf convert
--help``). For one input, every tessellation comes from the command line and
is measured with one yardstick: the largest distance from a triangle's centroid
or edge midpoint to a reference tessellation of the same surface at a much
finer uniform resolution (``geometry.MeshDistance``), relative to the
reference's bounding-box diagonal. The reference's own chordal error shrinks as
the square of its sample spacing; the result records an estimate of it.
Uniform resolutions N = 2, 3, ... are measured until one is at least as fine as
every tolerance's output; for each T the table then gives the triangles of T's
output and of the coarsest N that reaches the same measured error.
"""
from __future__ import annotations

import re
import tempfile

from .fidelity import c1surf_mesh, fine_resolution
from .geometry import MeshDistance, chordal_samples, diagonal
from .processes import SETTINGS

NOTE = re.compile(r"measured chordal error ([0-9.eE+-]+)")


def _measured(reference: MeshDistance, scale: float, points, triangles) -> float:
    return reference.max_distance(chordal_samples(points, triangles)) / scale


def _uniform_sweep(job, scratch, error_of, goal: float, stop: int) -> list[dict]:
    """Uniform resolutions 2, 3, ... up to ``stop``, until the measured error is at most ``goal``."""
    sweep = []
    for n in range(2, stop + 1):
        points, triangles, result = c1surf_mesh(job["path"], ["-r", n], scratch, job["timeout"])
        if points is None:
            raise RuntimeError(f"c1surf convert -r {n}: {result['error']}")
        sweep.append({"resolution": n, "triangles": int(len(triangles)), "error": error_of(points, triangles)})
        if sweep[-1]["error"] <= goal:
            break
    return sweep


def work_tolerance(job):
    """Triangles and measured chordal error of ``--tolerance T`` for each T, and of the uniform N matching each."""
    SETTINGS["root"] = job["root"]
    with tempfile.TemporaryDirectory(dir=job.get("scratch")) as scratch:
        points, _, result = c1surf_mesh(job["path"], ["-r", 2], scratch, job["timeout"])
        if points is None:
            raise RuntimeError(f"c1surf convert -r 2: {result['error']}")
        fine = fine_resolution(len(points), 2, job["budget"], job["max_resolution"])
        points, triangles, _ = c1surf_mesh(job["path"], ["-r", fine], scratch, job["timeout"])
        reference, scale = MeshDistance(points, triangles, k=3), diagonal(points)
        del points, triangles

        def error_of(p, t):
            return _measured(reference, scale, p, t)

        runs = []
        for t in job["tolerances"]:
            points, triangles, result = c1surf_mesh(job["path"], ["--tolerance", t], scratch, job["timeout"])
            if points is None:
                runs.append({"tolerance": t, "error": result["error"]})
                continue
            note = NOTE.search(result["stderr"])
            runs.append({"tolerance": t, "triangles": int(len(triangles)), "measured": error_of(points, triangles),
                         "reported": float(note.group(1)) if note else None, "seconds": result["seconds"]})
        goal = min([r["measured"] for r in runs if "measured" in r] + list(job["tolerances"]))
        sweep = _uniform_sweep(job, scratch, error_of, goal, max(2, fine // 2))
    for r in runs:  # None: no uniform resolution up to the sweep's end was as fine
        r["uniform"] = next((s for s in sweep if "measured" in r and s["error"] <= r["measured"]), None)
        r["uniform_within_t"] = next((s for s in sweep if s["error"] <= r["tolerance"]), None)
    last = sweep[-1]
    reference_error = last["error"] * ((last["resolution"] - 1) / (fine - 1)) ** 2
    return {"reference_resolution": fine, "reference_error_estimate": reference_error, "sweep": sweep,
            "tolerances": runs}
