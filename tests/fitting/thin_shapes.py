"""Small scans with thin parts, small holes and pinches, built in code (issue 39's tests).

``horned``: a unit icosphere with horns and, through a neck far thinner still, a second ball. A horn is a tube
grown from the one-ring of a sphere vertex (the ring's 6 vertices are its first ring), its rings shrinking to a
fraction of the ring's diameter and capped by an apex; the neck is such a tube joining a one-ring of each ball.
"""
from __future__ import annotations

import numpy as np
import trimesh


def _one_ring_hole(mesh: trimesh.Trimesh, direction):
    """(kept triangles, the boundary loop (6,) of the hole left by removing the one-ring of the vertex of valence
    6 nearest ``direction``, ordered along the hole's open half-edges)."""
    points, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    valence = np.bincount(faces.ravel(), minlength=len(points))
    unit = points / np.linalg.norm(points, axis=1, keepdims=True)
    score = unit @ (np.asarray(direction, float) / np.linalg.norm(direction))
    score[valence != 6] = -2
    v = int(np.argmax(score))
    ring = np.any(faces == v, axis=1)
    # the ring's outer edges (b -> c of each triangle v -> b -> c), in the triangles' orientation: the loop runs
    # the way the hole's rim does seen from the kept faces reversed; the tube takes them as they are
    nxt = {}
    for f in faces[ring]:
        k = int(np.flatnonzero(f == v)[0])
        b, c = f[(k + 1) % 3], f[(k + 2) % 3]
        nxt[int(b)] = int(c)
    loop = [next(iter(nxt))]
    while len(loop) < len(nxt):
        loop.append(nxt[loop[-1]])
    return faces[~ring], np.array(loop)


def _tube(rings: list, first_index: int):
    """Triangles joining consecutive rings (lists of vertex indices of equal length, same orientation)."""
    tris = []
    for r0, r1 in zip(rings[:-1], rings[1:]):
        n = len(r0)
        for j in range(n):
            a, b, c, d = r0[j], r0[(j + 1) % n], r1[(j + 1) % n], r1[j]
            tris += [(a, b, c), (a, c, d)]
    return tris


def horned(horns=((1, 0, 0.3), (0, 1, 0.5), (-0.6, 0.7, 0), (0, -1, 0.4), (0.2, 0.3, 1)), horn_scale=0.35,
           neck_scale=0.04, subdivisions=3):
    """(points, triangles): a unit icosphere (radius 1) with a horn 0.8 long along each of ``horns`` (its
    diameter ``horn_scale`` times a one-ring's, about 0.1 at ``subdivisions`` 3), and a ball of radius 0.5 at
    (-2.2, 0, 0) joined to it by a neck 0.7 long of ``neck_scale`` times a one-ring's diameter (about 0.01)."""
    body = trimesh.creation.icosphere(subdivisions, radius=1.0)
    points = [np.asarray(body.vertices)]
    faces = np.asarray(body.faces)
    triangles = []
    count = len(points[0])
    for direction in horns:
        faces, loop = _one_ring_hole(trimesh.Trimesh(points[0], faces, process=False), direction)
        ring = points[0][loop]
        centre, axis = ring.mean(axis=0), ring.mean(axis=0) / np.linalg.norm(ring.mean(axis=0))
        rings = [list(loop)]
        for step, (height, scale) in enumerate(((0.05, 0.6), (0.15, horn_scale), (0.5, horn_scale * 0.8),
                                               (0.8, horn_scale * 0.5))):
            points.append(centre + height * axis + scale * (ring - centre))
            rings.append(list(range(count, count + len(loop))))
            count += len(loop)
        points.append((centre + 0.9 * axis)[None])
        apex = count
        count += 1
        triangles += _tube(rings, 0)
        last = rings[-1]
        triangles += [(last[j], last[(j + 1) % len(last)], apex) for j in range(len(last))]
    # the second ball and the neck
    ball = trimesh.creation.icosphere(subdivisions, radius=0.5)
    ball_points = np.asarray(ball.vertices) + [-2.2, 0, 0]
    faces, loop_a = _one_ring_hole(trimesh.Trimesh(points[0], faces, process=False), (-1, 0.05, 0.02))
    ball_faces, loop_b = _one_ring_hole(ball, (1, 0.05, 0.02))
    offset = count
    points.append(ball_points)
    count += len(ball_points)
    ring_a, ring_b = points[0][loop_a], ball_points[loop_b]
    # the ball's loop runs the other way round the neck: reversed, and turned to the vertex nearest a's first
    loop_b = loop_b[::-1]
    ring_b = ring_b[::-1]
    shift = int(np.argmin(np.linalg.norm((ring_b - ring_b.mean(0)) - (ring_a[0] - ring_a.mean(0)), axis=1)))
    loop_b, ring_b = np.roll(loop_b, -shift), np.roll(ring_b, -shift, axis=0)
    ca, cb = ring_a.mean(axis=0), ring_b.mean(axis=0)
    rings = [list(loop_a)]
    for t, scale in ((0.08, 0.5), (0.2, neck_scale), (0.5, neck_scale), (0.8, neck_scale), (0.92, 0.5)):
        shape = (1 - t) * (ring_a - ca) + t * (ring_b - cb)
        points.append((1 - t) * ca + t * cb + scale * shape)
        rings.append(list(range(count, count + len(loop_a))))
        count += len(loop_a)
    rings.append(list(loop_b + offset))
    triangles += _tube(rings, 0)
    all_points = np.concatenate(points)
    all_triangles = np.concatenate([faces, np.asarray(triangles), ball_faces + offset])
    return _outward(all_points, all_triangles)


