"""The patch sides on either side of a C0 crease, paired (``mesh.creases.sheets``; integers only).

A crease side of a kept patch is the side dual to a refined edge from a real point to a ghost point:
an edge that *crosses* the crease. Both sheets have one such crossing for every place the crease is
crossed, named alike on both: by the uncut crease edge it lies on, the crease vertex it is next
to, and the once-refined cell it lies in (the crease edge's E-cell, or the vertex's V-cell). Sides
with the same name are the two sides of one crease curve piece; the sides along a cut boundary
(``CreaseSheets.open_edges``) have none and stay boundary sides.
"""
from __future__ import annotations

import numpy as np

from .refine.doo_sabin import FACE_FROM_EDGE, FACE_FROM_VERTEX

SIDE_EDGE = np.array([3, 0, 1, 2])  # side s of a patch crosses its frame's half-edge e_{(s + 3) % 4}


def crease_side_pairs(topology) -> np.ndarray:
    """(k, 2) int: curve ids ``4 * patch + side`` of the two sides of every crease piece.

    Parameters
    ----------
    topology : SurfaceTopology with ``crease_sheets`` (one or two refinements)

    Returns
    -------
    (k, 2) int64, in the order of the first side's curve id; (0, 2) without C0 creases. A piece shared by
    more than two sheets (a non-manifold edge cut into sheets) gives one pair for each side but its first.
    """
    sheets = topology.crease_sheets
    if sheets is None:
        return np.zeros((0, 2), dtype=np.int64)
    refined, level1, coarse, faces1 = topology.refined, topology.level1, topology.input, topology.faces1
    frames = topology.frames
    crossed = frames[:, SIDE_EDGE]  # (P, 4) refined half-edges from each patch's centre
    real = topology.real_vertex
    crease = ~real[refined.dest[crossed]]  # the neighbour across the side is a ghost point
    crease[topology.quad_frames.shape[0]:] = False  # no A3 hole touches a C0 crease (every crease vertex has 4 faces)
    patch, side = np.nonzero(crease)
    h = crossed[patch, side]
    near, far = refined.origin[h], refined.dest[h]
    # a ghost point of the sheets' ghost quads, not of the ghost layer closing the mesh boundary
    ours = np.isin(coarse.face[topology.coarse_corner(far)], sheets.ghost_faces)
    patch, side, near, far = patch[ours], side[ours], near[ours], far[ours]
    source = np.full(coarse.n_vertices, -1, dtype=np.int64)
    source[: sheets.vertex_name.size] = sheets.vertex_name  # copies of one vertex in several sheets: one name
    near_corner, far_corner = topology.coarse_corner(near), topology.coarse_corner(far)  # coarse half-edges
    vertex = source[coarse.origin[near_corner]]  # the crease vertex the crossing is next to
    # the crease edge: the edge the ghost corner's quad lies across (a crease ghost quad (B, A, ., .) starts with
    # the crease half-edge B -> A); after two steps, in an E-cell that cell's own edge
    ghost_quad_first = coarse.face_offsets[coarse.face[far_corner]]
    if topology.refinements == 1:  # one crossing per sheet, crease vertex and crease edge: the E-cell's edge
        kind, edge_halfedge = np.full(near.size, FACE_FROM_EDGE, dtype=np.int8), ghost_quad_first
    else:  # level-2 points = level-1 half-edges (corners of level-1 cells): a crossing in an E- or a V-cell
        cell = level1.face[near]
        kind, parent = faces1.kind[cell], faces1.parent[cell]
        edge_halfedge = np.where(kind == FACE_FROM_EDGE, parent, ghost_quad_first)
    a, b = source[coarse.origin[edge_halfedge]], source[coarse.dest[edge_halfedge]]
    if not np.all((kind == FACE_FROM_EDGE) | (kind == FACE_FROM_VERTEX)):
        raise ValueError("internal: a crease crossing in a face cell")
    keys = np.stack([kind.astype(np.int64), vertex, np.minimum(a, b), np.maximum(a, b)], axis=1)
    width = int(source.max(initial=0)) + 1
    open_keys, open_count = np.unique(sheets.open_edges[:, 0] * width + sheets.open_edges[:, 1], return_counts=True)
    boundary_keys = open_keys[open_count == 1]  # an edge cut in several sheets is a non-manifold crease
    on_boundary = np.isin(keys[:, 2] * width + keys[:, 3], boundary_keys)
    keys, patch, side = keys[~on_boundary], patch[~on_boundary], side[~on_boundary]  # one side: a boundary
    pairs = _pairs_by_key(keys, 4 * patch + side)
    darts = dart_spoke_pairs(topology)
    if darts.size:
        pairs = np.concatenate([pairs, darts])
        pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    return pairs


def dart_spoke_pairs(topology) -> np.ndarray:
    """(k, 2) int: curve ids of the crease spoke of every dart's hole (``refine.holes.split_dart_holes``): side
    u = 1 of p_{n-1} (P_3k) and side v = 1 of p_0 (P_k3), both real, the hole's two ghost corners last."""
    keep = topology.cubic_keep
    sizes = [g.n * g.cells.size for g in topology.holes]
    if not any(g.dart for g in topology.holes):
        return np.zeros((0, 2), dtype=np.int64)
    keep = np.ones(sum(sizes), dtype=bool) if keep is None else keep
    kept = np.cumsum(keep) - 1  # index among the kept bicubic patches
    start, out = 0, []
    for g, size in zip(topology.holes, sizes):
        if g.dart:
            first = start + g.n * np.arange(g.cells.size)  # corner 0 of each hole
            both = keep[first + g.n - 3] & keep[first]  # (a hole face beside the crease: its side is a boundary)
            before, after = topology.n_quad + kept[first + g.n - 3], topology.n_quad + kept[first]
            out.append(np.stack([4 * before + 1, 4 * after + 2], axis=1)[both])
        start += size
    return np.sort(np.concatenate(out), axis=1).astype(np.int64)


def _pairs_by_key(keys: np.ndarray, curves: np.ndarray) -> np.ndarray:
    """(k, 2) int: the curves (c,) that share a key (c, 4) row, paired with the first of their group; a
    curve alone (the other side makes no patches: a hole face beyond the crease) is a boundary side."""
    order = np.lexsort(keys.T[::-1])
    keys, curves = keys[order], curves[order]
    for _ in range(2):  # once more after dropping the curves alone
        if keys.shape[0] == 0:
            return np.zeros((0, 2), dtype=np.int64)
        start = np.r_[True, np.any(keys[1:] != keys[:-1], axis=1)]
        group = np.cumsum(start) - 1
        alone = np.bincount(group)[group] < 2
        if not alone.any():
            break
        keys, curves = keys[~alone], curves[~alone]
    # a piece of k sides (k sheets) is listed as k - 1 pairs, each with the piece's first side
    first = curves[np.flatnonzero(start)][group]
    pairs = np.sort(np.stack([first, curves], axis=1)[~start], axis=1)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


__all__ = ["crease_side_pairs"]
