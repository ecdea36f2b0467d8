"""The ripple of mean curvature around a dart: c1surf's C0 dart against Catmull-Clark's dart rule.

Run from the repository root: ``python docs/research/dart_ripple.py``. The mesh: a disk of quads around a
dart of valence n (``tests/construction/dart_meshes.polar_dart``, 4 rings, no noise) on the valley
z = |y|, whose bottom line is tagged infinitely sharp from the dart to the boundary (+x). Compared:

- c1surf with C0 creases (the dart's hole); exact mean curvature H on a 6 x 6 grid of cell centres per patch;
- the same with ``--g1-creases`` (the sharpest G1 crease, what darts were before session 9);
- Catmull-Clark with Hoppe et al.'s sharp rules (a sharp or boundary edge's point is its midpoint; a vertex
  on two sharp or boundary edges takes (6 v + a + b) / 8, on three or more stays; a dart, on one, is smooth,
  as in OpenSubdiv), 4 levels, H from the cotangent Laplacian (``bench/fit.py``).

rho (``bench/fit.py``: L x the area-RMS of H less its area-weighted mean within half an input edge) is taken
over the samples inside the dart's ring (within 1.2 input edges of the dart) and away from the crease line
(|y| > 0.15 where x > 0), where any surface has H unbounded or undefined.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "construction"), str(ROOT / "bench")]

from dart_meshes import polar_dart  # noqa: E402
from fit import cotangent_mean_curvature, ripple, sampler_samples  # noqa: E402

from c1surf.construction.surface import Surface, SurfaceOptions  # noqa: E402
from c1surf.evaluation.curvature import PatchSampler  # noqa: E402


def surface_samples(surface: Surface, n: int = 6):
    """(points, H, area weights) on an n x n grid of cell centres of every patch (``bench/fit.py``'s sampling)."""
    return sampler_samples(PatchSampler([surface.biquadratic, surface.bicubic]), n)


def catmull_clark(points, faces, sharp, levels: int):
    """Catmull-Clark with sharp edges (module docstring); faces: list of vertex lists; sharp: set of sorted pairs."""
    for _ in range(levels):
        edge_faces, vertex_faces, vertex_edges = {}, {}, {}
        for f, face in enumerate(faces):
            for i, a in enumerate(face):
                b = face[(i + 1) % len(face)]
                e = (min(a, b), max(a, b))
                edge_faces.setdefault(e, []).append(f)
                vertex_faces.setdefault(a, []).append(f)
                vertex_edges.setdefault(a, set()).add(e)
                vertex_edges.setdefault(b, set()).add(e)
        face_point = np.array([points[face].mean(axis=0) for face in faces])
        hard = {e for e, fs in edge_faces.items() if e in sharp or len(fs) == 1}
        edges = list(edge_faces)
        edge_index = {e: len(points) + len(faces) + k for k, e in enumerate(edges)}
        edge_point = []
        for e in edges:
            mid = (points[e[0]] + points[e[1]]) / 2
            edge_point.append(mid if e in hard else (mid * 2 + face_point[edge_faces[e]].sum(axis=0)) / 4)
        new_vertices = points.copy()
        for v in range(len(points)):
            around = vertex_edges.get(v, set())
            hard_here = [e for e in around if e in hard]
            if len(hard_here) >= 3:
                continue
            if len(hard_here) == 2:
                a, b = (e[0] if e[1] == v else e[1] for e in hard_here)
                new_vertices[v] = (6 * points[v] + points[a] + points[b]) / 8
                continue
            k = len(around)
            Q = face_point[vertex_faces[v]].mean(axis=0)
            R = np.mean([(points[e[0]] + points[e[1]]) / 2 for e in around], axis=0)
            new_vertices[v] = (Q + 2 * R + (k - 3) * points[v]) / k
        points = np.concatenate([new_vertices, face_point, np.array(edge_point)])
        new_faces, new_sharp = [], set()
        for f, face in enumerate(faces):
            for i, a in enumerate(face):
                b, z = face[(i + 1) % len(face)], face[i - 1]
                new_faces.append([a, edge_index[(min(a, b), max(a, b))], len(new_vertices) + f,
                                  edge_index[(min(z, a), max(z, a))]])
        for e in sharp:
            if e in edge_index:
                m = edge_index[e]
                new_sharp |= {(min(e[0], m), max(e[0], m)), (min(e[1], m), max(e[1], m))}
        faces, sharp = new_faces, new_sharp
    return points, faces


def region(points, centre):
    """Samples in the dart's ring, away from the crease line."""
    d = points - centre
    near = np.linalg.norm(d[:, :2], axis=1) < 1.2
    off_crease = ~((d[:, 0] > 0) & (np.abs(d[:, 1]) < 0.15))
    return near & off_crease


def main() -> None:
    print("| dart's valence | c1surf C0 dart | c1surf, sharpest G1 crease | Catmull-Clark, dart rule (4 levels) |"
          " c1surf, no crease | Catmull-Clark, no crease |")
    print("|---|---|---|---|---|---|")
    for n in (3, 4, 5, 6, 8):
        points, sizes, corners, features, dart = polar_dart([2] * n, rings=4, noise=0.0)
        centre = points[dart]
        row = []
        for exact in (True, False):
            surface = Surface(sizes, corners, points, SurfaceOptions(exact_creases=exact), features=features)
            x, H, w = surface_samples(surface)
            keep = region(x, centre)
            row.append(ripple(x[keep], H[keep], w[keep], 0.5))
        faces = np.split(corners, np.cumsum(sizes)[:-1])
        sharp = {tuple(sorted(map(int, e))) for e in features.crease_edges}
        row.append(cc_ripple(points, faces, sharp, centre))
        x, H, w = surface_samples(Surface(sizes, corners, points))
        keep = region(x, centre)
        row.append(ripple(x[keep], H[keep], w[keep], 0.5))
        row.append(cc_ripple(points, faces, set(), centre))
        print(f"| {n} | " + " | ".join(f"{r:.3f}" for r in row) + " |")


def cc_ripple(points, faces, sharp, centre) -> float:
    p, f = catmull_clark(points.copy(), [list(map(int, face)) for face in faces], sharp, 4)
    triangles = np.array([[q[0], q[1], q[2]] for q in f] + [[q[0], q[2], q[3]] for q in f])
    H, area = cotangent_mean_curvature(p, triangles)
    keep = region(p, centre)
    return ripple(p[keep], H[keep], area[keep], 0.5)


if __name__ == "__main__":
    main()
