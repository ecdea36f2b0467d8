"""The fitting core (``c1surf.fitting``) on a scan and a control mesh: deviation, rounds, seconds per stage.

    .venv/bin/python bench/fit_core.py SCAN CONTROL [key=value ...]

Keys: any ``FitOptions`` field (plane, point, fairness, max_iterations, stop, candidates, newton_steps,
start_resolution, solver), refinements=0|1|2|auto (default 2), align=1 (move the control mesh so that
its bounding box's centre in x is the scan's: fish's control mesh is offset from its scan by 3.4 in x),
split=k (split every n-gon of the control mesh into n quads, k times: larger control meshes),
subdivide=k (split every scan triangle into 4, k times: larger scans). The scan is welded (spot's
vertices are split along its texture seams).

Measured (issue 29), e.g.
    bench/fit_core.py ../shared/scans/spot.obj ../shared/meshes/spot/spot_control_mesh.obj refinements=auto
"""
from __future__ import annotations

import sys
import time

import numpy as np

from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.fitting.deviation import two_sided_deviation
from c1surf.fitting.iterate import fit_surface_points
from c1surf.fitting.options import FitOptions
from c1surf.prepare.mesh_edits import weld_mesh_file
from c1surf.io.meshes.read import read_mesh


def quad_split(points, sizes, corners):
    """Every n-gon into n quads (its centre, edge midpoints): (points, sizes, corners) of the finer mesh."""
    offsets = np.r_[0, np.cumsum(sizes)]
    face = np.repeat(np.arange(sizes.size), sizes)
    following = np.arange(corners.size) + 1
    following[offsets[1:] - 1] = offsets[:-1]
    previous = np.arange(corners.size) - 1
    previous[offsets[:-1]] = offsets[1:] - 1
    n = len(points)
    key = np.minimum(corners, corners[following]) * n + np.maximum(corners, corners[following])
    edges, edge = np.unique(key, return_inverse=True)
    middle = (points[edges // n] + points[edges % n]) / 2
    centre = np.zeros((sizes.size, 3))
    np.add.at(centre, face, points[corners])
    centre /= sizes[:, None]
    quads = np.stack([corners, n + edge, n + edges.size + face, n + edge[previous]], axis=1)
    return np.concatenate([points, middle, centre]), np.full(corners.size, 4), quads.ravel()


def main(argv):
    scan_path, control_path = argv[:2]
    keys = dict(a.split("=", 1) for a in argv[2:])
    refinements = keys.pop("refinements", "2")
    refinements = refinements if refinements == "auto" else int(refinements)
    align, split, subdivide = (int(keys.pop(k, "0")) for k in ("align", "split", "subdivide"))
    fields = FitOptions.__dataclass_fields__
    options = FitOptions(**{k: (v if fields[k].type == "str" else type(getattr(FitOptions(), k))(float(v)))
                            for k, v in keys.items()})
    start = time.perf_counter()
    scan, _ = weld_mesh_file(read_mesh(scan_path))
    if not np.all(scan.face_sizes == 3):
        raise SystemExit("the scan must be a triangle mesh")
    used = np.unique(scan.face_vertices)
    renumber = np.full(scan.points.shape[0], -1)
    renumber[used] = np.arange(used.size)
    points, triangles = scan.points[used], renumber[scan.face_vertices].reshape(-1, 3)
    for _ in range(subdivide):
        import trimesh

        points, triangles = trimesh.remesh.subdivide(points, triangles)
    control = read_mesh(control_path)
    cpoints, sizes, corners = control.points, control.face_sizes, control.face_vertices
    if align:
        shift = (points.max(0) + points.min(0)) / 2 - (cpoints.max(0) + cpoints.min(0)) / 2
        cpoints = cpoints + shift * np.array([1.0, 0.0, 0.0])
    for _ in range(split):
        cpoints, sizes, corners = quad_split(cpoints, sizes, corners)
    read = time.perf_counter()
    surface = Surface(sizes, corners, cpoints, SurfaceOptions(refinements=refinements))
    built = time.perf_counter()
    print(f"scan {points.shape[0]} vertices {triangles.shape[0]} triangles; control mesh {cpoints.shape[0]} vertices "
          f"{sizes.size} faces; refinements {surface.refinements}; patches {surface.n_patches}; "
          f"read {read - start:.2f} s, surface {built - read:.2f} s")
    result = fit_surface_points(surface, points, triangles, options)
    fitted = time.perf_counter()
    deviation = two_sided_deviation(surface, points, triangles, result.footpoints)
    measured = time.perf_counter()
    smooth = measure_smoothness([surface.biquadratic, surface.bicubic], samples=11, crease_sides=surface.crease_sides)
    print(f"fit {fitted - built:.2f} s ({result.solver}, {result.stopped}, {result.iterations} solves): "
          + ", ".join(f"{k} {v:.2f}" for k, v in result.timings.items()) + f"; deviation {measured - fitted:.2f} s")
    for h in result.history:
        print(f"  round {h['iteration']}: RMS {h['relative_rms']:.2e} p99 {h['relative_p99']:.2e} "
              f"max {h['relative_max']:.2e} ({h['seconds']:.2f} s)")
    for name, stats in (("scan to surface", deviation.scan_stats), ("surface to scan", deviation.surface_stats)):
        print(f"  {name}: RMS {stats['relative_rms']:.2e} p99 {stats['relative_p99']:.2e} "
              f"max {stats['relative_max']:.2e} of the diagonal {deviation.diagonal:.4g}")
    print(f"  G1: normal jump {smooth.max_normal_jump:.1e} rad, gap {smooth.max_gap:.1e} "
          f"on {smooth.shared_edges} edges")


if __name__ == "__main__":
    main(sys.argv[1:])
