"""Shared fixtures: where the meshes are, and building surfaces from files."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.io.meshes.obj import read_obj

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "sample_meshes"
SHARED_MESHES = ROOT.parent / "shared" / "meshes"

CLOSED_SAMPLES = sorted(p.name for p in SAMPLES.glob("*.obj"))

# Closed, orientable, manifold meshes of ../shared/meshes with no valence-2
# vertex and no degenerate face (MANIFEST notes without open / non-manifold /
# valence-2 / degenerate / pinch / inconsistent / unused).
CLOSED_SHARED = [
    "odedstein-meshes/fish_control_mesh.obj",
    "odedstein-meshes/penguin_control_mesh.obj",
    "odedstein-meshes/sword-quad-dominant.obj",
    "opensubdiv/bilinear_cube.obj",
    "opensubdiv/catmark_chaikin0.obj",
    "opensubdiv/catmark_chaikin1.obj",
    "opensubdiv/catmark_cube.obj",
    "opensubdiv/catmark_cube_corner0.obj",
    "opensubdiv/catmark_cube_corner1.obj",
    "opensubdiv/catmark_cube_corner2.obj",
    "opensubdiv/catmark_cube_corner3.obj",
    "opensubdiv/catmark_cube_corner4.obj",
    "opensubdiv/catmark_cube_creases0.obj",
    "opensubdiv/catmark_cube_creases1.obj",
    "opensubdiv/catmark_cube_creases2.obj",
    "opensubdiv/catmark_cubes_infsharp.obj",
    "opensubdiv/catmark_cubes_semisharp.obj",
    "opensubdiv/catmark_hole_test1.obj",
    "opensubdiv/catmark_lefthanded.obj",
    "opensubdiv/catmark_pyramid.obj",
    "opensubdiv/catmark_pyramid_creases0.obj",
    "opensubdiv/catmark_pyramid_creases1.obj",
    "opensubdiv/catmark_pyramid_creases2.obj",
    "opensubdiv/catmark_righthanded.obj",
    "opensubdiv/catmark_smoothtris0.obj",
    "opensubdiv/catmark_smoothtris1.obj",
    "opensubdiv/catmark_toroidal_tet.obj",
    "opensubdiv/catmark_torus.obj",
    "opensubdiv/catmark_torus_creases0.obj",
    "opensubdiv/catmark_torus_creases1.obj",
    "pmp-library/chamfer-cube.obj",
    "pmp-library/fandisk_quads.obj",
    "polyhedra-viewer/bilunabirotunda.obj",
    "polyhedra-viewer/decagonal-antiprism.obj",
    "polyhedra-viewer/dodecahedron.obj",
    "polyhedra-viewer/elongated-pentagonal-gyrocupolarotunda.obj",
    "polyhedra-viewer/gyrobifastigium.obj",
    "polyhedra-viewer/metabidiminished-rhombicosidodecahedron.obj",
    "polyhedra-viewer/octagonal-prism.obj",
    "polyhedra-viewer/pentagonal-rotunda.obj",
    "polyhedra-viewer/snub-cube.obj",
    "polyhedra-viewer/snub-dodecahedron.obj",
    "polyhedra-viewer/triangular-hebesphenorotunda.obj",
    "polyhedra-viewer/truncated-cuboctahedron.obj",
    "polyhedra-viewer/truncated-dodecahedron.obj",
    "polyhedra-viewer/truncated-icosahedron.obj",
    "polyhedra-viewer/truncated-icosidodecahedron.obj",
    "spot/spot_control_mesh.obj",
    "spot/spot_quadrangulated.obj",
]


def shared_mesh(relative: str) -> Path:
    """Path of a ../shared/meshes file; skips the test where shared/ is absent."""
    path = SHARED_MESHES / relative
    if not path.exists():
        pytest.skip(f"{path} not available")
    return path


def surface_of(path, **options) -> Surface:
    """Build the surface of an OBJ file with SurfaceOptions(**options)."""
    mesh = read_obj(path)
    return Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(**options))


def polygon_mesh(faces, points):
    """(face_sizes, face_vertices, points) from a list of faces."""
    return np.array([len(f) for f in faces]), np.concatenate([np.asarray(f) for f in faces]), np.asarray(points, float)


# -- small open meshes (tests of boundaries) ----------------------------------------------


def grid(n, height=lambda x, y: 0.0 * x):
    """An n x n quad grid, open."""
    x, y = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="ij")
    points = np.c_[x.ravel(), y.ravel(), height(x, y).ravel()]
    k = lambda i, j: i * (n + 1) + j  # noqa: E731
    faces = [[k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j + 1)] for i in range(n) for j in range(n)]
    return polygon_mesh(faces, points)


def fan(n, apex=0.4):
    """n triangles around a centre vertex of valence n (a disk)."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    points = np.r_[[[0, 0, apex]], np.c_[np.cos(a), np.sin(a), 0.1 * np.sin(3 * a)]]
    return polygon_mesh([[0, 1 + i, 1 + (i + 1) % n] for i in range(n)], points)


def open_cylinder(n=10, rows=3):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    points = np.concatenate([np.c_[np.cos(a), np.sin(a), np.full(n, z)] for z in range(rows + 1)])
    faces = [[r * n + i, r * n + (i + 1) % n, (r + 1) * n + (i + 1) % n, (r + 1) * n + i] for r in range(rows) for i in range(n)]
    return polygon_mesh(faces, points)


def misprinted_bicubic(surface: Surface) -> np.ndarray:
    """``surface.bicubic`` with the transcription's misprinted P_12 (NOTES item 1) in every patch."""
    x = surface.refined_points
    bad = surface.bicubic.copy()
    start = 0
    for g in surface.holes:
        A, B1, B2, C = (x[idx] for idx in (g.A, g.B1, g.B2, g.C))
        c = np.cos(2 * np.pi / g.n)
        a = c / (1 - c)
        B2_prev, C_prev = np.roll(B2, 1, axis=1), np.roll(C, 1, axis=1)
        misprint = (5 * B1 + 5 * C_prev + B2_prev + 25 * C) / 36 + a / 36 * (-11 * B1 + 3 * B2_prev + 3 * C_prev + 5 * C)
        count = g.cells.size * g.n
        bad[start : start + count, 1, 2] = misprint.reshape(-1, 3)
        start += count
    return bad
