"""Crease sectors of many faces merged into one or two polygons, so that the C0 crease is exact there.

The C0 crease (``mesh.creases.sheets``, docs/sharp-features.md) is exact at a smooth crease vertex
whose sectors (the faces between two consecutive seam edges around it) have one or two faces, and at
a corner whose sectors have one face each. Triangle meshes have three or more faces in most sectors
(a box edge of a CAD triangulation: 2 to 6 on each side), and valence-5 quad vertices have 3 on one
side. With the paper's bicubic holes no exact crease passes through such a vertex (the analysis in
docs/sharp-features.md: a hole straddling the crease needs the same n and opposite crease spokes on
both sides). So c1surf changes the mesh there, not the construction: the faces of such a sector are
merged across the interior edges at the vertex into two polygons (one at a corner), a fan
``(v, u0, u1, .., uk)`` split as evenly as it goes. The merged polygons are new, larger cells of the
mesh: the construction takes any polygon, and the surface still interpolates each cell's centroid
(the merged one's now) and stays G1 inside each sheet. A planar region stays planar.

Integers only: the points are untouched. An edge is not removed where that would leave an interior
vertex in fewer than two faces (one left in two is dissolved next, ``mesh.valence_two``), join faces
with different per-face data (``face_keys``: hole tags, blend ratios), remove a tagged semi-sharp
crease (``protected_edges``), make a polygon that visits a vertex twice, or close a ring of faces; a
crease component whose vertices cannot all be brought to the exact counts keeps its faces (and then
the sharpest G1 crease, named in a note by the caller). The one tagged edge that may go is the first
edge of a lone line (one crease edge whose two ends are darts, inside the surface, which stays a G1
crease; ``sheets.dart_chains``) inside a corner's sector, which must be one face: the caller names those edges in a note.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .sheets import corner_sectors, dart_ends, exact_crease_vertices, seam_corners
from ..halfedges import HalfEdgeMesh, build_halfedges, component_roots, orbit_labels, vertex_valences


@dataclass(frozen=True)
class SectorMerge:
    """What ``merge_crease_sectors`` changed.

    face_sizes, face_vertices : the merged mesh (F' faces)
    kept : (F,) bool, input faces that remain (a merged polygon takes the place of its lowest face)
    merged_faces : int, input faces taken into merged polygons (the lowest of each polygon counted too)
    polygons : int, merged polygons made
    vertices : (k,) int, seam vertices whose sectors were merged
    lost_creases : (d, 2) int, crease edges merged away: lone lines (one crease edge between two darts,
        ``sheets.dart_chains``) inside a corner's sector, which must be one face
    """

    face_sizes: np.ndarray
    face_vertices: np.ndarray
    kept: np.ndarray
    merged_faces: int
    polygons: int
    vertices: np.ndarray
    lost_creases: np.ndarray


def merge_crease_sectors(face_sizes, face_vertices, n_vertices: int, sharp_edges: np.ndarray,
                         tagged_corners: np.ndarray, face_keys: np.ndarray | None = None,
                         protected_edges: np.ndarray | None = None) -> SectorMerge | None:
    """Merge the faces of crease sectors that are too large for an exact C0 crease (module docstring).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    n_vertices : int
    sharp_edges : (E, 2) int, vertex pairs of the infinitely sharp crease edges
    tagged_corners : (C,) int, infinitely sharp corner vertices
    face_keys : (F,) int or None, faces with different keys are never merged
    protected_edges : (P, 2) int or None, vertex pairs never removed (tagged semi-sharp creases)

    Returns
    -------
    SectorMerge, or None when nothing is merged (no crease, nothing too large, or a mesh that is not
    a consistently oriented manifold: ``repair.prepare_topology`` comes later and the cut then decides).
    """
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    face_vertices = np.asarray(face_vertices, dtype=np.int64)
    sharp_edges = np.asarray(sharp_edges, dtype=np.int64).reshape(-1, 2)
    if not sharp_edges.size or not face_sizes.size:
        return None
    mesh = build_halfedges(face_sizes, face_vertices, n_vertices)
    if not _oriented_manifold(mesh):
        return None
    corner_tag = np.zeros(n_vertices, dtype=bool)
    corner_tag[np.asarray(tagged_corners, dtype=np.int64)] = True
    tagged = _sharp_halfedges(mesh, sharp_edges)
    sharp, corner_tag = seam_corners(mesh, tagged, corner_tag)  # as the cut will see them: lone lines left out
    removed = _planned_removals(mesh, sharp, corner_tag, face_keys, tagged & ~sharp)
    if protected_edges is not None and len(protected_edges):
        removed &= ~_sharp_halfedges(mesh, np.asarray(protected_edges, dtype=np.int64).reshape(-1, 2))
    for _ in range(3):  # components that stay inexact give their removals back; that may free others
        if not removed.any():
            return None
        removed, region = _valid_removals(mesh, removed)
        after = _merged(mesh, removed, region)
        still = _inexact_components(after, mesh, sharp, corner_tag)
        undo = removed & still[mesh.origin] | removed & still[mesh.dest]
        if not undo.any():
            break
        removed &= ~(undo | undo[np.maximum(mesh.twin, 0)])
    removed, region = _valid_removals(mesh, removed)
    if not removed.any():
        return None
    sizes, vertices, kept = _merged(mesh, removed, region)
    polygon_size = np.bincount(region, minlength=mesh.n_faces)
    at = np.unique(np.r_[mesh.origin[removed], mesh.dest[removed]])
    seam_vertex = np.zeros(n_vertices, dtype=bool)
    seam_vertex[mesh.origin[sharp | (mesh.twin < 0)]] = True
    lost = removed & tagged
    lost_edges = np.unique(np.sort(np.stack([mesh.origin[lost], mesh.dest[lost]], axis=1), axis=1), axis=0)
    return SectorMerge(sizes, vertices, kept, int(polygon_size[polygon_size > 1].sum()),
                       int(np.count_nonzero(polygon_size > 1)), at[seam_vertex[at]], lost_edges)


def _oriented_manifold(mesh: HalfEdgeMesh) -> bool:
    """True when every edge has one or two half-edges, opposite, and every vertex one fan of faces."""
    key = np.minimum(mesh.origin, mesh.dest) * mesh.n_vertices + np.maximum(mesh.origin, mesh.dest)
    counts = np.bincount(np.unique(key, return_inverse=True)[1].ravel())
    paired = np.count_nonzero(mesh.twin >= 0)
    if counts.max(initial=0) > 2 or paired != 2 * np.count_nonzero(counts == 2):
        return False
    fans = np.zeros(mesh.n_vertices, dtype=np.int64)  # fan starts: a boundary fan starts after an open edge
    turned = mesh.twin[mesh.prev]
    starts = turned < 0
    np.add.at(fans, mesh.origin[starts], 1)
    return bool(np.all(fans <= 1))


def _sharp_halfedges(mesh: HalfEdgeMesh, sharp_edges: np.ndarray) -> np.ndarray:
    """(H,) bool: half-edges on one of the vertex pairs ``sharp_edges``."""
    n = mesh.n_vertices
    key = np.minimum(mesh.origin, mesh.dest) * n + np.maximum(mesh.origin, mesh.dest)
    return np.isin(key, np.minimum(*sharp_edges.T) * n + np.maximum(*sharp_edges.T))


def _planned_removals(mesh: HalfEdgeMesh, sharp: np.ndarray, corner_tag: np.ndarray, face_keys,
                      dart: np.ndarray) -> np.ndarray:
    """(H,) bool: both half-edges of every interior edge to remove at a seam vertex whose sector is too large.

    A sector of k faces around a smooth seam vertex keeps one interior edge (``_kept_interior_edges``), a
    corner's sector none. Only components that the counts alone keep from being exact are touched (a lone
    corner: merging cannot help). ``dart`` (H,) bool, the lone lines' edges: kept by a smooth vertex's
    sector where it can, removed only in a corner's sector.
    """
    h = np.arange(mesh.n_halfedges)
    seam = sharp | (mesh.twin < 0)
    on_seam, exact, corner = exact_crease_vertices(mesh, sharp, corner_tag)
    once = seam & ((mesh.twin < 0) | (h < mesh.twin))
    seam_edges = np.bincount(np.r_[mesh.origin[once], mesh.dest[once]], minlength=mesh.n_vertices)
    fixable = on_seam & (exact | np.where(corner, seam_edges >= 2, seam_edges == 2))  # exact: darts too
    component = component_roots(mesh.n_vertices, mesh.origin[seam], mesh.dest[seam])
    creased = np.zeros(mesh.n_vertices, dtype=bool)
    creased[component[mesh.origin[sharp]]] = True
    blocked = np.zeros(mesh.n_vertices, dtype=bool)
    blocked[component[on_seam & ~fixable]] = True
    wanted = on_seam & creased[component] & ~blocked[component] & ~exact
    # the rank of every corner in its sector, from the seam edge the sector starts at (pointer jumping)
    turned = mesh.twin[mesh.prev]
    successor = np.where((turned >= 0) & ~seam[mesh.prev], turned, -1)
    sector = corner_sectors(mesh, seam)
    size = np.bincount(sector, minlength=mesh.n_halfedges)[sector]
    target = np.where(corner[mesh.origin], 1, 2)
    remove = wanted[mesh.origin] & (size > target) & (successor >= 0)
    least = _least_faces(mesh, on_seam, dart_ends(mesh, sharp, corner_tag))
    remove &= ~_kept_interior_edges(mesh, remove & (target == 2), sector, size, successor, least,
                                    remove & (target == 1), dart[mesh.prev])
    remove &= ~dart[mesh.prev] | (target == 1)
    if face_keys is not None:
        keys = np.asarray(face_keys)
        remove &= keys[mesh.face] == keys[mesh.face[np.maximum(successor, 0)]]
    edge = mesh.prev[remove]  # the interior edge between a corner and the next one around its vertex
    removed = np.zeros(mesh.n_halfedges, dtype=bool)
    removed[edge] = True
    removed[mesh.twin[edge]] = True
    return _keep_valences(mesh, removed, least)


def _kept_interior_edges(mesh: HalfEdgeMesh, candidate: np.ndarray, sector: np.ndarray, size: np.ndarray,
                         successor: np.ndarray, least: np.ndarray, certain: np.ndarray, prefer: np.ndarray) -> np.ndarray:
    """(H,) bool: the one interior edge each smooth seam vertex's large sector keeps (its corner ``h``).

    ``candidate``: corners whose following interior edge (``prev[h]``) a two-face target could keep;
    ``certain``: corners whose edge goes anyway (corner sectors). The edge kept is the one whose far
    vertex can least spare a face (the fewest faces left over ``_least_faces`` once the certain edges
    are gone), ties to the middle of the sector (``size // 2 - 1`` from its start); ``prefer`` (H,) bool:
    corners whose edge is kept before any other (a lone line's).
    """
    far = mesh.origin[mesh.prev]  # prev[h] runs from the far vertex to h's vertex
    lost = np.bincount(far[certain], minlength=mesh.n_vertices)
    spare = vertex_valences(mesh) - least - lost
    score = np.where(prefer, -(2**31), spare[far])
    h = np.flatnonzero(candidate)
    rank = _chain_ranks(successor, int(size.max(initial=0)))
    order = h[np.lexsort((np.abs(rank[h] - (size[h] // 2 - 1)), score[h], sector[h]))]
    first = np.r_[True, sector[order][1:] != sector[order][:-1]][: order.size]
    kept = np.zeros(mesh.n_halfedges, dtype=bool)
    kept[order[first]] = True
    return kept


def _least_faces(mesh: HalfEdgeMesh, on_seam: np.ndarray, dart: np.ndarray) -> np.ndarray:
    """(V,) int: the fewest faces a vertex may be left in: 2 inside (an interior vertex left in two faces is
    dissolved next, ``mesh.valence_two``; in one it would be inside the polygon), 1 on the boundary and on a
    seam (a seam vertex's sectors keep a face each, and its cut copies have four), 3 at a dart (``dart`` (V,)
    bool, ``sheets.dart_ends``: its one copy, n real faces and two ghost quads, is an (n + 2)-hole,
    ``construction.stencils.holes.dart``; at n = 2 that cell is a regular quad, folded onto itself)."""
    least = np.full(mesh.n_vertices, 2, dtype=np.int64)
    least[mesh.origin[mesh.twin < 0]] = 1
    least[on_seam] = 1
    least[dart] = 3
    return least


def _keep_valences(mesh: HalfEdgeMesh, removed: np.ndarray, least: np.ndarray) -> np.ndarray:
    """``removed`` less the edges at vertices that would be left in fewer faces than ``_least_faces``."""
    lost = np.bincount(mesh.origin[removed], minlength=mesh.n_vertices)  # removed edges at each vertex
    short = vertex_valences(mesh) - lost < least
    return removed & ~short[mesh.origin] & ~short[mesh.dest]


def _chain_ranks(successor: np.ndarray, longest: int) -> np.ndarray:
    """(n,) int: every element's distance from the start of its chain of ``successor`` (list ranking by
    pointer jumping, ceil(log2(longest)) + 1 steps; elements on cycles get meaningless ranks)."""
    n = successor.size
    pred = np.full(n, -1, dtype=np.int64)
    has = successor >= 0
    pred[successor[has]] = np.flatnonzero(has)
    rank = (pred >= 0).astype(np.int64)
    jump = pred
    reach = 1
    while reach < max(longest, 1) + 1 and np.any(jump >= 0):
        step = np.flatnonzero(jump >= 0)
        target = jump[step]
        new_rank, new_jump = rank.copy(), jump.copy()
        new_rank[step] += rank[target]
        new_jump[step] = jump[target]
        rank, jump = new_rank, new_jump
        reach *= 2
    return rank


def _regions(mesh: HalfEdgeMesh, removed: np.ndarray):
    """Faces joined across removed edges: (region (F,) int, the lowest face of each; valid (F,) bool per
    region: a tree of faces (no ring) whose boundary visits no vertex twice)."""
    a = mesh.face[removed]
    b = mesh.face[mesh.twin[removed]]
    region = component_roots(mesh.n_faces, a, b)
    faces = np.bincount(region, minlength=mesh.n_faces)
    edges = np.bincount(region[a], minlength=mesh.n_faces) // 2
    valid = edges == faces - 1
    valid[faces == 0] = True
    inner = ~removed & (mesh.twin >= 0)  # a kept edge between two faces of one region: not a disk
    inner &= region[mesh.face] == region[mesh.face[np.maximum(mesh.twin, 0)]]
    valid[region[mesh.face[inner]]] = False
    # a boundary corner of each region: no vertex twice
    keep = ~removed
    key = region[mesh.face[keep]].astype(np.int64) * mesh.n_vertices + mesh.origin[keep]
    unique, counts = np.unique(key, return_counts=True)
    valid[(unique[counts > 1] // mesh.n_vertices)] = False
    return region, valid


def _valid_removals(mesh: HalfEdgeMesh, removed: np.ndarray):
    """(removed less the edges of invalid regions, the regions of what is left): ``_regions``' checks applied."""
    region, valid = _regions(mesh, removed)
    removed = removed & valid[region[mesh.face]] & valid[region[mesh.face[np.maximum(mesh.twin, 0)]]]
    return removed, np.where(valid[region], region, np.arange(mesh.n_faces))  # an invalid region's faces alone


def _merged(mesh: HalfEdgeMesh, removed: np.ndarray, region: np.ndarray):
    """(face_sizes, face_vertices, kept (F,) bool) of ``mesh`` with the faces across ``removed`` edges merged
    (``region``: ``_regions`` of ``removed``)."""
    h = np.arange(mesh.n_halfedges)
    keep = ~removed
    # the next boundary half-edge of a region: next, and across removed edges around the vertex
    following = mesh.next.astype(np.int64).copy()
    for _ in range(int(vertex_valences(mesh).max(initial=0))):
        across = removed[following]
        if not across.any():
            break
        following[across] = mesh.next[mesh.twin[following[across]]]
    cycle = orbit_labels(np.where(keep, following, -1), int(mesh.face_sizes.sum()))
    start = np.full(cycle.max(initial=-1) + 1, mesh.n_halfedges, dtype=np.int64)
    np.minimum.at(start, cycle[keep], h[keep])
    # rank along each boundary cycle from its lowest half-edge: the cycle broken there, then pointer jumping
    chain = np.where(keep, following, -1)
    chain[np.isin(chain, start)] = -1
    rank = _chain_ranks(chain, int(np.bincount(cycle[keep]).max(initial=0)))
    order = h[keep][np.lexsort((rank[keep], region[mesh.face[keep]]))]
    owner = region[mesh.face[order]]
    kept = region == np.arange(mesh.n_faces)
    sizes = np.bincount(owner, minlength=mesh.n_faces)[kept]
    return sizes.astype(np.int64), mesh.origin[order].astype(np.int64), kept


def _inexact_components(merged, mesh: HalfEdgeMesh, seam_sharp: np.ndarray, corner_tag: np.ndarray) -> np.ndarray:
    """(V,) bool: vertices of seam components that are still not exact after the merge (``merged``);
    ``seam_sharp`` (H,) bool: the half-edges of ``mesh`` on the seams' sharp edges."""
    sizes, vertices, _ = merged
    after = build_halfedges(sizes, vertices, mesh.n_vertices)
    sharp = _sharp_halfedges(after, np.stack([mesh.origin[seam_sharp], mesh.dest[seam_sharp]], axis=1))
    on_seam, exact, _ = exact_crease_vertices(after, sharp, corner_tag)
    seam = sharp | (after.twin < 0)
    component = component_roots(after.n_vertices, after.origin[seam], after.dest[seam])
    bad = np.zeros(after.n_vertices, dtype=bool)
    bad[component[on_seam & ~exact]] = True
    return bad[component] & on_seam


__all__ = ["SectorMerge", "merge_crease_sectors"]
