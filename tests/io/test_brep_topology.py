"""The B-rep of a patch set (io/patches/brep/topology.py): faces, shared edges, vertices and loops, checked
against the mesh's topology and against the geometry of the faces themselves."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from c1surf.evaluation.bezier import evaluate_patches_at
from c1surf.evaluation.merge import merge_biquadratic
from c1surf.evaluation.patch_set import surface_patch_set
from c1surf.io.meshes.obj import read_obj
from c1surf.io.patches.brep.topology import FACE_PIECE, brep_topology, edge_curves
from c1surf.io.patches.merged import piece_patches

from conftest import SAMPLES, surface_of, weighted_cube

CLOSED = ["cube", "tetrahedron", "octahedron", "icosahedron", "dodecahedron", "torus", "double_torus", "twisted",
          "high_valence", "triangular_prism", "hexagonal_prism"]


def euler_characteristic(path) -> int:
    mesh = read_obj(path)
    offsets = mesh.face_offsets()
    edges = {tuple(sorted((int(f[i]), int(f[(i + 1) % len(f)]))))
             for f in (mesh.face_vertices[a:b] for a, b in zip(offsets[:-1], offsets[1:])) for i in range(len(f))}
    return mesh.n_vertices - len(edges) + mesh.n_faces


def patch_set_of(path, merge: bool, **options):
    surface = surface_of(path, **options)
    patch_set = surface_patch_set(surface)
    if merge:
        patch_set = dataclasses.replace(patch_set, merged=merge_biquadratic(surface))
    return patch_set


def face_point(patch_set, topology, f: int, uv: np.ndarray) -> np.ndarray:
    """The face's surface at parameters uv (k, 2) of its domain: (k, 3)."""
    index = int(topology.face_index[f])
    if topology.face_kind[f] == FACE_PIECE:
        piece = patch_set.merged[index]
        nets, weights = piece_patches(piece)
        m, n = piece.patches.shape
        i = np.minimum(np.floor(uv[:, 0]).astype(int), m - 1)
        j = np.minimum(np.floor(uv[:, 1]).astype(int), n - 1)
        span, u, v = i * n + j, uv[:, 0] - i, uv[:, 1] - j
    else:
        first = 0
        for k, g in enumerate(patch_set.groups):
            if first <= index < first + len(g):
                nets = g[index - first: index - first + 1]
                weights = None if not patch_set.weights else patch_set.weights[k][index - first: index - first + 1]
                break
            first += len(g)
        span, u, v = np.zeros(len(uv), int), uv[:, 0], uv[:, 1]
    nets = np.asarray(nets)[span]
    if weights is None:
        return evaluate_patches_at(nets, u, v)
    w = np.asarray(weights)[span]
    h = evaluate_patches_at(np.concatenate([nets * w[..., None], w[..., None]], axis=-1), u, v)
    return h[:, :3] / h[:, 3:]


def curve_point(points: np.ndarray, weights, t: np.ndarray) -> np.ndarray:
    from c1surf.evaluation.bezier import bernstein_basis
    basis = bernstein_basis(points.shape[0] - 1, t)  # (k, d + 1)
    if weights is None:
        return basis @ points
    h = basis @ np.concatenate([points * weights[:, None], weights[:, None]], axis=1)
    return h[:, :3] / h[:, 3:]


@pytest.mark.parametrize("merge", [False, True])
@pytest.mark.parametrize("name", CLOSED)
def test_closed_sample_meshes_give_a_closed_brep_of_the_mesh_topology(name, merge):
    path = SAMPLES / f"{name}.obj"
    patch_set = patch_set_of(path, merge)
    topology = brep_topology(patch_set)
    assert topology.closed
    # the surface is homeomorphic to the mesh: same Euler characteristic
    assert len(topology.vertex_points) - topology.n_edges + topology.n_faces == euler_characteristic(path)
    if merge and patch_set.merged:
        assert topology.n_faces < patch_set.n_patches
    # every edge used twice runs once with and once against its two loops (consistent orientation)
    forward_uses = np.bincount(topology.loop_edge, weights=topology.loop_forward, minlength=topology.n_edges)
    assert np.all(forward_uses == 1)
    check_loops_and_geometry(patch_set, topology)


