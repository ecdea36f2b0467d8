"""The control meshes `c1surf fit` starts from, on every scan of ../shared/scans (issue 29), unfitted.

For each scan and requested face count: the remesh's seconds and face count, what the cleanup changed,
whether the Surface builds without repairs and G1, its patches and Doo-Sabin steps ("auto"), the packed
CAD faces it would write (merged biquadratic rectangles + the other patches), and the unfitted distance
from the scan's vertices to the surface (closest points on its tessellation at -r 8), as fractions of
the scan's bounding-box diagonal.

    PYTHONPATH=. .venv/bin/python bench/control_meshes.py [--faces 500 1000 2000] [--scans fish wingnut]
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

SCANS = Path(__file__).resolve().parents[1].parent / "shared" / "scans"
NAMES = ("fish", "goathead", "koala_low_resolution", "spot", "wingnut")


def closest_distances(query: np.ndarray, points: np.ndarray, triangles: np.ndarray, k: int = 8) -> np.ndarray:
    """(q,) distance from each query point to the triangle mesh: the closest point on the triangles at the
    k nearest vertices (exact when the closest triangle has one of them as a corner)."""
    from scipy.sparse import csr_matrix
    from scipy.spatial import cKDTree
    from trimesh.triangles import closest_point

    _, near = cKDTree(points).query(query, k=k)
    incidence = csr_matrix((np.ones(triangles.size), (triangles.ravel(), np.repeat(np.arange(len(triangles)), 3))),
                           shape=(points.shape[0], len(triangles)))
    best = np.full(query.shape[0], np.inf)
    for column in range(k):
        rows = incidence[near[:, column]].tocoo()
        found = closest_point(points[triangles[rows.col]], query[rows.row])
        np.minimum.at(best, rows.row, np.linalg.norm(found - query[rows.row], axis=1))
    return best


def cad_faces(surface) -> int:
    """Faces a packed STEP/IGES file gets: merged biquadratic rectangles, then every patch they leave."""
    from c1surf.evaluation.merge import merge_biquadratic

    pieces = merge_biquadratic(surface)
    covered = sum(p.patches.size for p in pieces)
    return len(pieces) + surface.n_patches - covered


def measure(name: str, faces: int, crease_angle):
    import trimesh

    from c1surf.construction.surface import Surface, SurfaceOptions
    from c1surf.evaluation.smoothness import measure_smoothness
    from c1surf.evaluation.tessellate import tessellate
    from c1surf.fitting.control.control_mesh import control_mesh_from_scan

    scan = trimesh.load(SCANS / f"{name}.obj", process=False)
    points, triangles = np.asarray(scan.vertices, dtype=np.float64), np.asarray(scan.faces)
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    start = time.perf_counter()
    mesh = control_mesh_from_scan(points, triangles, faces, crease_angle)
    seconds = time.perf_counter() - start
    start = time.perf_counter()
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(refinements="auto"),
                      features=mesh.features())
    build = time.perf_counter() - start
    repaired = {k: v for k, v in surface.repairs.items() if k in ("flipped_faces", "split_vertices", "unused_vertices") and v}
    jump = measure_smoothness([surface.biquadratic, surface.bicubic]).max_normal_jump
    t = tessellate([surface.biquadratic, surface.bicubic], surface.refined, surface.frames, 8)
    d = closest_distances(points, t.points[:, :3], np.asarray(t.triangles)) / diagonal
    r = mesh.report
    changed = {k: r[k] for k in ("welded_vertices", "collapsed_edges", "dropped_faces", "non_manifold_faces",
                                 "filled_holes", "closed_holes", "split_vertices", "flipped_faces", "doublets", "valence_two", "paired_triangles",
                                 "stray_components") if r.get(k)}
    valence = np.bincount(mesh.face_vertices, minlength=mesh.points.shape[0])
    print(f"{name:21s} {len(triangles):6d} tri | ask {faces:5d} remesh {r['remeshed_faces']:5d} ({r['remeshes']}x, "
          f"{r['remesh_seconds']:.2f} s) -> {mesh.n_faces:5d} faces, {np.count_nonzero(valence != 4)} irregular v, "
          f"{seconds:.2f} s | cleanup {changed or '-'} | creases {r['crease_edges']} | build {build:.2f} s, "
          f"repairs {repaired or 'none'}, G1 {jump:.1e} rad | {surface.n_patches} patches, {surface.refinements} DS steps, "
          f"{cad_faces(surface)} CAD faces | unfitted RMS {np.sqrt(np.mean(d ** 2)):.1e} p99 {np.percentile(d, 99):.1e} "
          f"max {d.max():.1e}", flush=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--faces", type=int, nargs="+", default=[500, 1000, 2000])
    parser.add_argument("--scans", nargs="+", default=list(NAMES))
    parser.add_argument("--crease-angle", type=float, default=None, help="for wingnut only (default: none)")
    args = parser.parse_args()
    for name in args.scans:
        for faces in args.faces:
            measure(name, faces, args.crease_angle if name == "wingnut" else None)


if __name__ == "__main__":
    main()
