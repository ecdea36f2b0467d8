"""Points closer than a tolerance, clustered by sorting grid cells (the geometric side matcher's points, ``evaluation.adjacency``).

``cluster_points`` gives the labels that connected components of the pairs within the tolerance give
(``scipy.spatial.cKDTree.query_pairs`` then ``connected_components``, what ``adjacency.cluster_points`` did),
numbered alike (in order of each cluster's first point), without a k-d tree over all the points: the points
are hashed by grid cells of ``CELL_TOLERANCES`` tolerances and sorted by hash; the candidate pairs are the
points of one hash (their distance checked) and, for the few points within a tolerance of a cell's face
(whose partner may lie in the next cell), the pairs a k-d tree finds among those points only.

A cell crowded with points equal bit for bit (a corner where thousands of patches meet) has them linked to
their first equal before the pairwise checks, which grow with the square of a cell's points (the 10,000-gon's
check: 28.7 s and 6.9 GB before, 2.7 s and 0.4 GB after).

Measured on the sides of a 147,840-patch surface (2.4 M corner and side points), the whole side matching
(``adjacency._match``): 7.8 s with the k-d tree over all points, 3.4 s this way (the labels identical, as on
every sample mesh's patch file).
"""
from __future__ import annotations

from functools import partial

import numpy as np

from ...parallel import run_tasks

_CHUNK = 1 << 20  # points (or pairs) of a block of the hashing and of the distance checks
_LONG_RUN = 64  # points of one cell hash beyond which exact duplicates are taken out first
CELL_TOLERANCES = 1024.0  # a cell's side in tolerances: a point is near a face with a chance of ~6 / 1024
_HASH = np.array([0x9E3779B97F4A7C15 - (1 << 64), 0xC2B2AE3D27D4EB4F - (1 << 64), 0x165667B19E3779F9],
                 dtype=np.int64)  # odd multipliers: cells of one hash are rare (and checked by distance anyway)


