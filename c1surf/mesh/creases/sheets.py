"""Infinitely sharp creases as C0 seams: the mesh cut into sheets along them, each sheet closed by ghost quads.

The paper has no creases; this is c1surf's exact crease (docs/sharp-features.md, "C0 creases"). Along
an infinitely sharp edge the mesh is cut: every vertex on it gets one copy per *sector* (the faces
between two consecutive crease edges around it), so each side of the crease is a sheet of its own,
and every crease half-edge gets a ghost quad across it, a face that refines but makes no patches.
Where a sector has one face the ghost quads at that vertex copy are joined by one more, diagonal,
quad; where it has two faces the two ghost quads share their edge there. Every crease vertex copy
then has exactly four faces, so after two Doo-Sabin steps the crease runs between regular patches.

The geometry (``construction.stencils.creases.mirror_rows``) sets every ghost point at a crease
vertex, after the first step, to the mirror of the real point across the crease; then both sheets
build the same crease curve from crease points only. This module is the integers: which crease
components the construction makes exact, the cut, the ghost quads and the mirror pairs.

Exact (``exact_crease_vertices``): a vertex on two seam edges whose sectors have one or two faces
each (quad meshes: valence 3 or 4 on the crease), and a corner (three or more seam edges, a tagged
corner, or a boundary vertex in one face) whose sectors have one face each (a box's corners). The
mesh boundary is a seam with one side: a crease that reaches it cuts the boundary loop too, whose
ghost quads are then mirrored like a crease's (the boundary curve becomes the quadratic B-spline of
the twice Chaikin-refined boundary polygon, ending at corners), so the crease ends at a corner of
the boundary curve. A seam component (crease and boundary edges joined at vertices) that holds a
crease is cut only when all its vertices are exact; the others keep the sharpest G1 crease of
``stencils.creases`` (the caller says which, in a note), and boundary loops that no crease reaches
keep the ghost layer's rule (``mesh.ghost_layer``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..halfedges import HalfEdgeMesh, build_halfedges, component_roots, orbit_labels, vertex_valences


@dataclass(frozen=True)
class CreaseSheets:
    """A mesh cut along its exact creases and closed by ghost quads (integers only).

    Attributes
    ----------
    mesh : HalfEdgeMesh, the cut mesh: the uncut mesh's faces first (same corners, same half-edge
        numbering), then the ghost quads
    vertex_source : (V',) int, vertex of the uncut mesh of every vertex of ``mesh`` (ghost vertices:
        the crease vertex they sit at)
    ghost_faces : (G,) int, the ghost quads (faces of ``mesh``)
    mirror_ghost, mirror_real : (M,) int, half-edges of ``mesh``: a ghost quad's corner at a crease
        vertex, and the real corner it mirrors (the same vertex, the face across the crease edge)
    mirror_toward : (M,) int, vertex of ``mesh`` at the other end of that crease edge (the crease
        polygon's Chaikin point lies between the corner's vertex and this one)
    cut_halfedges : (C,) int, the half-edges cut (crease and boundary; the same numbers in ``mesh``)
    crease_vertex : (V',) int, vertex of the uncut mesh of every vertex of ``mesh`` on a cut crease
        (its copies and the ghost vertices at it), -1 elsewhere: the corners there share one blend ratio
    diagonal_ghost, diagonal_real : (D,) int, the diagonal ghost quad's corner at a one-face sector's
        vertex, and that sector's one real corner
    diagonal_mirrors : (D, 2) int, the two crease ghost quads' corners at the same vertex
    diagonal_corner : (D,) bool, the vertex is a corner (else a smooth crease vertex)
    cut_edges : (E, 2) int, the crease edges cut (vertex pairs, in ``names`` numbering)
    open_edges : (B, 2) int, the boundary edges cut with them (``names``): their ghost quads are mirrored
        too, but they have one side; an edge listed more than once is a non-manifold edge cut into sheets
        (``non_manifold``), whose sheets meet along it
    vertex_name : (V',) int, ``names`` of every vertex of ``mesh`` (crease pieces are named by these)
    kept_edges : (K, 2) int, crease edges left uncut (dart chains, and components that are not exact; ``names``)
    dart_edges : (k, 2) int, of those, the lone crease edges (one edge between two darts: ``dart_chains``;
        ``names``)
    dart_vertex : (k,) int, vertices of ``mesh`` where a cut crease ends inside the surface (darts): one copy
        each, in as many real faces as the dart's valence and two ghost quads (``construction.stencils.holes.dart``)
    inexact_vertices : (k,) int, vertices that keep their components from being cut (``names``)
    """

    mesh: HalfEdgeMesh
    vertex_source: np.ndarray
    ghost_faces: np.ndarray
    mirror_ghost: np.ndarray
    mirror_real: np.ndarray
    mirror_toward: np.ndarray
    cut_halfedges: np.ndarray
    crease_vertex: np.ndarray
    diagonal_ghost: np.ndarray
    diagonal_real: np.ndarray
    diagonal_mirrors: np.ndarray
    diagonal_corner: np.ndarray
    cut_edges: np.ndarray
    open_edges: np.ndarray
    kept_edges: np.ndarray
    inexact_vertices: np.ndarray
    dart_edges: np.ndarray = None
    vertex_name: np.ndarray = None
    dart_vertex: np.ndarray = None


def corner_sectors(mesh: HalfEdgeMesh, sharp: np.ndarray) -> np.ndarray:
    """(H,) int: the sector of every corner (half-edge ``h`` = the corner at ``origin[h]`` in ``face[h]``).

    Corners around a vertex share a sector unless a sharp edge lies between them.

    Parameters
    ----------
    mesh : HalfEdgeMesh
    sharp : (H,) bool, half-edges on a sharp edge (both half-edges of an edge alike)
    """
    turned = mesh.twin[mesh.prev]  # the next corner around origin[h], across the edge prev[h]
    successor = np.where((turned >= 0) & ~sharp[mesh.prev], turned, -1)
    return orbit_labels(successor, int(vertex_valences(mesh).max(initial=0)))


def dart_ends(mesh: HalfEdgeMesh, sharp: np.ndarray, tagged_corner: np.ndarray) -> np.ndarray:
    """(V,) bool: darts, interior vertices (not tagged corners) on exactly one sharp edge: a crease line ends there."""
    n, h = mesh.n_vertices, np.arange(mesh.n_halfedges)
    boundary = np.zeros(n, dtype=bool)
    boundary[mesh.origin[mesh.twin < 0]] = True
    once = np.flatnonzero(sharp & ((mesh.twin < 0) | (h < mesh.twin)))
    degree = np.bincount(np.r_[mesh.origin[once], mesh.dest[once]], minlength=n)
    return (degree == 1) & ~boundary & ~tagged_corner


def dart_chains(mesh: HalfEdgeMesh, sharp: np.ndarray, tagged_corner: np.ndarray) -> np.ndarray:
    """(H,) bool: the lone crease edges, each alone on its crease line with both ends inside the surface.

    A chain runs along sharp edges through interior vertices on exactly two of them (not tagged corners).
    A chain with a dart end (a crease end inside the surface) is cut: its dart gets the dart's hole
    (``construction.stencils.holes.dart``), C0 up to the end, also at both ends of a line of two or more edges.
    A line of one edge between two darts is not: its two ghost quads would close on each other (a pillow
    of two quads whose outer vertices have two faces); it keeps the sharpest G1 crease, which fades out at
    both ends as OpenSubdiv's does.

    Parameters
    ----------
    mesh : HalfEdgeMesh
    sharp : (H,) bool, half-edges on infinitely sharp edges
    tagged_corner : (V,) bool
    """
    n, h = mesh.n_vertices, np.arange(mesh.n_halfedges)
    once = np.flatnonzero(sharp & ((mesh.twin < 0) | (h < mesh.twin)))
    a, b = mesh.origin[once], mesh.dest[once]
    peeled = np.zeros(mesh.n_halfedges, dtype=bool)
    dart = dart_ends(mesh, sharp, tagged_corner)
    if not dart.any():
        return peeled
    boundary = np.zeros(n, dtype=bool)
    boundary[mesh.origin[mesh.twin < 0]] = True
    degree = np.bincount(np.r_[a, b], minlength=n)
    link = (degree == 2) & ~boundary & ~tagged_corner  # chains continue through these
    ends = np.r_[a, b]
    joins = np.tile(np.arange(once.size), 2)[link[ends]]
    chain = component_roots(once.size + n, joins, once.size + ends[link[ends]])[: once.size]
    dart_count = np.bincount(chain, weights=dart[a].astype(float) + dart[b], minlength=once.size + n)
    edges = np.bincount(chain, minlength=once.size + n)
    lone = (dart_count[chain] >= 2) & (edges[chain] == 1)
    peeled[once[lone]] = True
    twin = mesh.twin[once[lone]]
    peeled[twin[twin >= 0]] = True
    return peeled


def seam_corners(mesh: HalfEdgeMesh, sharp: np.ndarray, tagged_corner: np.ndarray):
    """(sharp edges of the C0 seams, corners): ``sharp`` less the lone lines (``dart_chains``), and
    ``tagged_corner`` with every vertex that was on three or more sharp or boundary edges before them
    (OpenSubdiv's corner rule counts the edges whatever becomes of them)."""
    peeled = dart_chains(mesh, sharp, tagged_corner)
    if not peeled.any():
        return sharp, tagged_corner
    h = np.arange(mesh.n_halfedges)
    seam = sharp | (mesh.twin < 0)
    once = seam & ((mesh.twin < 0) | (h < mesh.twin))
    edges = np.bincount(np.r_[mesh.origin[once], mesh.dest[once]], minlength=mesh.n_vertices)
    return sharp & ~peeled, tagged_corner | (edges >= 3)


def exact_crease_vertices(mesh: HalfEdgeMesh, sharp: np.ndarray, tagged_corner: np.ndarray):
    """Which vertices on seams (sharp edges and the mesh boundary) the C0 crease handles exactly.

    The mesh boundary counts as a seam with one side: where a crease reaches it, the boundary is cut
    and mirrored as the crease is, so the crease ends at a corner of the boundary curve.

    Parameters
    ----------
    mesh : HalfEdgeMesh with V vertices
    sharp : (H,) bool, half-edges on infinitely sharp edges
    tagged_corner : (V,) bool, infinitely sharp corners named by the input

    Returns
    -------
    on_seam : (V,) bool, vertices on a sharp or boundary edge
    exact : (V,) bool, of those, the ones handled exactly (module docstring)
    corner : (V,) bool, corners: three or more seam edges, a tagged corner, or a boundary vertex in one face
    """
    n = mesh.n_vertices
    open_ = mesh.twin < 0
    seam = sharp | open_
    once = seam & (open_ | (np.arange(mesh.n_halfedges) < mesh.twin))
    seam_edges = np.bincount(np.r_[mesh.origin[once], mesh.dest[once]], minlength=n)
    on_seam = seam_edges > 0
    sector = corner_sectors(mesh, seam)
    size = np.bincount(sector, minlength=mesh.n_halfedges)[sector]  # faces in each corner's sector
    largest = np.zeros(n, dtype=np.int64)
    np.maximum.at(largest, mesh.origin, size)
    boundary = np.zeros(n, dtype=bool)
    boundary[mesh.origin[open_]] = True
    corner = on_seam & ((seam_edges >= 3) | tagged_corner | (boundary & (largest == 1)))
    smooth_ok = (seam_edges == 2) & ~corner & (largest <= 2)
    corner_ok = corner & (seam_edges >= 2) & (largest == 1)
    dart_ok = dart_ends(mesh, sharp, tagged_corner)  # any valence: the dart's hole (construction.stencils.holes.dart)
    return on_seam, on_seam & (smooth_ok | corner_ok | dart_ok), corner


def cut_crease_sheets(mesh: HalfEdgeMesh, sharp: np.ndarray, tagged_corner: np.ndarray,
                      names: np.ndarray | None = None) -> CreaseSheets | None:
    """Cut ``mesh`` along the crease components it handles exactly and close every cut with ghost quads.

    Parameters
    ----------
    mesh : HalfEdgeMesh, oriented, every vertex one fan (``repair.prepare_topology``)
    sharp : (H,) bool, half-edges on infinitely sharp edges
    tagged_corner : (V,) bool, infinitely sharp corners named by the input
    names : (V,) int or None, the vertex numbers to report edges and vertices in (the input's)

    Returns
    -------
    CreaseSheets, or None when no crease component is exact (nothing to cut).
    Long: one pass of vectorized steps (components, copies, ghost slots, quads, mirror pairs) that
    share their index arrays; split up they would pass a dozen arrays between them.
    """
    n, h_all = mesh.n_vertices, np.arange(mesh.n_halfedges)
    all_sharp = sharp
    sharp, tagged_corner = seam_corners(mesh, sharp, tagged_corner)  # lone lines stay G1 creases
    on_seam, exact, corner = exact_crease_vertices(mesh, sharp, tagged_corner)
    # seam components: vertices joined by sharp or boundary edges; cut those that hold a sharp edge
    # and whose every vertex is exact (a boundary loop no crease reaches keeps the ghost layer's rule)
    seam = sharp | (mesh.twin < 0)
    a, b = mesh.origin[seam], mesh.dest[seam]
    component = component_roots(n, a, b)  # the smallest vertex of each component names it
    creased = np.zeros(component.max() + 1, dtype=bool)
    creased[component[mesh.origin[sharp]]] = True
    bad = np.zeros(component.max() + 1, dtype=bool)
    bad[component[on_seam & ~exact]] = True
    cut = seam & creased[component[mesh.origin]] & ~bad[component[mesh.origin]]
    on_crease = on_seam & creased[component]
    once = (mesh.twin < 0) | (h_all < mesh.twin)
    names = np.arange(n) if names is None else np.asarray(names)
    # edges by name, once: the copies of one non-manifold edge (one per sheet) share their names
    edges = lambda mask: np.unique(np.sort(names[np.stack([mesh.origin[mask & once], mesh.dest[mask & once]], axis=1)],
                                           axis=1).reshape(-1, 2), axis=0)
    if not cut.any():
        return None
    # one vertex per (vertex, sector) of the cut
    sector = corner_sectors(mesh, cut)
    keys, copy = np.unique(sector, return_inverse=True)
    copy = copy.ravel()
    n_copies = keys.size
    copy_source = np.zeros(n_copies, dtype=np.int64)
    copy_source[copy] = mesh.origin
    faces_in_sector = np.bincount(copy, minlength=n_copies)
    # every cut half-edge A -> B gets the ghost quad (B, A, out[A], in[B]); a sector's copy X has one
    # cut half-edge leaving it and one arriving, whose ghost quads hold out[X] and in[X] next to X
    leaving, arriving = h_all[cut], mesh.next[cut]
    A, B = copy[leaving], copy[arriving]
    crease_copies = np.unique(A)
    k = faces_in_sector[crease_copies]
    single = crease_copies[k == 1]
    slot_out = np.full(n_copies, -1, dtype=np.int64)
    slot_in = np.full(n_copies, -1, dtype=np.int64)
    slot_out[crease_copies] = n_copies + np.arange(crease_copies.size)
    slot_in[crease_copies] = slot_out[crease_copies]  # two faces: the ghost quads share their edge at X
    slot_in[single] = n_copies + crease_copies.size + np.arange(single.size)
    diagonal_vertex = n_copies + crease_copies.size + single.size + np.arange(single.size)
    n_total = n_copies + crease_copies.size + 2 * single.size
    quads = np.stack([B, A, slot_out[A], slot_in[B]], axis=1)
    diagonals = np.stack([single, slot_in[single], diagonal_vertex, slot_out[single]], axis=1)
    ghost_quads = np.concatenate([quads, diagonals])
    sizes = np.r_[mesh.face_sizes, np.full(len(ghost_quads), 4)]
    cut_mesh = build_halfedges(sizes, np.r_[copy, ghost_quads.ravel()], n_total)
    source = np.r_[copy_source, copy_source[crease_copies], copy_source[single], copy_source[single]]
    # mirror pairs: the crease ghost quad of half-edge A -> B has its corner at B first, at A second
    first_quad = mesh.n_halfedges + 4 * np.arange(len(quads))
    mirror_ghost = np.r_[first_quad + 1, first_quad]
    mirror_real = np.r_[leaving, arriving]
    mirror_toward = np.r_[B, A]
    # the diagonal quad (X, in[X], d, out[X]): its corner at X; the crease quads' corners at X
    diagonal_ghost = mesh.n_halfedges + 4 * len(quads) + 4 * np.arange(single.size)
    real_of = np.full(n_copies, -1, dtype=np.int64)
    real_of[copy] = h_all
    ghost_at_out = np.full(n_copies, -1, dtype=np.int64)
    ghost_at_out[A] = first_quad + 1
    ghost_at_in = np.full(n_copies, -1, dtype=np.int64)
    ghost_at_in[B] = first_quad
    on_cut = np.zeros(n, dtype=bool)
    on_cut[mesh.origin[cut]] = True
    dart = dart_ends(mesh, sharp, tagged_corner) & on_cut
    dart_vertex = np.unique(copy[dart[mesh.origin]])
    crease_vertex = np.where(on_cut[source], source, -1)
    return CreaseSheets(
        mesh=cut_mesh, vertex_source=source, ghost_faces=mesh.n_faces + np.arange(len(ghost_quads)),
        mirror_ghost=mirror_ghost, mirror_real=mirror_real, mirror_toward=mirror_toward, cut_halfedges=leaving, crease_vertex=crease_vertex,
        diagonal_ghost=diagonal_ghost, diagonal_real=real_of[single],
        diagonal_mirrors=np.stack([ghost_at_out[single], ghost_at_in[single]], axis=1),
        diagonal_corner=corner[copy_source[single]],
        cut_edges=edges(cut & sharp), kept_edges=edges(all_sharp & ~cut), dart_edges=edges(all_sharp & ~sharp),
        open_edges=np.sort(names[np.stack([mesh.origin[cut & (mesh.twin < 0)], mesh.dest[cut & (mesh.twin < 0)]], axis=1)], axis=1),
        vertex_name=names[source],
        inexact_vertices=np.unique(names[on_crease & ~exact]), dart_vertex=dart_vertex,
    )


__all__ = ["CreaseSheets", "corner_sectors", "dart_ends", "dart_chains", "seam_corners", "exact_crease_vertices", "cut_crease_sheets"]
