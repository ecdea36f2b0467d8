"""CAD-like triangle meshes made in the tests: feature lines that only a crease angle finds."""
from __future__ import annotations

import numpy as np


class _Builder:
    """Vertices by position (shared exactly where two grids meet) and triangles."""

    def __init__(self):
        self.index, self.points, self.faces = {}, [], []

    def vertex(self, p) -> int:
        key = tuple(np.round(np.asarray(p, dtype=float), 10) + 0.0)
        if key not in self.index:
            self.index[key] = len(self.points)
            self.points.append(key)
        return self.index[key]

    def grid(self, rows, flip=False, rng=None):
        """Triangulate a grid of point rows (each row a list of points, all rows as long); a random
        diagonal per quad when ``rng`` is given, else alternating."""
        ids = [[self.vertex(p) for p in row] for row in rows]
        for i in range(len(ids) - 1):
            for j in range(len(ids[i]) - 1):
                a, b, c, d = ids[i][j], ids[i][j + 1], ids[i + 1][j + 1], ids[i + 1][j]
                if flip:
                    a, b, c, d = a, d, c, b
                split = rng.random() < 0.5 if rng is not None else (i + j) % 2 == 0
                tris = [(a, b, c), (a, c, d)] if split else [(a, b, d), (b, c, d)]
                self.faces += [t for t in tris if len(set(t)) == 3]

    def mesh(self):
        faces = np.array(self.faces, dtype=np.int64)
        return np.full(len(faces), 3, dtype=np.int64), faces.ravel(), np.array(self.points)


def boss_box(m: int = 4, seed: int | None = 0):
    """A box [-1, 1]^2 x [-0.6, 0] with a cylindrical boss on its top, blended in by a concave fillet,
    as a CAD tessellator would triangulate it: (face_sizes, face_vertices, points), all triangles.

    Feature lines at 90 degrees: the box's 12 edges and the boss's top rim; everything else (the top
    face, the fillet, the wall, the boss's top) meets at less than 25 degrees per edge. ``m``: segments
    per box edge (the boss has 4 m around); ``seed``: random diagonals (None: alternating).
    """
    rng = None if seed is None else np.random.default_rng(seed)
    b = _Builder()
    n = 4 * m
    t = np.arange(n + 1) / m  # around the square: side k covers t in [k, k + 1]
    corners = np.array([[1, -1], [1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float)
    k = np.minimum(t.astype(int), 3)
    square = corners[k] + (t - k)[:, None] * (corners[k + 1] - corners[k])
    angle = np.arctan2(square[:, 1], square[:, 0])
    unit = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    r_wall, r_fillet, height, depth = 0.45, 0.7, 0.4, 0.6
    f = r_fillet - r_wall
    rows = [np.c_[square, np.zeros(n + 1)]]  # top face: square to the fillet's outer circle
    for s in (1 / 3, 2 / 3, 1.0):
        rows.append(np.c_[(1 - s) * square + s * r_fillet * unit, np.zeros(n + 1)])
    for phi in np.linspace(0, np.pi / 2, 5)[1:]:  # the fillet, a quarter circle in (r, z)
        rows.append(np.c_[(r_fillet - f * np.sin(phi)) * unit, np.full(n + 1, f - f * np.cos(phi))])
    for z in np.linspace(f, height, 4)[1:]:
        rows.append(np.c_[r_wall * unit, np.full(n + 1, z)])
    for r in (0.3, 0.15):  # the boss's top disk
        rows.append(np.c_[r * unit, np.full(n + 1, height)])
    b.grid([list(map(tuple, row)) for row in rows], rng=rng)
    centre = b.vertex((0.0, 0.0, height))
    last = [b.vertex(p) for p in rows[-1]]
    b.faces += [(last[j], last[j + 1], centre) for j in range(n)]
    for side in range(4):  # the box's sides and bottom: grids matching the top face's edge
        top = square[side * m : side * m + m + 1]
        levels = np.linspace(0, -depth, m + 1)
        b.grid([[(x, y, z) for x, y in top] for z in levels], flip=True, rng=rng)
    xs = np.linspace(-1, 1, m + 1)
    b.grid([[(x, y, -depth) for x in xs] for y in xs], flip=True, rng=rng)
    return b.mesh()


def write_obj(path, face_sizes, face_vertices, points) -> None:
    """A plain OBJ of the mesh (vertices from 1)."""
    faces = np.split(np.asarray(face_vertices) + 1, np.cumsum(face_sizes)[:-1])
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in points] + ["f " + " ".join(map(str, f)) for f in faces]
    path.write_text("\n".join(lines) + "\n")