def check_loops_and_geometry(patch_set, topology, tolerance=1e-12):
    size = np.ptp(topology.vertex_points, axis=0).max()
    ev = topology.edge_vertices
    start = np.where(topology.loop_forward, ev[topology.loop_edge, 0], ev[topology.loop_edge, 1])
    end = np.where(topology.loop_forward, ev[topology.loop_edge, 1], ev[topology.loop_edge, 0])
    curves, curve_weights = edge_curves(patch_set, topology)
    t = np.linspace(0, 1, 5)
    for f in range(topology.n_faces):
        loop = topology.loop(f)
        # a closed loop of edges: each entry ends where the next starts
        assert np.array_equal(end[loop], np.roll(start[loop], -1))
        uv = topology.loop_uv[loop]
        assert np.array_equal(uv[:, 1], np.roll(uv[:, 0], -1, axis=0))
        # the vertices are the face's surface at the loop's corners
        at = face_point(patch_set, topology, f, uv[:, 0])
        assert np.abs(at - topology.vertex_points[start[loop]]).max() <= tolerance * size
        # each pcurve (a straight segment of the domain) traces the edge's 3D curve
        for k, e in zip(range(loop.start, loop.stop), topology.loop_edge[loop].tolist()):
            s = t if topology.loop_forward[k] else 1 - t  # the curve's parameter at the loop's t
            along = topology.loop_uv[k, 0] + t[:, None] * (topology.loop_uv[k, 1] - topology.loop_uv[k, 0])
            w = None if curve_weights is None else curve_weights[e]
            expected = curve_point(curves[e], w, s)
            assert np.abs(face_point(patch_set, topology, f, along) - expected).max() <= tolerance * size


@pytest.mark.parametrize("rational", [False, True])
def test_rational_cube_brep_curves_lie_on_both_faces(tmp_path, rational):
    from c1surf.api import surface_from_file

    surface = surface_from_file(weighted_cube(tmp_path, rational))[0]
    for merge in (False, True):
        patch_set = surface_patch_set(surface)
        if merge:
            patch_set = dataclasses.replace(patch_set, merged=merge_biquadratic(surface))
        topology = brep_topology(patch_set)
        assert topology.closed
        check_loops_and_geometry(patch_set, topology)


def test_open_mesh_has_boundary_edges_used_once():
    from c1surf.construction.surface import Surface, SurfaceOptions

    from conftest import grid

    surface = Surface(*grid(4, lambda x, y: 0.1 * x * y), SurfaceOptions())
    for merge in (False, True):
        patch_set = surface_patch_set(surface)
        if merge:
            patch_set = dataclasses.replace(patch_set, merged=merge_biquadratic(surface))
        topology = brep_topology(patch_set)
        assert not topology.closed
        assert set(np.unique(topology.edge_uses).tolist()) == {1, 2}
        on_boundary = topology.edge_uses[topology.loop_edge] == 1
        # the boundary edges, run as their faces' loops run, form closed chains: every boundary
        # vertex starts as many of them as it ends
        ev = topology.edge_vertices[topology.loop_edge[on_boundary]]
        forward = topology.loop_forward[on_boundary]
        n = len(topology.vertex_points)
        starts = np.bincount(np.where(forward, ev[:, 0], ev[:, 1]), minlength=n)
        ends = np.bincount(np.where(forward, ev[:, 1], ev[:, 0]), minlength=n)
        assert np.array_equal(starts, ends) and starts.sum() == 4 * 4 * 4  # 4 x 4 quads, 4 patch sides each
        check_loops_and_geometry(patch_set, topology)
