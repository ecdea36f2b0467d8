"""The IGES B-rep's edges (io/patches/brep/iges_edges.py): edge_chains' chains of patch sides with one B-spline
curve each, checked against the topology they coarsen, against the STEP B-rep's chains and against the faces'
own geometry."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.interpolate import BSpline

from c1surf.api import surface_from_file
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.merge import merge_biquadratic
from c1surf.evaluation.patch_set import surface_patch_set
from c1surf.io.patches.brep.edge_chains import edge_chains
from c1surf.io.patches.brep.iges_edges import iges_edges
from c1surf.io.patches.brep.iges_brep import edge_polygons
from c1surf.io.patches.brep.topology import brep_topology

from conftest import SAMPLES, grid, weighted_cube
from test_brep_topology import CLOSED, euler_characteristic, face_point, patch_set_of


def runs_of(patch_set):
    topology = brep_topology(patch_set)
    return topology, iges_edges(topology, edge_polygons(patch_set, topology))


def run_curve(runs, edge: int):
    """Control points (n, 3), weights (n,) or None, degree, spans and interior knot multiplicity of edge ``edge``."""
    for edges, d, k, m, points, weights in runs.curves:
        where = np.flatnonzero(edges == edge)
        if where.size:
            return points[where[0]], None if weights is None else weights[where[0]], d, k, m
    raise AssertionError(f"edge {edge} has no curve")


def curve_at(points, weights, d: int, k: int, m: int, t: np.ndarray) -> np.ndarray:
    """The clamped B-spline of ``k`` unit spans (interior knots m-fold) at parameters t in [0, k] (rational through w)."""
    knots = np.r_[np.zeros(d + 1), np.repeat(np.arange(1.0, k), m), np.full(d + 1, float(k))]
    if weights is None:
        return BSpline(knots, points, d)(t)
    h = BSpline(knots, np.c_[points * weights[:, None], weights], d)(t)
    return h[:, :3] / h[:, 3:]


def check_runs(patch_set, topology, runs, tolerance=1e-12):
    coarse = runs.topology
    size = float(np.ptp(topology.vertex_points, axis=0).max())
    # the same surface: faces kept, Euler characteristic and closedness unchanged
    assert coarse.n_faces == topology.n_faces and np.array_equal(coarse.face_size, topology.face_size)
    assert len(coarse.vertex_points) - coarse.n_edges == len(topology.vertex_points) - topology.n_edges
    assert coarse.closed == topology.closed
    assert np.array_equal(np.bincount(coarse.loop_edge, minlength=coarse.n_edges), coarse.edge_uses)
    twice = coarse.edge_uses == 2  # an edge in two loop entries runs once with each
    forward_uses = np.bincount(coarse.loop_edge, weights=coarse.loop_forward, minlength=coarse.n_edges)
    assert np.all(forward_uses[twice] == 1)
    ev = coarse.edge_vertices
    start = np.where(coarse.loop_forward, ev[coarse.loop_edge, 0], ev[coarse.loop_edge, 1])
    end = np.where(coarse.loop_forward, ev[coarse.loop_edge, 1], ev[coarse.loop_edge, 0])
    t = np.linspace(0.0, 1.0, 7)
    for f in range(coarse.n_faces):
        loop = coarse.loop(f)
        assert np.array_equal(end[loop], np.roll(start[loop], -1))  # loops close
        uv = coarse.loop_uv[loop]
        assert np.array_equal(uv[:, 1], np.roll(uv[:, 0], -1, axis=0))
        for k, e in zip(range(loop.start, loop.stop), coarse.loop_edge[loop].tolist()):
            points, weights, d, spans, m = run_curve(runs, e)
            step = coarse.loop_uv[k, 1] - coarse.loop_uv[k, 0]
            assert np.abs(step).sum() == spans and np.count_nonzero(step) == 1  # straight, whole spans
            along = coarse.loop_uv[k, 0] + t[:, None] * step  # the pcurve at parameter spans * t
            s = spans * (t if coarse.loop_forward[k] else 1 - t)  # the curve's parameter there
            gap = np.abs(face_point(patch_set, topology, f, along) - curve_at(points, weights, d, spans, m, s)).max()
            assert gap <= tolerance * size, (f, k, gap)
    for e in range(coarse.n_edges):  # curves end at their vertices (to round-off)
        points, *_ = run_curve(runs, e)
        assert np.abs(points[[0, -1]] - coarse.vertex_points[ev[e]]).max() <= 1e-15 * size


@pytest.mark.parametrize("name", CLOSED)
def test_runs_of_closed_sample_meshes_trace_their_faces(name):
    patch_set = patch_set_of(SAMPLES / f"{name}.obj", True)
    topology, runs = runs_of(patch_set)
    coarse = runs.topology
    assert len(coarse.vertex_points) - coarse.n_edges + coarse.n_faces == euler_characteristic(SAMPLES / f"{name}.obj")
    if patch_set.merged:
        assert coarse.n_edges <= topology.n_edges
    check_runs(patch_set, topology, runs)


def test_the_edges_are_the_step_b_rep_chains_with_c1_curves_along_pieces():
    """IGES and STEP share their edges (edge_chains); along merged pieces every chain is written as one C1
    B-spline (interior knots simple), none in chain_curve's C0 form."""
    for name in ("twisted", "torus", "double_torus"):
        patch_set = patch_set_of(SAMPLES / f"{name}.obj", True)
        topology, runs = runs_of(patch_set)
        chains = edge_chains(topology)
        assert runs.topology.n_edges == chains.n_chains
        assert np.array_equal(runs.topology.loop_edge, chains.loop_chain)
        assert np.array_equal(runs.spans, np.diff(chains.chain_start))
        assert all(m == 1 or k == 1 for _, _, k, m, _, _ in runs.curves) and runs.spans.max() > 1


