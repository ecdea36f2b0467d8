"""The driver: the scan as quads, coarsened by local operations in the order of the error the fit will see.

Rounds of (Tarini et al. 2010; Bozzo et al. 2010's order by a size field):

1. **Diagonal collapses**, cheapest first: a face's cost is its shorter diagonal over the control edge wanted
   there (``sizing``: sagitta of the curvature, the rims' turning, at most a quarter of the diagonal on flat
   parts), so flat parts coarsen first and curved or thin ones last. An edge longer than ``scale`` times the
   curvature edge, or than 0.6 of the local thickness (the thickness guard: a limb keeps five faces or so around),
   is never made (``edits.try_edit``'s limit), nor a fold, nor a corner above ``max_corner`` degrees.
2. **Doublets** removed; **edges turned** where the valences of the six hexagon vertices come nearer 4 (3 on a rim);
3. **Polychords** collapsed, shortest crossing edge first: the only operation that coarsens a rim;
4. **Smoothing** in the tangent plane, projected onto the scan (``smoothing``).

With a face budget the scale grows (x ``grow``) whenever a round gains little, until the budget is met; without,
it stays 1 and the rounds end when nothing more may go: the error decides the size.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..decimated_quads import THIN_EDGE
from .quad_mesh import QuadMesh
from .rounds import collapse_pass, doublet_pass, polychord_pass, rotate_pass
from .sizing import edge_sizing, rim_edges
from .smoothing import ScanTarget, smooth
from .start import start_mesh

__all__ = ["SimplifyOptions", "simplify_scan", "simplify_mesh"]

CHEAPEST = 0.5  # a round tries the cheapest half of the faces' collapses (the rest wait: their cost may change)


@dataclass(frozen=True)
class SimplifyOptions:
    """The driver's controls (module docstring).

    faces : int or None, the face budget (None: as few as the error allows)
    error : float, the sagitta the curvature edge allows, a fraction of the diagonal
    thin_edge : float, the longest control edge over the local thickness
    max_corner : float degrees, the largest corner angle an operation may make
    min_fold : float, the least cosine between a new face's corner normals and the faces it replaces
    grow : float > 1, the scale's growth when a round gains less than ``slow`` of the faces
    patience : int, the slow rounds of strips alone before diagonal collapses join (strips keep valences)
    rounds : int, the most rounds
    smoothing : int, smoothing steps a round
    chord_tries : int, failed polychord attempts in a row that end a round's strips
    """

    faces: int | None = None
    error: float = 1e-3
    thin_edge: float = THIN_EDGE
    max_corner: float = 170.0
    min_fold: float = 0.2
    grow: float = 1.3
    slow: float = 0.02
    patience: int = 2
    rounds: int = 250
    smoothing: int = 2
    chord_tries: int = 40


def simplify_scan(points: np.ndarray, triangles: np.ndarray, options: SimplifyOptions = SimplifyOptions()):
    """(quads (F, 4) int64, points (V, 3) float64, info dict): the scan's pure-quad control mesh (module docstring).

    points : (m, 3) float; triangles : (t, 3) int, a consistently oriented manifold mesh (``control_mesh`` welds
    scans first). info: ``start_faces``, ``rounds``, ``collapses``, ``turns``, ``strips``, ``doublets``, ``seconds``.
    """
    start = time.perf_counter()
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    mesh, _ = start_mesh(points, triangles, options.faces)
    info = {"start_faces": mesh.n_faces}
    info.update(simplify_mesh(mesh, points, triangles, options))
    quads, quad_points = mesh.arrays()
    info["seconds"] = time.perf_counter() - start
    return quads, quad_points, info


def _limits(mesh: QuadMesh, tree: cKDTree, curvature_edge, thin_limit, scale: float):
    """(V,) float: the longest edge allowed at each mesh vertex (the sizing at its nearest scan vertex: ``scale``
    times the curvature edge, at most the thickness limit)."""
    used = np.flatnonzero(mesh.counts > 0)
    _, near = tree.query(mesh.points[used])
    limit = np.full(mesh.points.shape[0], np.inf)
    limit[used] = np.minimum(scale * curvature_edge[near], thin_limit[near])
    return limit


def _valences(mesh: QuadMesh):
    """(edge valence (V,), ideal valence (V,): 4 inside, 3 on a rim) of the live faces."""
    q = mesh.live_quads()
    n = mesh.points.shape[0]
    a, b = q.ravel(), np.roll(q, -1, axis=1).ravel()
    rim = ~np.isin(b * n + a, a * n + b)
    on_rim = np.zeros(n, dtype=bool)
    on_rim[a[rim]] = True
    return mesh.counts + on_rim, np.where(on_rim, 3, 4)


def start_quadrics(mesh: QuadMesh) -> np.ndarray:
    """(V, 4, 4) float: each vertex's quadric (Garland and Heckbert 1997), the area-weighted planes of the start's
    faces at it (the start lies on the scan): x^T Q x is the area times the squared distance to those planes."""
    q, p = mesh.live_quads(), mesh.points
    normal = np.cross(p[q[:, 2]] - p[q[:, 0]], p[q[:, 3]] - p[q[:, 1]])
    area = 0.5 * np.linalg.norm(normal, axis=1)
    unit = normal / np.maximum(2 * area, 1e-300)[:, None]
    plane = np.concatenate([unit, -np.einsum("ij,ij->i", unit, p[q].mean(axis=1))[:, None]], axis=1)
    face = 0.25 * area[:, None, None] * plane[:, :, None] * plane[:, None, :]
    quadrics = np.zeros((p.shape[0], 4, 4))
    np.add.at(quadrics, q.ravel(), np.repeat(face, 4, axis=0))
    return quadrics


def _collapse_order(mesh: QuadMesh, limit: np.ndarray, quadrics: np.ndarray):
    """(faces, corners): the live faces whose diagonal is below the limit at its ends, cheapest first, and the
    corner each collapses from. The cost: the merged quadric's error at the diagonal's midpoint plus (0.03 d^2)^2
    (d the diagonal: a tie-break towards even sizes where the scan is flat), times 2^(dE / 2), dE the change of
    the sum of (valence - ideal)^2 over the quad's corners (a collapse that makes the valences regular first)."""
    live = np.flatnonzero(mesh.alive)
    q = mesh.quads[live]
    p = mesh.points
    valence, ideal = _valences(mesh)
    dev = (valence - ideal)[q]
    cost, ratio = [], []
    for k in range(2):
        a, c = q[:, k], q[:, k + 2]
        length = np.linalg.norm(p[c] - p[a], axis=1)
        ratio.append(length / np.minimum(limit[a], limit[c]))
        x = np.concatenate([0.5 * (p[a] + p[c]), np.ones((a.size, 1))], axis=1)
        error = np.einsum("ij,ijk,ik->i", x, quadrics[a] + quadrics[c], x)
        merged = valence[a] + valence[c] - 2 - np.minimum(ideal[a], ideal[c])
        before = (dev ** 2).sum(axis=1)
        after = merged ** 2 + (dev[:, k + 1] - 1) ** 2 + (dev[:, (k + 3) % 4] - 1) ** 2
        cost.append((np.maximum(error, 0) + (0.03 * length ** 2) ** 2) * 2.0 ** (0.5 * (after - before)))
    corner = np.where(cost[0] <= cost[1], 0, 1)
    rows = np.arange(live.size)
    best, fits = np.stack(cost, axis=1)[rows, corner], np.stack(ratio, axis=1)[rows, corner]
    keep = np.flatnonzero(fits <= 1.0)
    order = keep[np.argsort(best[keep], kind="stable")][:max(1, int(CHEAPEST * live.size))]
    return live[order], corner[order]


