#!/usr/bin/env python
"""The fit's fairness measured in process: scan-to-surface RMS / p99 / max, surface-to-scan max and rho (the
ripple of mean curvature, ``bench/fit.py``'s) of ``fit_scan`` at the defaults and at FitOptions variants, against
rho of the Catmull-Clark limit of the same control mesh (unfitted, as ``bench/fit.py``: computed once a scan, cached
in --cache) and of the fitted control mesh (``fitted_cc_rho``: the same shape, a C2 surface).

    .venv/bin/python bench/fairness.py goathead fairness_term=thin-plate,fairness=1e-2 fairness_term=umbrella

Each argument after the scan is one variant: comma-separated FitOptions fields (``faces=N`` sets the control
faces, ``crease_angle=DEG`` tags the scan's sharp edges as ``--crease-angle``). Prints one JSON line per variant.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import fit as bench_fit  # noqa: E402


def parse_variant(text: str):
    from c1surf.fitting.options import FitOptions

    fields, faces, crease = {}, None, None
    for item in filter(None, text.split(",")):
        key, value = item.split("=", 1)
        if key in ("faces", "crease_angle"):
            faces, crease = (int(value), crease) if key == "faces" else (faces, float(value))
            continue
        kind = type(getattr(FitOptions(), key))
        fields[key] = value if kind is str else kind(float(value))
    return FitOptions(**fields), faces, crease


def catmull_clark_rho(scan: str, faces: int, cache: Path, crease_angle: float | None = None) -> dict:
    """rho of the Catmull-Clark limit proxy of the fit's control mesh and the ripple radius (cached)."""
    from c1surf.api import read_scan
    from c1surf.fitting.control.control_mesh import control_mesh_from_scan

    key = f"{Path(scan).stem}:{faces}" + (f":{crease_angle:g}" if crease_angle else "")
    known = json.loads(cache.read_text()) if cache.exists() else {}
    if key not in known:
        points, triangles, _ = read_scan(scan)
        control = control_mesh_from_scan(points, triangles, faces, crease_angle)
        radius = 0.5 * bench_fit.median_edge(control.face_sizes, control.face_vertices, control.points)
        cc_points, cc_triangles = bench_fit.catmull_clark(control, bench_fit.CC_LEVELS)
        H, area = bench_fit.cotangent_mean_curvature(cc_points, cc_triangles)
        known[key] = {"rho": bench_fit.ripple(cc_points, H, area, radius), "radius": radius}
        cache.write_text(json.dumps(known, indent=1))
    return known[key]


def measure(scan: str, variant: str, cache: Path) -> dict:
    from c1surf.api import read_scan
    from c1surf.evaluation.curvature import PatchSampler
    from c1surf.fitting.scan_fit import ScanFitOptions, default_face_count, fit_scan

    options, faces, crease = parse_variant(variant)
    points, triangles, _ = read_scan(scan)
    start = time.perf_counter()
    result = fit_scan(points, triangles, ScanFitOptions(faces=faces, crease_angle=crease, fit=options))
    seconds = time.perf_counter() - start
    requested = faces or default_face_count(triangles.shape[0])
    cc = catmull_clark_rho(scan, requested, cache, crease)
    surface = result.surface
    rho = bench_fit.sampler_ripple(PatchSampler([surface.biquadratic, surface.bicubic]), cc["radius"])
    cc_points, cc_triangles = bench_fit.catmull_clark(result.control, bench_fit.CC_LEVELS)  # the fitted cage's
    H, area = bench_fit.cotangent_mean_curvature(cc_points, cc_triangles)
    fitted_cc_rho = bench_fit.ripple(cc_points, H, area, cc["radius"])
    a, b = result.deviation.scan_stats, result.deviation.surface_stats
    row = {"scan": Path(scan).stem, "variant": variant or "defaults", "faces": result.control.n_faces,
           "rms": a["relative_rms"], "p99": a["relative_p99"], "max": a["relative_max"],
           "surface_max": b["relative_max"], "rho": rho, "cc_rho": cc["rho"], "rho_ratio": rho / cc["rho"],
           "fitted_cc_rho": fitted_cc_rho,
           "iterations": result.fit.iterations, "stopped": result.fit.stopped, "fairness": result.fit.fairness, "seconds": seconds,
           **{f"t_{k}": v for k, v in result.fit.timings.items()}}
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scan", help="a scan's name in ../shared/scans or a path")
    parser.add_argument("variants", nargs="*", default=[""])
    parser.add_argument("--cache", default="/tmp/c1surf-fairness-cc.json")
    args = parser.parse_args(argv)
    scan = args.scan if Path(args.scan).exists() else str(bench_fit.SCANS / f"{args.scan}.obj")
    for variant in args.variants or [""]:
        row = measure(scan, variant, Path(args.cache))
        print(json.dumps({k: (float(f"{v:.4g}") if isinstance(v, float) else v) for k, v in row.items()}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