def test_a_chain_that_is_not_c1_keeps_its_exact_sides():
    """A kinked joint (a polygon moved off C1) falls back to the sides one after the other (knots d-fold)."""
    patch_set = patch_set_of(SAMPLES / "twisted.obj", True)
    topology = brep_topology(patch_set)
    polygons = edge_polygons(patch_set, topology)
    chains = edge_chains(topology)
    c = int(np.argmax(np.diff(chains.chain_start)))  # a chain of several sides
    edge = int(chains.chain_edges[chains.chain_start[c]])
    for edges, net, _ in polygons:
        if edge in edges:
            net[np.flatnonzero(edges == edge)[0], 1] += 1e-6  # its middle control point: no longer C1
    runs = iges_edges(topology, polygons)
    points, _, d, k, m = run_curve(runs, c)
    assert (d, m) == (2, 2) and k > 1 and len(points) == k * d + 1


def test_without_pieces_every_side_stays_an_edge():
    patch_set = patch_set_of(SAMPLES / "twisted.obj", False)
    topology, runs = runs_of(patch_set)
    assert np.all(runs.spans == 1) and np.array_equal(runs.topology.loop_edge, topology.loop_edge)
    assert np.array_equal(runs.topology.vertex_points, topology.vertex_points)
    for (edges, points, weights), (same, d, k, m, net, w) in zip(edge_polygons(patch_set, topology), runs.curves):
        assert np.array_equal(edges, same) and k == 1 and np.array_equal(points, net) and w is None


def test_runs_join_along_pieces_only():
    """The torus is one piece: its two seams become two closed edges on one vertex; twisted keeps its corners."""
    _, runs = runs_of(patch_set_of(SAMPLES / "torus.obj", True))
    assert runs.topology.n_edges == 2 and len(runs.topology.vertex_points) == 1
    assert sorted(runs.spans.tolist()) == sorted(runs.topology.face_size[0].tolist())
    topology, runs = runs_of(patch_set_of(SAMPLES / "twisted.obj", True))
    assert runs.spans.max() > 1 and runs.topology.n_edges < topology.n_edges


@pytest.mark.parametrize("rational", [False, True])
def test_runs_of_a_rational_and_an_open_surface(tmp_path, rational):
    surface = surface_from_file(weighted_cube(tmp_path, rational))[0]
    patch_set = dataclasses.replace(surface_patch_set(surface), merged=merge_biquadratic(surface))
    topology, runs = runs_of(patch_set)
    assert runs.spans.max() > 1 and all((w is None) != rational for *_, w in runs.curves)
    check_runs(patch_set, topology, runs)
    open_surface = Surface(*grid(4, lambda x, y: 0.1 * x * y), SurfaceOptions())
    patch_set = dataclasses.replace(surface_patch_set(open_surface), merged=merge_biquadratic(open_surface))
    topology, runs = runs_of(patch_set)
    assert not runs.topology.closed and set(runs.topology.edge_uses.tolist()) == {1, 2}
    check_runs(patch_set, topology, runs)
