"""Every local operation keeps a valid pure-quad mesh and its topology (issue 43's first acceptance point).

Random sequences of operations (hypothesis) on small meshes with and without rims: a closed cube-sphere, a torus,
a disc (one rim) and an annulus (two rims). After every operation, kept or refused, the mesh is checked by
``validity.quad_mesh_problems`` (plain numpy, independent of the compiled link test) and its components, Euler
characteristic and rims by ``mesh.topology_counts``. The geometric guards are switched off here (no corner bound,
no fold test, no edge limit) so that the topology checks alone decide, over as many configurations as possible.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from c1surf.fitting.control.quads import operations
from c1surf.fitting.control.quads.quad_mesh import QuadMesh
from c1surf.fitting.control.quads.validity import quad_mesh_problems, quad_topology


def grid(nu: int, nv: int, wrap_u: bool, wrap_v: bool):
    """(quads, points) of an nu x nv grid of quads, glued along u and/or v (annulus, torus) or not (disc)."""
    cols, rows = nu + (0 if wrap_u else 1), nv + (0 if wrap_v else 1)
    index = lambda i, j: (i % cols) * rows + (j % rows)  # noqa: E731
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    quads = np.stack([index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)], -1).reshape(-1, 4)
    u, v = np.meshgrid(np.arange(cols) / cols, np.arange(rows) / rows, indexing="ij")
    u, v = u.ravel() * 2 * np.pi, v.ravel() * 2 * np.pi
    if wrap_u and wrap_v:
        points = np.stack([(2 + np.cos(v)) * np.cos(u), (2 + np.cos(v)) * np.sin(u), np.sin(v)], 1)
    elif wrap_u:
        radius = 1 + v / (2 * np.pi)
        points = np.stack([radius * np.cos(u), radius * np.sin(u), 0 * u], 1)
    else:
        points = np.stack([u, v, 0.1 * np.sin(u + v)], 1)
    return quads, points


def cube_sphere(n: int):
    """(quads, points): the six faces of a cube cut n x n, outward, on the unit sphere."""
    ticks = np.linspace(-1, 1, n + 1)
    quads, points, lookup = [], [], {}

    def vertex(p):
        key = tuple(np.round(p, 9))
        if key not in lookup:
            lookup[key] = len(points)
            points.append(p)
        return lookup[key]

    for axis in range(3):
        for sign in (-1, 1):
            for a in range(n):
                for b in range(n):
                    corners = []
                    for da, db in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = np.zeros(3)
                        p[axis] = sign
                        p[(axis + 1) % 3], p[(axis + 2) % 3] = ticks[a + da], ticks[b + db]
                        corners.append(vertex(p))
                    quads.append(corners if sign > 0 else corners[::-1])
    points = np.array(points)
    return np.array(quads), points / np.linalg.norm(points, axis=1, keepdims=True)


def with_doublets(quads, points, faces):
    """(quads, points): each quad (a, b, c, d) of ``faces`` cut along its diagonal a - c by a new vertex v at its
    centre into (v, a, b, c) and (v, c, d, a): v is a doublet (an interior vertex of valence 2)."""
    quads, points = [list(q) for q in quads], list(points)
    for f in faces:
        a, b, c, d = quads[f]
        v = len(points)
        points.append(np.mean([points[i] for i in (a, b, c, d)], axis=0))
        quads[f] = [v, a, b, c]
        quads.append([v, c, d, a])
    return np.array(quads), np.array(points)


MESHES = {"sphere": cube_sphere(3), "torus": grid(8, 6, True, True), "disc": grid(5, 4, False, False),
          "annulus": grid(10, 3, True, False), "doublets": with_doublets(*grid(8, 6, True, True), [3, 20, 40])}


def _apply(mesh: QuadMesh, step) -> None:
    """One operation of ``step`` (kind, face pick, corner, turn) on ``mesh``, topology checks alone."""
    kind, pick, k, turn = step
    live = np.flatnonzero(mesh.alive)
    face = int(live[pick % live.size])
    n_faces, n_points = mesh.quads.shape[0], mesh.points.shape[0]
    common = (mesh.state(), (np.full(n_points, np.inf), np.array([-1.0, -2.0]), np.zeros(n_faces, dtype=bool)))
    if kind == 0:
        operations.collapse_diagonal(*common, face, k % 2)
    elif kind == 1:
        operations.rotate_edge(*common, face, k, turn)
    elif kind == 2:  # a vertex in two faces where there is one (a doublet, or a rim vertex), else a corner
        two = np.flatnonzero(mesh.counts == 2)
        operations.remove_doublet(*common, int(two[pick % two.size]) if two.size else int(mesh.quads[face, k]))
    else:
        operations.collapse_polychord(*common, face, k, (np.empty(n_faces, dtype=np.int64),
                                      np.empty((n_faces + 1, 2), dtype=np.int64), np.full(n_points, -1, np.int64)))


STEPS = st.lists(st.tuples(st.integers(0, 3), st.integers(0, 10_000), st.integers(0, 3), st.sampled_from([-1, 1])),
                 min_size=1, max_size=25)


@pytest.mark.parametrize("name", sorted(MESHES))
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(steps=STEPS)
def test_random_operations_keep_a_valid_quad_mesh_and_its_topology(name, steps):
    quads, points = MESHES[name]
    want = quad_topology(quads, points.shape[0])
    assert quad_mesh_problems(quads, points.shape[0]) == []
    mesh = QuadMesh.from_quads(quads, points)
    for step in steps:
        _apply(mesh, step)
        live = mesh.live_quads()
        assert quad_mesh_problems(live, mesh.points.shape[0]) == [], step
        assert quad_topology(live, mesh.points.shape[0]) == want, step
        # the vertex-face table is the live faces' own
        counts = np.bincount(live.ravel(), minlength=mesh.points.shape[0])
        assert np.array_equal(counts, mesh.counts)


def test_each_operation_does_something_on_a_torus():
    """The four operations are not refused wholesale: a diagonal collapse, a turn, a strip and the doublet a collapse
    at a valence-3 corner leaves (made here on purpose) each change the face count as they should."""
    quads, points = grid(8, 6, True, True)
    mesh = QuadMesh.from_quads(quads, points)
    n_faces, n_points = mesh.quads.shape[0], mesh.points.shape[0]
    common = (mesh.state(), (np.full(n_points, np.inf), np.array([np.cos(np.radians(179)), -0.5]),
                             np.zeros(n_faces, dtype=bool)))
    assert operations.collapse_polychord(*common, 0, 0, (np.empty(n_faces, np.int64),
                                         np.empty((n_faces + 1, 2), np.int64), np.full(n_points, -1, np.int64))) > 0
    assert mesh.n_faces == 48 - 8 or mesh.n_faces == 48 - 6
    before = mesh.n_faces
    assert operations.collapse_diagonal(*common, int(np.flatnonzero(mesh.alive)[10]), 0)
    assert mesh.n_faces == before - 1
    valence = np.bincount(mesh.live_quads().ravel(), minlength=n_points)
    assert sorted(np.bincount(valence[valence > 0]).nonzero()[0].tolist()) == [3, 4, 6]
    assert quad_topology(mesh.live_quads(), n_points) == (1, 0, 0)


def test_doublets_are_removed_and_never_made():
    """A doublet (``with_doublets``) is dissolved into one quad; and the link test refuses every collapse that would
    leave one (two faces meeting at two vertices that are not an edge), so after any operation there is none new."""
    quads, points = with_doublets(*grid(8, 6, True, True), [3, 20, 40])
    mesh = QuadMesh.from_quads(quads, points)
    n_faces, n_points = mesh.quads.shape[0], mesh.points.shape[0]
    common = (mesh.state(), (np.full(n_points, np.inf), np.array([-1.0, -2.0]), np.zeros(n_faces, dtype=bool)))
    doublets = np.flatnonzero(mesh.counts == 2)
    assert doublets.size == 3
    for v in doublets:
        assert operations.remove_doublet(*common, int(v))
    assert mesh.n_faces == 48 and not np.any(mesh.counts == 2)
    assert quad_mesh_problems(mesh.live_quads(), n_points) == []
    # every diagonal collapse that would leave a valence-2 vertex is refused
    for face in np.flatnonzero(mesh.alive)[:20]:
        operations.collapse_diagonal(*common, int(face), 0)
        assert not np.any(mesh.counts == 2)
