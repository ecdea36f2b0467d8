"""The seven pure-quad meshes of issue 40, for tests/construction/test_one_step.py: open meshes, C0 creases,
corners and a dart, each of which one Doo-Sabin step serves (docs/sharp-features.md, "One Doo-Sabin step").

Every builder returns ``(face sizes, face vertices, points, SharpFeatures or None)``; the points carry a little
noise (seeded) so that no symmetry hides a mistake.
"""
from __future__ import annotations

import numpy as np

from c1surf.construction.features import SharpFeatures

SHARP = 10.0


def _quads(faces, points, features=None, noise=0.01, seed=0):
    rng = np.random.default_rng(seed)
    points = np.asarray(points, dtype=float)
    points = points + noise * rng.standard_normal(points.shape)
    faces = np.asarray(faces, dtype=np.int64)
    return np.full(len(faces), 4), faces.ravel(), points, features


def _grid_faces(m, n, at):
    return [[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)] for j in range(n) for i in range(m)]


def open_tube(around=8, along=4):
    """A cylinder open at both ends: every rim vertex in two faces (regular with its two ghost quads)."""
    at = lambda i, j: (i % around) + j * around
    a = 2 * np.pi * np.arange(around) / around
    points = [(np.cos(t), np.sin(t), 0.5 * j) for j in range(along + 1) for t in a]
    return _quads(_grid_faces(around, along, at), points)


def windowed_torus(nu=12, nv=8, R=2.0, r=0.7):
    """A regular torus with a 2 x 2 window cut out: the window's corners are rim vertices in three faces
    (valence 5 with their ghost quads), one edge apart from the next corner."""
    u, v = np.meshgrid(2 * np.pi * np.arange(nu) / nu, 2 * np.pi * np.arange(nv) / nv, indexing="ij")
    points = np.c_[((R + r * np.cos(v)) * np.cos(u)).ravel(), ((R + r * np.cos(v)) * np.sin(u)).ravel(),
                   (r * np.sin(v)).ravel()]
    at = lambda i, j: (i % nu) * nv + j % nv
    faces = [[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)] for i in range(nu) for j in range(nv)
             if not (i in (3, 4) and j in (2, 3))]
    used = np.unique(faces)
    renumber = np.full(len(points), -1)
    renumber[used] = np.arange(used.size)
    return _quads(renumber[np.array(faces)], points[used])


def _welding(points: list):
    """``vertex(p)``: the index of point ``p`` in ``points`` (appended when new; equal to 1e-9 means the same)."""
    index = {}

    def vertex(p):
        key = tuple(np.round(p, 9))
        if key not in index:
            index[key] = len(points)
            points.append(np.asarray(p, float))
        return index[key]

    return vertex


def bowl(k=3):
    """An open box (a cube without its top, every face k x k) pushed onto a sphere: four valence-3 vertices at
    the bottom corners; the rim's corners lie in two faces (regular)."""
    points, faces = [], []
    vertex = _welding(points)

    sides = [((0, 0, -1), (0, 1, 0), (1, 0, 0)),  # bottom, seen from below (outside)
             ((1, 0, 0), (0, 1, 0), (0, 0, 1)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
             ((0, 1, 0), (0, 0, 1), (1, 0, 0)), ((0, -1, 0), (1, 0, 0), (0, 0, 1))]
    for normal, du, dv in sides:
        n, du, dv = map(np.array, (normal, du, dv))
        at = lambda i, j: vertex(n + (2 * i / k - 1) * du + (2 * j / k - 1) * dv)
        faces += [[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)] for j in range(k) for i in range(k)]
    points = np.array(points)  # no top face: the rim is the square at z = 1
    sphere = points / np.linalg.norm(points, axis=1, keepdims=True)
    return _quads(faces, 0.5 * points + 0.5 * sphere)


def saddle(m=5, n=4):
    """An open quad grid on z = (x^2 - y^2) / 10: its four corners lie in one face each (valence 3)."""
    at = lambda i, j: i + j * (m + 1)
    points = [(i, j, 0.1 * ((i - m / 2) ** 2 - (j - n / 2) ** 2)) for j in range(n + 1) for i in range(m + 1)]
    return _quads(_grid_faces(m, n, at), points)


def _cube_grid(k):
    """A cube [-1, 1]^3 with every face k x k: (faces, points, edges on the cube's 12 edges)."""
    points, faces = [], []
    vertex = _welding(points)

    for axis in range(3):
        for sign in (1, -1):
            n = np.zeros(3)
            n[axis] = sign
            du, dv = np.zeros(3), np.zeros(3)
            du[(axis + 1) % 3], dv[(axis + 2) % 3] = 1, 1
            if sign < 0:
                du, dv = dv, du
            at = lambda i, j: vertex(n + (2 * i / k - 1) * du + (2 * j / k - 1) * dv)
            faces += [[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)] for j in range(k) for i in range(k)]
    points = np.array(points)
    edges = {tuple(sorted((f[q], f[(q + 1) % 4]))) for f in faces for q in range(4)}
    on_edge = lambda e: np.sum(np.isclose(np.abs(points[list(e)]).min(axis=0), 1.0)) >= 2
    return faces, points, np.array(sorted(e for e in edges if on_edge(e)))


def sharp_cube(k=2):
    """A cube with every face k x k and all 12 edges infinitely sharp (C0 seams; corners 1 | 1 | 1)."""
    faces, points, edges = _cube_grid(k)
    return _quads(faces, points, SharpFeatures(edges, np.full(len(edges), SHARP)), noise=0.0)


def tagged_box(k=3):
    """A cube with every face k x k; the four edges of the top face are creases (C0) and two bottom corners
    are infinitely sharp corner tags (off the seams: interpolated)."""
    faces, points, edges = _cube_grid(k)
    top = edges[np.all(np.isclose(points[edges][:, :, 2], 1.0), axis=1)]
    corners = np.flatnonzero(np.all(np.isclose(np.abs(points), 1.0), axis=1) & np.isclose(points[:, 2], -1.0))[:2]
    features = SharpFeatures(top, np.full(len(top), SHARP), corners, np.full(corners.size, SHARP))
    return _quads(faces, points, features)


def half_sharp_roof(m=8, n=6):
    """An open roof z = 1 - |y - n/2| / 2 over an m x n grid whose ridge is sharp from the gable x = 0 to x = m/2,
    where it ends inside the surface (a dart of valence 4)."""
    at = lambda i, j: i + j * (m + 1)
    points = [(i, j, 1 - abs(j - n / 2) / 2) for j in range(n + 1) for i in range(m + 1)]
    ridge = np.array([[at(i, n // 2), at(i + 1, n // 2)] for i in range(m // 2)])
    return _quads(_grid_faces(m, n, at), points, SharpFeatures(ridge, np.full(len(ridge), SHARP)))


KINDS = {"open tube": open_tube, "torus with a window": windowed_torus, "bowl": bowl, "saddle grid": saddle,
         "sharp cube": sharp_cube, "tagged box": tagged_box, "half-sharp roof": half_sharp_roof}
