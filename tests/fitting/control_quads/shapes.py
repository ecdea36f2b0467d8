"""Small triangle meshes for the quad-simplification tests: a torus, a genus-2 shape, a flat outline, a sphere with
three thin limbs (implicit surfaces meshed by pymeshlab's marching cubes, or built by hand)."""
from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial import Delaunay


def outward(points: np.ndarray, triangles: np.ndarray):
    """The mesh with its triangles turned so that a closed one encloses a positive volume."""
    if trimesh.Trimesh(points, triangles, process=False).volume < 0:
        triangles = triangles[:, ::-1]
    return np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(triangles, dtype=np.int64)


def torus(nu: int = 80, nv: int = 40, big: float = 1.0, small: float = 0.35):
    """A torus triangulated from a (nu, nv) grid: 2 nu nv triangles."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, nu, endpoint=False), np.linspace(0, 2 * np.pi, nv, endpoint=False),
                       indexing="ij")
    points = np.stack([(big + small * np.cos(v)) * np.cos(u), (big + small * np.cos(v)) * np.sin(u),
                       small * np.sin(v)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * nv + j, ((i + 1) % nu) * nv + j
    c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
    triangles = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return outward(points, triangles)


def implicit(expression: str, box: float, voxel: float):
    """The zero set of a muparser ``expression`` in x, y, z over [-box, box]^3, meshed by marching cubes."""
    import pymeshlab

    meshes = pymeshlab.MeshSet()
    meshes.create_implicit_surface(voxelsize=voxel, expr=expression, minx=-box, miny=-box, minz=-box, maxx=box,
                                   maxy=box, maxz=box)
    meshes.meshing_remove_duplicate_vertices()
    mesh = meshes.current_mesh()
    return outward(mesh.vertex_matrix(), mesh.face_matrix())


def genus_two(voxel: float = 0.06):
    """A genus-2 surface: (x (x - 1)^2 (x - 2) + y^2)^2 + z^2 = 0.03, shifted to the origin."""
    return implicit("((x+1)*x*x*(x-1) + y*y)^2 + z*z - 0.03", 1.7, voxel)


def limbs(voxel: float = 0.065, radius: float = 0.11):
    """A unit sphere with three limbs of ``radius`` reaching out to 1.9 along x, y and -z."""
    capsule = "(sqrt({a}^2 + {b}^2) - {r})"
    x_limb = capsule.format(a="y", b="z", r=radius) + " + (x < 0) * 10 + (x > 1.9) * 10"
    y_limb = capsule.format(a="x", b="z", r=radius) + " + (y < 0) * 10 + (y > 1.9) * 10"
    z_limb = capsule.format(a="x", b="y", r=radius) + " + (z > 0) * 10 + (z < -1.9) * 10"
    expression = f"min(min(sqrt(x*x + y*y + z*z) - 1, {x_limb}), min({y_limb}, {z_limb}))"
    return implicit(expression, 2.1, voxel)


def flat_outline(spacing: float = 0.035, lobes: int = 5):
    """A planar outline r = 1 + 0.2 cos(lobes theta), Delaunay-triangulated from a hexagonal grid (about 6k
    triangles at the default spacing)."""
    theta = np.linspace(0, 2 * np.pi, int(2 * np.pi * 1.1 / spacing), endpoint=False)
    radius = 1 + 0.2 * np.cos(lobes * theta)
    rim = np.stack([radius * np.cos(theta), radius * np.sin(theta)], 1)
    x, y = np.meshgrid(np.arange(-1.3, 1.3, spacing), np.arange(-1.3, 1.3, spacing * np.sqrt(3) / 2))
    x = x + (np.arange(x.shape[0])[:, None] % 2) * spacing / 2
    grid = np.stack([x.ravel(), y.ravel()], 1)
    r, t = np.hypot(grid[:, 0], grid[:, 1]), np.arctan2(grid[:, 1], grid[:, 0])
    grid = grid[r < 1 + 0.2 * np.cos(lobes * t) - 0.6 * spacing]
    plane = np.concatenate([rim, grid])
    triangles = Delaunay(plane).simplices
    centre = plane[triangles].mean(axis=1)
    r, t = np.hypot(centre[:, 0], centre[:, 1]), np.arctan2(centre[:, 1], centre[:, 0])
    triangles = triangles[r < 1 + 0.2 * np.cos(lobes * t)]
    a, b, c = plane[triangles[:, 0]], plane[triangles[:, 1]], plane[triangles[:, 2]]
    flip = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    triangles[flip] = triangles[flip][:, ::-1]
    points = np.concatenate([plane, np.zeros((plane.shape[0], 1))], axis=1)
    return points, triangles.astype(np.int64)
