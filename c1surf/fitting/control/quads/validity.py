"""Whether a pure-quad mesh is valid, checked on plain arrays independently of the compiled link test.

A valid mesh (what every local operation must keep): each quad has four distinct vertices; each directed edge
lies in one face at most (consistent orientation; an undirected edge in two faces at most); each vertex's faces
form one fan (no pinch: the corners at a vertex are joined through shared edges into one group), and a rim
vertex has one boundary edge out and one in. The counts (components, Euler characteristic, rims) are
``mesh.topology_counts``'.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ....mesh.topology_counts import topology_counts

__all__ = ["quad_mesh_problems", "quad_topology"]


def quad_topology(quads: np.ndarray, n_vertices: int) -> tuple:
    """(components, Euler characteristic, rims) of a quad mesh (F, 4)."""
    counts = topology_counts(np.full(quads.shape[0], 4), np.asarray(quads).ravel(), n_vertices)
    return counts.components, counts.euler_characteristic, counts.rims


def quad_mesh_problems(quads: np.ndarray, n_vertices: int) -> list:
    """The ways ``quads`` (F, 4) int breaks the module docstring's rules, as short strings; [] when valid."""
    quads = np.asarray(quads, dtype=np.int64)
    problems = []
    rows = np.sort(quads, axis=1)
    if np.any(rows[:, 1:] == rows[:, :-1]):
        problems.append("a quad repeats a vertex")
    a, b = quads.ravel(), np.roll(quads, -1, axis=1).ravel()
    directed = a * n_vertices + b
    if np.unique(directed).size != directed.size:
        problems.append("a directed edge lies in two faces")
    twin = np.isin(b * n_vertices + a, directed)
    out_rim = np.bincount(a[~twin], minlength=n_vertices)
    in_rim = np.bincount(b[~twin], minlength=n_vertices)
    if np.any(out_rim > 1) or np.any(out_rim != in_rim):
        problems.append("a rim vertex has more than one boundary edge each way")
    if _fans(quads, a, b, directed, n_vertices) != np.unique(quads).size:
        problems.append("a vertex is pinched (its faces form more than one fan)")
    return problems


def _fans(quads, a, b, directed, n_vertices) -> int:
    """The fans of faces over all vertices: corners at a vertex joined when their faces share an edge there."""
    corners = np.arange(a.size)
    # corner c at vertex v with edge v -> w; the face with w -> v holds the corner at v whose previous edge is w -> v
    order = np.argsort(directed)
    reverse = b * n_vertices + a
    where = np.searchsorted(directed[order], reverse)
    where = np.minimum(where, a.size - 1)
    found = directed[order][where] == reverse
    other = order[where[found]]  # the corner at w with edge w -> v: the next corner of its face is at v
    partner = (other // 4) * 4 + (other % 4 + 1) % 4
    graph = coo_matrix((np.ones(found.sum()), (corners[found], partner)), shape=(a.size, a.size))
    _, label = connected_components(graph, directed=False)
    return np.unique(a * (label.max() + 1) + label).size