def _chord_order(mesh: QuadMesh, limit: np.ndarray):
    """(faces, corners): every live face's edge, shortest over its ends' limit first, below half of it (merged,
    the faces beside it about double across)."""
    live = np.flatnonzero(mesh.alive)
    q = mesh.quads[live]
    p = mesh.points
    nxt = np.roll(q, -1, axis=1)
    ratio = np.linalg.norm(p[nxt] - p[q], axis=2) / np.minimum(limit[q], limit[nxt])
    face, corner = np.nonzero(ratio <= 0.5)
    order = np.argsort(ratio[face, corner], kind="stable")
    return live[face[order]], corner[order].astype(np.int64)


def simplify_mesh(mesh: QuadMesh, points, triangles, options: SimplifyOptions = SimplifyOptions()) -> dict:
    """Coarsen ``mesh`` in place towards the scan (points (m, 3), triangles (t, 3)) and ``options``; the counts.

    Long: one loop of the module docstring's four steps, with its stopping rule."""
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    curvature_edge, thin_limit = edge_sizing(points, triangles, options.error * diagonal, options.thin_edge)
    tree = cKDTree(points)
    target = ScanTarget(points, triangles, rim_edges(triangles, points.shape[0]))
    params = np.array([np.cos(np.radians(options.max_corner)), options.min_fold])
    marks = np.zeros(mesh.quads.shape[0], dtype=bool)
    stamp = np.full(mesh.points.shape[0], -1, dtype=np.int64)
    quadrics = start_quadrics(mesh)
    budget = options.faces if options.faces is not None else 0
    scale, stalls = 1.0, 0
    totals = dict(rounds=0, collapses=0, turns=0, strips=0, doublets=0)
    state = mesh.state()
    for round_id in range(options.rounds):
        live = live_before = mesh.n_faces
        if live <= budget:
            break
        limit = _limits(mesh, tree, curvature_edge, thin_limit, scale)
        faces, corners = _chord_order(mesh, limit)
        live, strips = polychord_pass(state, (limit, params, marks), faces, corners,
                                      (live, budget, options.chord_tries), quadrics, stamp, 2 * round_id)
        collapses = doublets = 0
        slow = mesh.n_faces > live_before * (1 - options.slow)
        stalls = stalls + 1 if slow else 0
        if stalls > options.patience and live > budget:  # the strips alone gain little, even at a larger scale
            faces, corners = _collapse_order(mesh, limit, quadrics)
            live, collapses = collapse_pass(state, (limit, params, marks), faces, corners.astype(np.int64),
                                            (live, budget), quadrics, stamp, 2 * round_id + 1)
        doublets = doublet_pass(state, (limit, params, marks))
        turns = rotate_pass(state, (limit, params, marks), *_valences(mesh))
        doublets += doublet_pass(state, (limit, params, marks))
        smooth(mesh, target, options.smoothing)
        for key, value in (("rounds", 1), ("collapses", collapses), ("turns", turns), ("strips", strips),
                           ("doublets", doublets)):
            totals[key] += int(value)
        if options.faces is None and collapses + strips == 0 and stalls > options.patience:
            break
        if options.faces is not None and slow:
            scale *= options.grow
    limit = _limits(mesh, tree, curvature_edge, thin_limit, scale)
    totals["turns"] += int(rotate_pass(state, (limit, params, marks), *_valences(mesh)))
    totals["doublets"] += int(doublet_pass(state, (np.full(mesh.points.shape[0], np.inf), params, marks)))
    used = np.flatnonzero(mesh.counts > 0)
    inside = used[_valences(mesh)[1][used] == 4]  # not on a rim
    mesh.points[inside] = target.onto_surface(mesh.points[inside])
    totals["scale"] = scale
    return totals