def cluster_points(points: np.ndarray, tolerance: float, components=None) -> np.ndarray:
    """(k,) int64 label per point of (k, 3) ``points``: points closer than ``tolerance`` (a chain of such
    pairs) share one; labels 0, 1, 2, ... in order of each cluster's first point.

    components : None, or callable(points, key, order, tolerance, pairs) -> labels: the pairs of one cell hash
        checked and the components labelled by the caller (``evaluation.compiled.kernels.cell_components``, compiled),
        given the hashes sorted (key, order, as ``_same_cell_pairs`` takes them) and the other pairs (m, 2)
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    n = points.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    key, near = _hashes(points, tolerance)
    index = np.int32 if n < 2**31 else np.int64  # point ids: half the bytes while they fit
    order = np.argsort(key).astype(index)  # the order within a hash does not matter: every pair of it is tried
    key = key[order]
    duplicates, key, order, near = _without_exact_duplicates(points, key, order, near)
    if components is not None:
        others = np.concatenate([duplicates, _near_face_pairs(points, near, tolerance).astype(index)])
        return components(points, key, order, tolerance, others)
    pairs = np.concatenate([duplicates, _same_cell_pairs(points, key, order, tolerance),
                            _near_face_pairs(points, near, tolerance).astype(index)])
    del key, near, order
    graph = coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    del pairs
    return connected_components(graph, directed=False)[1].astype(np.int64)


def _hashes(points: np.ndarray, tolerance: float):
    """(key (k,) int64, the hash of each point's cell; near (m,) int, the points within about a tolerance of
    their cell's faces), by blocks of ``_CHUNK`` points (block-sized temporaries only)."""
    # cells no finer than the coordinates' own resolution (a tolerance of 1e-320 would overflow the division);
    # larger cells only bring more candidate pairs, each checked, and a margin of at least two tolerances
    largest = float(np.abs(points).max(initial=0.0))
    size = max(tolerance * CELL_TOLERANCES, largest * 2.0**-40) if tolerance > 0 else 1.0
    margin = 2.0 * max(tolerance, 0.0) / size if tolerance > 0 else -1.0  # twice a tolerance: rounding cannot hide a point
    key, near = np.empty(points.shape[0], dtype=np.int64), []
    for a in range(0, points.shape[0], _CHUNK):
        scaled = points[a : a + _CHUNK] / size
        cell = np.floor(scaled)
        scaled -= cell
        cell += 0.0  # -0.0 and 0.0: one cell
        key[a : a + _CHUNK] = cell.view(np.int64) @ _HASH  # wraps around: a hash
        near.append(np.flatnonzero(((scaled < margin) | (scaled > 1.0 - margin)).any(axis=1)) + a)
    return key, np.concatenate(near)


def _without_exact_duplicates(points: np.ndarray, key: np.ndarray, order: np.ndarray, near: np.ndarray):
    """In runs of one hash longer than ``_LONG_RUN`` (many points in one cell: a corner where thousands of
    patches meet), the points equal to an earlier one of their run, bit for bit, linked to it and taken out of
    the pairwise checks, which are quadratic in a run's length (a 10,000-valent corner: 5e7 pairs, 6.8 GB).

    Returns (pairs (m, 2) linking each such point to the first of its equals, key, order and near without them).
    """
    first = np.ones(key.size, dtype=bool)
    np.not_equal(key[1:], key[:-1], out=first[1:])
    starts = np.flatnonzero(first)
    lengths = np.diff(np.r_[starts, key.size])
    long = lengths > _LONG_RUN
    if not long.any():
        return np.zeros((0, 2), dtype=order.dtype), key, order, near
    position = np.flatnonzero(np.repeat(long, lengths))  # sorted positions in long runs
    run = np.repeat(np.arange(long.sum()), lengths[long])
    members = order[position]
    xyz = points[members]
    by = np.lexsort((xyz[:, 2], xyz[:, 1], xyz[:, 0], run))  # equal points of one run next to each other
    same = np.zeros(by.size, dtype=bool)
    same[1:] = (run[by][1:] == run[by][:-1]) & (xyz[by][1:] == xyz[by][:-1]).all(axis=1)
    representative = by[np.maximum.accumulate(np.where(same, 0, np.arange(by.size)))]  # first of each equal block
    duplicate = by[same]
    pairs = np.stack([members[duplicate], members[representative[same]]], axis=1)
    drop = np.zeros(key.size, dtype=bool)
    drop[position[duplicate]] = True
    gone = np.zeros(points.shape[0], dtype=bool)
    gone[members[duplicate]] = True
    return pairs, key[~drop], order[~drop], near[~gone[near]]


def _same_cell_pairs(points: np.ndarray, key: np.ndarray, order: np.ndarray, tolerance: float) -> np.ndarray:
    """(m, 2) int: the pairs of points of one cell hash within ``tolerance`` of each other; ``key`` (k,) the
    hashes sorted, ``order`` (k,) the points in that order."""
    found = []
    run = np.flatnonzero(key[:-1] == key[1:])  # i with key[i] == key[i + d], d = 1, 2, ...
    d = 1
    while run.size:
        a, b = order[run], order[run + d]
        close = _within(points, a, b, tolerance)
        found.append(np.stack([a[close], b[close]], axis=1))
        run = run[run + d + 1 < key.size]
        run = run[key[run] == key[run + d + 1]]
        d += 1
    return np.concatenate(found) if found else np.zeros((0, 2), dtype=order.dtype)


def _near_face_pairs(points: np.ndarray, near: np.ndarray, tolerance: float) -> np.ndarray:
    """(m, 2) int: the pairs within ``tolerance`` among the points ``near`` a cell's face (their partner may lie
    in the next cell)."""
    from scipy.spatial import cKDTree

    if near.size < 2:
        return np.zeros((0, 2), dtype=np.int64)
    pairs = cKDTree(points[near]).query_pairs(tolerance, output_type="ndarray")
    return near[pairs].reshape(-1, 2)


def _within(points: np.ndarray, a: np.ndarray, b: np.ndarray, tolerance: float) -> np.ndarray:
    """(m,) bool: points a and b lie within ``tolerance`` (as the k-d tree's query: distance <= tolerance), by
    blocks of pairs (the two gathers in increasing order of ``a`` where they can be: points near in the file are
    near in memory)."""
    out = np.empty(a.size, dtype=bool)

    def check(lo: int) -> None:  # a block of pairs, a task of the thread pool (the gathers run without the GIL)
        difference = points[a[lo : lo + _CHUNK]] - points[b[lo : lo + _CHUNK]]
        out[lo : lo + _CHUNK] = np.einsum("ij,ij->i", difference, difference) <= tolerance * tolerance
    run_tasks([partial(check, lo) for lo in range(0, a.size, _CHUNK)])
    return out


__all__ = ["cluster_points", "CELL_TOLERANCES"]