def _outward(points, triangles):
    """The mesh with consistent outward faces (trimesh's fix_normals), unused vertices dropped."""
    mesh = trimesh.Trimesh(points, triangles, process=False)
    trimesh.repair.fix_normals(mesh, multibody=True)
    used, inverse = np.unique(np.asarray(mesh.faces), return_inverse=True)
    return np.asarray(mesh.vertices)[used], inverse.reshape(-1, 3)


def holed_sheet(n=48, holes=((0.2, 0.25), (0.5, 0.7), (0.75, 0.3), (0.3, 0.75), (0.8, 0.8)), radius=0.045):
    """(points, triangles): the unit square, gently curved (z = 0.1 sin(pi x) sin(pi y)), in n x n cells of two
    triangles, with the triangles whose centroid lies within ``radius`` of each of ``holes`` removed: five holes."""
    t = np.linspace(0.0, 1.0, n + 1)
    x, y = np.meshgrid(t, t, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), 0.1 * np.sin(np.pi * x.ravel()) * np.sin(np.pi * y.ravel())], axis=1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    v = (i * (n + 1) + j).ravel()
    triangles = np.concatenate([np.stack([v, v + n + 1, v + n + 2], 1), np.stack([v, v + n + 2, v + 1], 1)])
    centre = points[triangles].mean(axis=1)[:, :2]
    keep = np.ones(len(triangles), dtype=bool)
    for h in holes:
        keep &= np.linalg.norm(centre - h, axis=1) > radius
    used, inverse = np.unique(triangles[keep], return_inverse=True)
    return points[used], inverse.reshape(-1, 3)


def pinched_pair(subdivisions=3):
    """(points, triangles): two unit icospheres touching at one shared vertex (a pinched vertex) and a separate
    small sphere of radius 0.15 at (0, 2.5, 0): as read 2 vertex-connected parts, as a manifold 3 spheres."""
    a = trimesh.creation.icosphere(subdivisions, radius=1.0)
    b = trimesh.creation.icosphere(subdivisions, radius=1.0)
    pa = np.asarray(a.vertices)
    top = int(np.argmax(pa[:, 0]))
    pb = np.asarray(b.vertices) * [-1, 1, 1]  # mirrored: its leftmost vertex at x = -1
    fb = np.asarray(b.faces)[:, ::-1]
    low = int(np.argmin(pb[:, 0]))
    pb = pb + (pa[top] - pb[low])
    small = trimesh.creation.icosphere(2, radius=0.15)
    ps = np.asarray(small.vertices) + [0, 2.5, 0]
    nb = len(pb)
    # b's vertex `low` is a's `top`: renumber b without it
    index_b = np.arange(nb) + len(pa)
    index_b[low + 1:] -= 1
    index_b[low] = top
    points = np.concatenate([pa, np.delete(pb, low, axis=0), ps])
    triangles = np.concatenate([np.asarray(a.faces), index_b[fb], np.asarray(small.faces) + len(pa) + nb - 1])
    return points, triangles
