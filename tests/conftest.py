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


def weighted_cube(tmp_path, rational: bool):
    """sample_meshes/cube.obj written with OBJ vertex weights (v x y z w), differing from 1 where ``rational``."""
    mesh = read_obj(SAMPLES / "cube.obj")
    weights = np.linspace(0.5, 2.0, mesh.n_vertices) if rational else np.ones(mesh.n_vertices)
    source = tmp_path / "cube.obj"
    offsets = mesh.face_offsets()
    source.write_text("".join(f"v {x!r} {y!r} {z!r} {w!r}\n" for (x, y, z), w in zip(mesh.points.tolist(), weights.tolist()))
                      + "".join("f " + " ".join(str(v + 1) for v in mesh.face_vertices[a:b]) + "\n"
                                for a, b in zip(offsets[:-1], offsets[1:])))
    return source


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


def single_polygon(n):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return polygon_mesh([list(range(n))], np.c_[np.cos(a), np.sin(a), 0.05 * np.cos(2 * a)])


def slab_with_polygons():
    """A box whose top (z = 1) is a 6 x 6 grid with a merged octagon and hexagon."""
    n = 6
    xs = np.linspace(-1, 1, n + 1)
    top = {(i, j): k for k, (i, j) in enumerate((i, j) for i in range(n + 1) for j in range(n + 1))}
    points = [(xs[i], xs[j], 1.0) for i in range(n + 1) for j in range(n + 1)]
    faces = []
    merged = {(2, 2), (2, 3), (3, 2), (3, 3), (0, 4), (0, 5)}
    for i in range(n):
        for j in range(n):
            if (i, j) not in merged:
                faces.append([top[i, j], top[i + 1, j], top[i + 1, j + 1], top[i, j + 1]])
    # octagon around the removed centre vertex (3, 3), counter-clockwise from above
    ring = [(2, 2), (3, 2), (4, 2), (4, 3), (4, 4), (3, 4), (2, 4), (2, 3)]
    faces.append([top[p] for p in ring])
    faces.append([top[p] for p in [(0, 4), (1, 4), (1, 5), (1, 6), (0, 6), (0, 5)]])
    # close with a bottom vertex for every boundary vertex of the top, sides as quads
    boundary = [(i, 0) for i in range(n)] + [(n, j) for j in range(n)] + [(i, n) for i in range(n, 0, -1)] + [(0, j) for j in range(n, 0, -1)]
    base = len(points)
    points += [(xs[i], xs[j], -1.0) for i, j in boundary]
    m = len(boundary)
    for k in range(m):
        a, b = boundary[k], boundary[(k + 1) % m]
        faces.append([top[b], top[a], base + k, base + (k + 1) % m])
    faces.append([base + k for k in range(m)][::-1])
    used = sorted({v for f in faces for v in f})
    remap = {v: k for k, v in enumerate(used)}
    faces = [[remap[v] for v in f] for f in faces]
    points = np.array(points)[used]
    return polygon_mesh(faces, points)


def rational_sphere_patch(radius, centre):
    """Rational biquadratic patch of a sphere: a 90 degree meridian arc (latitude -45..45)
    swept through 90 degrees of longitude (tensor product of two rational quadratic arcs)."""
    s = np.sqrt(0.5)
    meridian = np.array([[s, -s], [2 * s, 0.0], [s, s]])  # (r, z); middle point at 1/cos(45)
    meridian_w = np.array([1.0, s, 1.0])
    sweep = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    sweep_w = np.array([1.0, s, 1.0])
    Q = np.zeros((3, 3, 4))
    for i in range(3):
        for j in range(3):
            w = meridian_w[i] * sweep_w[j]
            x = radius * np.array([meridian[i, 0] * sweep[j, 0], meridian[i, 0] * sweep[j, 1], meridian[i, 1]]) + centre
            Q[i, j] = np.append(x * w, w)
    return Q


# -- Open CASCADE (cadquery-ocp, test extra) ----------------------------------------------


def ocp_shapes(shape, kind) -> list:
    """The sub-shapes of ``shape`` of the TopAbs kind ``kind``, in explorer order."""
    from OCP.TopExp import TopExp_Explorer

    found = []
    explorer = TopExp_Explorer(shape, kind)
    while explorer.More():
        found.append(explorer.Current())
        explorer.Next()
    return found


def read_step(path):
    """The one shape of a STEP file, read by Open CASCADE's STEPControl_Reader."""
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_Reader

    reader = STEPControl_Reader()
    assert reader.ReadFile(str(path)) == IFSelect_RetDone
    assert reader.TransferRoots() >= 1
    return reader.OneShape()
