"""Which refined points feed which patch: hole neighbourhoods and patch frames (integers only).

Names follow the paper and NOTES-ON-THE-SEED.md: an n-sided cell (a *hole*)
has corners C_1..C_n; B_{i,1} and B_{i,2} are the edge neighbours of C_i on the
C_{i-1} and C_{i+1} side, A_i is diagonal to C_i.

Every patch belongs to one vertex of the refined mesh and is described by that
vertex's four outgoing half-edges ``e0..e3`` in counter-clockwise order: its
corner [0,0] is the centroid of face(e2), [d,0] of face(e3), [d,d] of face(e0)
and [0,d] of face(e1). Its side u=1 crosses edge e0, v=1 crosses e1, u=0
crosses e2 and v=0 crosses e3. A biquadratic patch sits at every vertex whose
four faces are quads (A2); bicubic patch p_i sits at corner C_i of a hole with
``e0`` the hole's half-edge C_i -> C_{i+1} (A3).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ...mesh.errors import TopologyError
from ...mesh.halfedges import HalfEdgeMesh, first_outgoing
from ...parallel import ranges_of, run_tasks


@dataclass(frozen=True)
class HoleGroup:
    """All n-sided holes of the refined mesh, for one n.

    Attributes
    ----------
    n : int
    cells : (k,) int, refined face index of each hole
    halfedges : (k, n) int, half-edge C_i -> C_{i+1} of each hole
    A, B1, B2, C : (k, n) int, refined vertex indices of A_i, B_{i,1}, B_{i,2}, C_i
    dart : bool, the holes of darts (``split_dart_holes``): corners n - 2 and n - 1 are the ghost corners
        across the crease, whose patches are not kept (``construction.stencils.holes.dart``)
    """

    n: int
    cells: np.ndarray
    halfedges: np.ndarray
    A: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    C: np.ndarray
    dart: bool = False


def cell_neighbourhood(mesh: HalfEdgeMesh, h: np.ndarray):
    """The points A, B1, B2, C around cells whose half-edges C_i -> C_{i+1} are ``h``.

    Parameters
    ----------
    mesh : HalfEdgeMesh, every cell next to the given ones a quad
    h : (k, n) int

    Returns
    -------
    A, B1, B2, C : (k, n) int, refined vertices
    corner_quads, side_quads : (k, n) int, the faces at corner C_i and beside edge i
    """
    t = mesh.twin[h]  # C_{i+1} -> C_i in the quad beside edge i
    to_b2 = mesh.next[t]  # C_i -> B_{i,2}
    back = mesh.twin[to_b2]  # B_{i,2} -> C_i in the corner quad
    A = mesh.origin[mesh.next[mesh.next[mesh.next[back]]]]  # prev in a corner quad, without the mesh's prev
    B1 = mesh.origin[mesh.next[mesh.next[back]]]
    return A, B1, mesh.dest[to_b2], mesh.origin[h], mesh.face[back], mesh.face[t]


def hole_neighbourhoods(mesh: HalfEdgeMesh, wanted_vertex=None) -> list[HoleGroup]:
    """Find the A, B, C points around every non-quadrilateral cell, grouped by n.

    Parameters
    ----------
    mesh : HalfEdgeMesh, the twice-refined mesh (every vertex used by a patch 4-valent)
    wanted_vertex : (V,) bool or None; if given, only holes with a wanted corner
        (open meshes: holes that reach into the real surface)
    """
    groups = []
    for n, cells, h in mesh.faces_by_size(skip=(4,)):  # not the quads (92 MB of half-edges for the 180k torus)
        if wanted_vertex is not None:
            keep = wanted_vertex[mesh.origin[h]].any(axis=1)
            cells, h = cells[keep], h[keep]
            if cells.size == 0:
                continue
        A, B1, B2, C, corner_quads, side_quads = cell_neighbourhood(mesh, h)
        if np.any(mesh.face_sizes[corner_quads] != 4) or np.any(mesh.face_sizes[side_quads] != 4):
            raise TopologyError("internal: a hole of the refined mesh is not surrounded by quads")
        groups.append(HoleGroup(n=n, cells=cells, halfedges=h, A=A, B1=B1, B2=B2, C=C))
    return groups


def split_dart_holes(holes: list[HoleGroup], dart_cell: np.ndarray, ghost_corner: np.ndarray) -> list[HoleGroup]:
    """``holes`` with the holes of darts taken out into groups of their own (``HoleGroup.dart``), each turned
    so that its two ghost corners come last.

    A dart (a crease that ends inside the surface, ``mesh.creases.sheets``) is a cut vertex in its n real
    faces and two ghost quads, one across the crease from each side: its hole has n + 2 corners, the two
    ghost ones next to each other, each the mirror of its real neighbour across the crease.

    Parameters
    ----------
    holes : list of HoleGroup
    dart_cell : (k,) int, refined faces (holes) of the darts
    ghost_corner : (V,) bool, refined points in the crease sheets' ghost quads
    """
    if dart_cell.size == 0:
        return holes
    plain, darts = [], []
    for g in holes:
        is_dart = np.isin(g.cells, dart_cell)
        if not is_dart.all():
            part = lambda x: x[~is_dart]
            plain.append(HoleGroup(g.n, part(g.cells), part(g.halfedges), part(g.A), part(g.B1), part(g.B2), part(g.C)))
        if not is_dart.any():
            continue
        ghost = ghost_corner[g.C[is_dart]]  # (k, n)
        pair = ghost & np.roll(ghost, -1, axis=1)  # corner i and i + 1 both ghost
        if np.any(ghost.sum(axis=1) != 2) or np.any(pair.sum(axis=1) != 1):
            raise TopologyError("internal: a dart's hole without its two ghost corners side by side")
        first = np.argmax(pair, axis=1)
        order = (np.arange(g.n)[None, :] + first[:, None] - (g.n - 2)) % g.n  # the ghost pair at n - 2, n - 1
        turn = lambda x: np.take_along_axis(x[is_dart], order, axis=1)
        darts.append(HoleGroup(g.n, g.cells[is_dart], turn(g.halfedges), turn(g.A), turn(g.B1), turn(g.B2), turn(g.C),
                               dart=True))
    return plain + darts


def vertex_frames(mesh: HalfEdgeMesh, first: np.ndarray) -> np.ndarray:
    """Four outgoing half-edges e0..e3 counter-clockwise, starting at ``first``.

    Parameters
    ----------
    first : (k,) int, outgoing half-edges of 4-valent vertices

    Returns
    -------
    (k, 4) int
    """
    frames = np.empty((first.size, 4), dtype=np.result_type(first, mesh.twin))
    twin, nxt = mesh.twin, mesh.next

    def fill(start: int, stop: int) -> bool:  # rotations by blocks that stay in cache, on the thread pool
        ok = True
        for a in range(start, stop, 1 << 16):
            b = min(stop, a + (1 << 16))
            block, e = frames[a:b], first[a:b]
            block[:, 0] = e
            # clockwise, e3, e2, e1 and back to e0: next[twin[e]] undoes rotate (twin[prev[e]]) and needs
            # no prev (a refined mesh makes its prev only when read); twin -1 is a boundary
            for i in (3, 2, 1, 0):
                t = np.take(twin, e, mode="clip")
                ok = ok and not np.any(t < 0)
                e = np.take(nxt, t, mode="clip")
                if i:
                    block[:, i] = e
            ok = ok and not np.any(e != first[a:b])
        return ok

    if not all(run_tasks([partial(fill, a, b) for a, b in zip(*_pairs(ranges_of(first.size, 1 << 17)))])):
        raise TopologyError("internal: a refined vertex is not 4-valent")
    return frames


def _pairs(bounds: list) -> tuple:
    """(starts, stops) of consecutive ``bounds``."""
    return bounds[:-1], bounds[1:]


def patch_frames(mesh: HalfEdgeMesh, holes: list[HoleGroup], wanted_vertex=None):
    """Frames (e0..e3) of all biquadratic and the wanted bicubic patches, in one array.

    Parameters
    ----------
    wanted_vertex : (V,) bool or None, refined vertices that get a biquadratic patch if regular,
        and a bicubic patch if a hole's corner (None: all)

    Returns
    -------
    frames : (Nq + Nc, 4) int, the biquadratic patches' first, one per regular (wanted) refined vertex in
        vertex order, then the bicubic patches' at wanted corners, hole by hole (``holes`` order), corner by corner
    n_quad : int, Nq
    cubic_keep : (sum over holes of n,) bool, which bicubic patches are kept
    """
    first = first_outgoing(mesh)
    irregular = np.zeros(mesh.n_vertices, dtype=bool)
    for g in holes:
        irregular[g.C.ravel()] = True
    wanted = (first >= 0) if wanted_vertex is None else (first >= 0) & wanted_vertex
    regular = np.flatnonzero(wanted & ~irregular)
    # Every corner of a kept hole is irregular, so a regular vertex has four quads
    # around it as long as no vertex is a corner of two holes (R3):
    if irregular.sum() != sum(g.C.size for g in holes):
        raise TopologyError("internal: a refined vertex touches two holes")
    corners = np.concatenate([g.halfedges.ravel() for g in holes]).astype(mesh.twin.dtype) if holes else \
        np.zeros(0, dtype=mesh.twin.dtype)
    cubic_keep = np.ones(corners.size, dtype=bool) if wanted_vertex is None else wanted_vertex[mesh.origin[corners]]
    # one array for both kinds (``SurfaceTopology.frames`` hands it out without a copy)
    starts = first[regular] if not holes else np.concatenate([first[regular], corners[cubic_keep]])
    return vertex_frames(mesh, starts), int(regular.size), cubic_keep
