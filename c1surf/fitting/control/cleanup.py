"""Cleaning a remesher's polygon mesh until c1surf's construction takes it without repairs.

A quad remesher (Instant Meshes) can return what ``Surface`` refuses or repairs: coincident
vertices, edges in three faces, interior vertices of valence 2, faces whose orientation disagrees
with their neighbours', tiny faces. ``clean_control_mesh`` fixes each and says what it did, never
refusing the mesh for the remesher's faults. The steps, repeated until nothing changes:

1. weld vertices closer than ``WELD`` of the diagonal (``mesh.weld``) and collapse edges shorter than ``1e-3`` of the median
   edge, and the shortest edge of faces with less than ``1e-4`` of the median area (merged into the
   lower-numbered vertex, at the pair's midpoint); faces left with fewer than three corners or
   visiting a vertex twice go, and so do repeated faces (``mesh.duplicate_faces``);
2. edges in three or more faces: in rounds, on every such edge the face on the most such edges
   goes (the fewest faces that make the mesh manifold, greedily; ties: the face with the most
   boundary edges, a flap standing on the surface); a boundary loop that only the
   dropped faces' vertices make (a hole the drop opened) is filled with one polygon; when the scan
   is closed, every boundary loop of at most ``LARGEST_HOLE`` edges is (the remesher leaves holes at
   thin parts);
3. orientation: neighbours agree (``repair.orientation_flips``), and each closed component encloses
   a positive volume (outward normals); an open component takes the orientation most of the scan's
   nearby triangles have, when a scan is given;
4. pinched vertices (two fans of faces at one vertex) get one vertex per fan
   (``repair.split_pinched_vertices``);
5. interior valence-2 vertices: a *doublet*, a vertex v in two quads (v, a, c, b) and (v, b, d, a),
   is collapsed: both quads go, a and b become one vertex at v's place (regular where a and b had
   valence 4, as in a pure-quad remesh, where they are edge midpoints) and c and d lose one edge each.
   Dissolving v instead (one quad (a, c, b, d)) leaves a and b at valence 3 next to c and d, which
   in a subdivided quad-dominant mesh are often irregular too: two irregular vertices side by side
   need two Doo-Sabin steps instead of one (``refine.fewer_steps``, R2), four times the patches.
   Other valence-2 vertices are dissolved (``mesh.valence_two``), and two triangles that share an
   edge become one quad;
6. components the scan does not have (the remesher's stray pieces at thin parts: more components
   than the scan's, each under a tenth of the faces) are dropped, the smallest first;
7. unused vertices are dropped.
"""
from __future__ import annotations

import numpy as np

from ...mesh.duplicate_faces import repeated_faces
from ...mesh.halfedges import build_halfedges, component_roots
from ...mesh.repair import orientation_flips, reverse_faces, split_pinched_vertices
from ...mesh.valence_two import dissolve_valence_two
from ...mesh.weld import collapse_repeated_corners, weld_vertices

__all__ = ["clean_control_mesh", "cleanup_notes", "edge_keys"]

WELD = 1e-6  # vertices closer than this fraction of the diagonal are welded
SHORT_EDGE = 1e-3  # edges shorter than this fraction of the median edge are collapsed
SMALL_FACE = 1e-4  # faces below this fraction of the median area lose their shortest edge
LARGEST_FILL = 12  # holes the cleanup opened are filled when their loop has at most this many edges
LARGEST_HOLE = 64  # holes of a remesh of a closed scan are filled when their loop has at most this many edges


def edge_keys(face_sizes: np.ndarray, face_vertices: np.ndarray, n_vertices: int):
    """Every corner's edge to the next corner of its face.

    Returns
    -------
    a, b : (H,) int, the corner's vertex and the next corner's
    key : (H,) int64, min(a, b) * n_vertices + max(a, b)
    face : (H,) int, the corner's face
    """
    sizes = np.asarray(face_sizes, dtype=np.int64)
    a = np.asarray(face_vertices, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    face = np.repeat(np.arange(sizes.size), sizes)
    b = a[offsets[face] + (np.arange(a.size) - offsets[face] + 1) % np.maximum(sizes[face], 1)]
    return a, b, np.minimum(a, b) * n_vertices + np.maximum(a, b), face


def _face_areas(sizes: np.ndarray, vertices: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(F,) float: half the length of each face's Newell vector."""
    a, b, _, face = edge_keys(sizes, vertices, points.shape[0])
    newell = np.zeros((sizes.size, 3))
    np.add.at(newell, face, np.cross(points[a], points[b]))
    return 0.5 * np.linalg.norm(newell, axis=1)


def _collapse_short_edges(sizes, vertices, points):
    """Merge the ends of too-short edges (module docstring, step 1). Returns sizes, vertices, points, count."""
    n = points.shape[0]
    a, b, _, face = edge_keys(sizes, vertices, n)
    length = np.linalg.norm(points[a] - points[b], axis=1)
    typical = float(np.median(length[length > 0])) if np.any(length > 0) else 0.0
    short = length < SHORT_EDGE * typical
    area = _face_areas(sizes, vertices, points)
    small = area < SMALL_FACE * float(np.median(area)) if area.size else np.zeros(0, bool)
    if small.any():  # the shortest edge of each small face
        order = np.lexsort((length, face))
        first = order[np.searchsorted(face[order], np.flatnonzero(small))]
        short[first] = True
    short &= a != b
    if not short.any():
        return sizes, vertices, points, 0
    root = component_roots(n, a[short], b[short])  # the lowest vertex of each group of merged vertices
    members = np.bincount(root, minlength=n)
    merged = points.copy()
    sums = np.zeros_like(points)
    np.add.at(sums, root, points)
    group = members > 1
    merged[group] = sums[group] / members[group, None]
    return sizes, root[vertices], merged, int(np.count_nonzero(root != np.arange(n)))


def _drop_bad_faces(sizes, vertices):
    """Drop corners repeating the previous one, then faces with < 3 corners, visiting a vertex twice, or repeated."""
    sizes, vertices, _ = collapse_repeated_corners(sizes, vertices)
    face = np.repeat(np.arange(sizes.size), sizes)
    twice = np.unique(face[_repeats_in_face(face, vertices)])
    keep = sizes >= 3
    keep[twice] = False
    sizes, vertices = sizes[keep], vertices[np.repeat(keep, sizes)]
    copies = repeated_faces(sizes, vertices)
    dropped = int(np.count_nonzero(~keep) + np.count_nonzero(copies))
    return sizes[~copies], vertices[np.repeat(~copies, sizes)], dropped


def _repeats_in_face(face: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """(H,) bool: corners whose vertex another corner of the same face also has."""
    key = face * (int(vertices.max(initial=0)) + 1) + vertices
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    return counts[inverse.ravel()] > 1


def _make_manifold(sizes, vertices, n_vertices):
    """Drop faces until no edge is in three or more (module docstring, step 2).

    Returns sizes, vertices (kept faces), the dropped faces' vertices (k,) and how many faces went.
    """
    keep = np.ones(sizes.size, dtype=bool)
    for _ in range(64):
        kept_sizes = sizes[keep]
        kept_vertices = vertices[np.repeat(keep, sizes)]
        _, _, key, face = edge_keys(kept_sizes, kept_vertices, n_vertices)
        unique, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
        on_bad = counts[inverse.ravel()] > 2
        if not on_bad.any():
            break
        badness = np.bincount(face[on_bad], minlength=kept_sizes.size)
        loose = np.bincount(face[counts[inverse.ravel()] == 1], minlength=kept_sizes.size)
        # on every bad edge, the face on the most bad edges goes; ties: the one with the most boundary
        # edges (a flap standing on the surface), then the later face
        corners = np.flatnonzero(on_bad)
        edge = inverse.ravel()[corners]
        order = np.lexsort((-face[corners], -loose[face[corners]], -badness[face[corners]], edge))
        first = order[np.r_[True, edge[order][1:] != edge[order][:-1]]]
        keep[np.flatnonzero(keep)[np.unique(face[corners[first]])]] = False
    dropped_vertices = np.unique(vertices[np.repeat(~keep, sizes)])
    return sizes[keep], vertices[np.repeat(keep, sizes)], dropped_vertices, int(np.count_nonzero(~keep))


def _fill_opened_holes(sizes, vertices, n_vertices, opened_vertices, longest: int = LARGEST_FILL):
    """One polygon for each boundary loop made only of ``opened_vertices`` (at most ``longest`` edges)."""
    if opened_vertices.size == 0:
        return sizes, vertices, 0
    mesh = build_halfedges(sizes, vertices, n_vertices)
    open_edge = np.flatnonzero(mesh.twin < 0)
    origin, dest = mesh.origin[open_edge], mesh.dest[open_edge]
    outgoing = np.bincount(origin, minlength=n_vertices)
    successor = np.full(n_vertices, -1, dtype=np.int64)
    simple = outgoing[origin] == 1  # a vertex with two open edges leaving it is pinched: not followed
    successor[origin[simple]] = dest[simple]
    opened = np.zeros(n_vertices, dtype=bool)
    opened[opened_vertices] = True
    seen = np.zeros(n_vertices, dtype=bool)
    new_faces = []
    for start in np.flatnonzero(opened & (successor >= 0)):  # the few vertices the drop touched
        if seen[start]:
            continue
        loop = [start]
        seen[start] = True
        v = successor[start]
        while v >= 0 and v != start and not seen[v] and len(loop) <= longest:
            loop.append(v)
            seen[v] = True
            v = successor[v]
        if v == start and len(loop) >= 3 and opened[loop].all():
            new_faces.append(loop[::-1])  # the hole's face runs against its rim's open half-edges
    if not new_faces:
        return sizes, vertices, 0
    return (np.r_[sizes, [len(f) for f in new_faces]], np.r_[vertices, np.concatenate(new_faces)], len(new_faces))


def _orient(sizes, vertices, points, scan=None):
    """Consistent orientation; closed components outward, open ones along the scan (module docstring, step 4).

    Returns vertices, how many faces were reversed.
    """
    n = points.shape[0]
    raw = build_halfedges(sizes, vertices, n)
    flip, non_orientable = orientation_flips(raw)
    if non_orientable.size:  # the construction's double cover takes it; nothing better to do here
        flip[:] = False
    oriented = reverse_faces(sizes, vertices, flip) if flip.any() else vertices
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    a, b, _, face = edge_keys(sizes, oriented, n)
    root = component_roots(n, a, b)
    component = root[oriented[first]]
    mesh = build_halfedges(sizes, oriented, n)
    open_face = np.zeros(sizes.size, dtype=bool)
    open_face[mesh.face[mesh.twin < 0]] = True
    is_open = np.zeros(n, dtype=bool)
    is_open[component[open_face]] = True
    centre = np.zeros((sizes.size, 3))
    np.add.at(centre, face, points[a])
    centre /= sizes[:, None]
    # signed volume of each closed component: the cones from the face centres' to the edges
    volume = np.bincount(component[face], weights=np.einsum("ij,ij->i", centre[face], np.cross(points[a], points[b])),
                         minlength=n)
    wrong = ~is_open & (volume < 0)
    if scan is not None and is_open.any():
        normals = _newell(sizes, oriented, points)
        agree = np.einsum("ij,ij->i", normals, _scan_normals_near(scan, centre))
        vote = np.bincount(component, weights=np.sign(agree), minlength=n)
        wrong |= is_open & (vote < 0)
    turn = wrong[component]
    if non_orientable.size:
        turn[:] = False
    if turn.any():
        oriented = reverse_faces(sizes, oriented, turn)
    return oriented, int(np.count_nonzero(flip ^ turn))


def _newell(sizes, vertices, points):
    a, b, _, face = edge_keys(sizes, vertices, points.shape[0])
    normal = np.zeros((sizes.size, 3))
    np.add.at(normal, face, np.cross(points[a], points[b]))
    return normal


def _scan_normals_near(scan, query):
    """(q, 3) area-weighted normal of the scan triangle whose centroid is nearest each query point."""
    from scipy.spatial import cKDTree

    points, triangles = scan
    corners = points[triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    _, nearest = cKDTree(corners.mean(axis=1)).query(query)
    return normals[nearest]


def _collapse_doublets(sizes, vertices, points):
    """Collapse interior valence-2 vertices between two quads (module docstring, step 5).

    Returns sizes, vertices, points (the merged vertex moved to the doublet's), how many were collapsed.
    """
    n = points.shape[0]
    mesh = build_halfedges(sizes, vertices, n)
    valence = np.bincount(mesh.origin, minlength=n)
    candidates = np.flatnonzero((valence == 2) & (np.bincount(vertices, minlength=n) == 2))
    if candidates.size == 0:
        return sizes, vertices, points, 0
    outgoing = np.flatnonzero(np.isin(mesh.origin, candidates))
    outgoing = outgoing[np.argsort(mesh.origin[outgoing], kind="stable")]
    h1, h2 = outgoing[0::2], outgoing[1::2]  # the two half-edges leaving each candidate, in its two faces
    v = mesh.origin[h1]
    a, b = mesh.dest[h1], mesh.dest[h2]
    ok = ((mesh.twin[h1] >= 0) & (mesh.twin[h2] >= 0) & (sizes[mesh.face[h1]] == 4) & (sizes[mesh.face[h2]] == 4)
          & (mesh.face[h1] != mesh.face[h2]) & (mesh.origin[mesh.prev[h1]] == b) & (mesh.origin[mesh.prev[h2]] == a))
    key = np.minimum(mesh.origin, mesh.dest) * n + np.maximum(mesh.origin, mesh.dest)
    ok &= ~np.isin(np.minimum(a, b) * n + np.maximum(a, b), key)  # a and b not joined already
    taken = np.zeros(n, dtype=bool)
    drop = np.zeros(sizes.size, dtype=bool)
    representative = np.arange(n)
    moved = points.copy()
    count = 0
    for k in np.flatnonzero(ok):  # the few doublets, each apart from the others
        around = [v[k], a[k], b[k], mesh.origin[mesh.next[mesh.next[h1[k]]]], mesh.origin[mesh.next[mesh.next[h2[k]]]]]
        if taken[around].any():
            continue
        taken[around] = True
        drop[[mesh.face[h1[k]], mesh.face[h2[k]]]] = True
        keep, gone = min(a[k], b[k]), max(a[k], b[k])
        representative[gone] = keep
        moved[keep] = points[v[k]]
        count += 1
    if count == 0:
        return sizes, vertices, points, 0
    kept_vertices = representative[vertices[np.repeat(~drop, sizes)]]
    return sizes[~drop], kept_vertices, moved, count


def _pair_triangles(sizes, vertices, n_vertices):
    """Merge triangles that share an edge into quads, each triangle in one pair at most.

    Returns sizes, vertices, how many pairs were merged.
    """
    triangle = sizes == 3
    if np.count_nonzero(triangle) < 2:
        return sizes, vertices, 0
    a, b, key, face = edge_keys(sizes, vertices, n_vertices)
    on_triangle = np.flatnonzero(triangle[face])
    order = on_triangle[np.argsort(key[on_triangle], kind="stable")]
    same = key[order][1:] == key[order][:-1]
    first, second = order[:-1][same], order[1:][same]  # corners of two triangles on one edge
    taken = np.zeros(sizes.size, dtype=bool)
    pairs = []
    for h, g in zip(first, second):  # the few triangle pairs: a greedy matching
        f, e = face[h], face[g]
        if f != e and not taken[f] and not taken[e] and a[h] == b[g]:
            taken[f] = taken[e] = True
            pairs.append((h, g))
    if not pairs:
        return sizes, vertices, 0
    h, g = np.array(pairs).T
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    # triangle f runs a -> b -> x, triangle e runs b -> a -> y: the quad a -> y -> b -> x
    x = vertices[offsets[face[h]] + (h - offsets[face[h]] + 2) % 3]
    y = vertices[offsets[face[g]] + (g - offsets[face[g]] + 2) % 3]
    quads = np.stack([a[h], y, b[h], x], axis=1)
    keep = ~taken
    return (np.r_[sizes[keep], np.full(len(pairs), 4)], np.r_[vertices[np.repeat(keep, sizes)], quads.ravel()],
            len(pairs))


def _drop_stray_components(sizes, vertices, n_vertices, scan, points=None):
    """Drop the smallest components beyond the scan's count, each under a tenth of the faces.

    Returns sizes, vertices, how many components and faces went, and a description of each dropped one
    (``_describe_parts``, with ``points``: (V, 3) float).
    """
    if scan is None:
        return sizes, vertices, 0, 0, []
    a, b, _, _ = edge_keys(sizes, vertices, n_vertices)
    root = component_roots(n_vertices, a, b)
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    component = root[vertices[first]]
    labels, counts = np.unique(component, return_counts=True)
    scan_points, scan_triangles = scan
    scan_root = component_roots(scan_points.shape[0], scan_triangles[:, 0].repeat(2),
                                scan_triangles[:, [1, 2]].ravel())
    extra = labels.size - np.unique(scan_root[scan_triangles[:, 0]]).size
    if extra <= 0:
        return sizes, vertices, 0, 0, []
    order = np.argsort(counts, kind="stable")[:extra]
    order = order[counts[order] < 0.1 * sizes.size]
    drop = np.isin(component, labels[order])
    parts = [] if points is None else _describe_parts(sizes[drop], vertices[np.repeat(drop, sizes)],
                                                      component[drop], points)
    return sizes[~drop], vertices[np.repeat(~drop, sizes)], int(order.size), int(np.count_nonzero(drop)), parts


def _describe_parts(sizes, vertices, component, points) -> list:
    """One phrase per component (``component`` (F,) labels of the faces ``sizes``, ``vertices``): its faces,
    vertices and bounding-box centre."""
    parts = []
    for label in np.unique(component):  # the few dropped components
        corners = vertices[np.repeat(component == label, sizes)]
        box = points[np.unique(corners)]
        centre = ", ".join(f"{c:.4g}" for c in 0.5 * (box.min(axis=0) + box.max(axis=0)))
        parts.append(f"{np.count_nonzero(component == label)} faces, {box.shape[0]} vertices around ({centre})")
    return parts


def _is_closed(triangles: np.ndarray) -> bool:
    """Whether every edge of the triangles is in exactly two of them."""
    a, b, key, _ = edge_keys(np.full(len(triangles), 3), np.asarray(triangles).ravel(), int(np.max(triangles)) + 1)
    return bool(np.all(np.unique(key, return_counts=True)[1] == 2))


def _compact(sizes, vertices, points):
    """Drop unused vertices. Returns vertices renumbered, points, and how many went."""
    used = np.zeros(points.shape[0], dtype=bool)
    used[vertices] = True
    rank = np.cumsum(used) - 1
    return rank[vertices], points[used], int(np.count_nonzero(~used))


def clean_control_mesh(face_sizes, face_vertices, points, scan=None, rounds: int = 6):
    """Clean a polygon mesh until the construction needs no repair (module docstring).

    Parameters
    ----------
    face_sizes : (F,) int
    face_vertices : (sum(face_sizes),) int
    points : (V, 3) float
    scan : (scan_points (m, 3), triangles (t, 3)) or None: orients open components like the scan
    rounds : int, how many times the steps are repeated at most

    Returns
    -------
    face_sizes : (F',) int64
    face_vertices : (sum(face_sizes'),) int64
    points : (V', 3) float
    report : dict of int: ``welded_vertices``, ``collapsed_edges``, ``dropped_faces`` (degenerate or
        repeated), ``non_manifold_faces`` (dropped from edges in three or more faces), ``filled_holes``,
        ``closed_holes`` (of a closed scan's remesh),
        ``split_vertices``, ``flipped_faces``, ``doublets`` (collapsed), ``valence_two`` (dissolved), ``paired_triangles`` (merged into
        quads), ``stray_components`` and ``stray_faces`` (dropped), ``unused_vertices``; and ``stray_parts``,
        a list of str naming each dropped component (faces, vertices, bounding-box centre)

    Long: the cleanup's steps in their one order, each a call, repeated until a round changes nothing;
    splitting it would only hide that order.
    """
    sizes = np.asarray(face_sizes, dtype=np.int64)
    vertices = np.asarray(face_vertices, dtype=np.int64)
    points = np.asarray(points, dtype=np.float64)
    report = dict.fromkeys(("welded_vertices", "collapsed_edges", "dropped_faces", "non_manifold_faces",
                            "filled_holes", "closed_holes", "split_vertices", "flipped_faces", "doublets", "valence_two", "paired_triangles",
                            "stray_components", "stray_faces", "unused_vertices"), 0)
    closed_scan = scan is not None and _is_closed(scan[1])
    for _ in range(rounds):
        before = dict(report)
        sizes, vertices, _, weld = weld_vertices(points, sizes, vertices, WELD)
        report["welded_vertices"] += weld["welded_vertices"]
        report["dropped_faces"] += weld["dropped_faces"]
        sizes, vertices, points, collapsed = _collapse_short_edges(sizes, vertices, points)
        report["collapsed_edges"] += collapsed
        sizes, vertices, dropped = _drop_bad_faces(sizes, vertices)
        report["dropped_faces"] += dropped
        sizes, vertices, opened, dropped = _make_manifold(sizes, vertices, points.shape[0])
        report["non_manifold_faces"] += dropped
        sizes, vertices, filled = _fill_opened_holes(sizes, vertices, points.shape[0], opened)
        report["filled_holes"] += filled
        if closed_scan:
            sizes, vertices, filled = _fill_opened_holes(sizes, vertices, points.shape[0],
                                                         np.arange(points.shape[0]), LARGEST_HOLE)
            report["closed_holes"] += filled
        vertices, points, unused = _compact(sizes, vertices, points)
        report["unused_vertices"] += unused
        vertices, flipped = _orient(sizes, vertices, points, scan)  # before the split: a flipped face is no fan
        report["flipped_faces"] += flipped
        split, source, n_split = split_pinched_vertices(build_halfedges(sizes, vertices, points.shape[0]))
        vertices, points = split, points[source]
        report["split_vertices"] += n_split
        for _ in range(8):  # doublets next to each other go in turn
            sizes, vertices, points, doublets = _collapse_doublets(sizes, vertices, points)
            report["doublets"] += doublets
            if not doublets:
                break
        sizes, vertices, _, dissolved = dissolve_valence_two(sizes, vertices, points.shape[0])
        report["valence_two"] += int(dissolved.size)
        sizes, vertices, paired = _pair_triangles(sizes, vertices, points.shape[0])
        report["paired_triangles"] += paired
        sizes, vertices, stray, stray_faces, parts = _drop_stray_components(sizes, vertices, points.shape[0], scan,
                                                                            points)
        report["stray_components"] += stray
        report["stray_faces"] += stray_faces
        if parts:
            report["stray_parts"] = report.get("stray_parts", []) + parts
        vertices, points, unused = _compact(sizes, vertices, points)
        report["unused_vertices"] += unused - int(dissolved.size)  # the dissolved ones are counted there
        if report == before:
            break
    return sizes, vertices, points, report


CLEANUP_WORDS = {
    "welded_vertices": "welded {} (nearly) coincident vertices",
    "collapsed_edges": "collapsed {} tiny edges",
    "dropped_faces": "dropped {} degenerate or repeated faces",
    "non_manifold_faces": "dropped {} faces on edges in three or more faces",
    "filled_holes": "filled {} holes that drop opened",
    "closed_holes": "closed {} holes the remesher left in a closed scan",
    "split_vertices": "split {} pinched vertices",
    "flipped_faces": "reversed {} faces to orient them consistently and outward",
    "doublets": "collapsed {} interior valence-2 vertices between two quads",
    "valence_two": "dissolved {} other interior valence-2 vertices",
    "paired_triangles": "merged {} pairs of triangles into quads",
    "stray_components": "dropped {} stray components the scan does not have",
}


def _stray_parts_text(report: dict) -> str:
    """The dropped components as the note names them (faces, vertices, bounding-box centre), or ""."""
    parts = report.get("stray_parts") or []
    more = f"; and {len(parts) - 4} more" if len(parts) > 4 else ""
    return f" ({'; '.join(parts[:4])}{more})" if parts else ""


def cleanup_notes(report: dict) -> list[str]:
    """One line saying what the cleanup changed, or nothing when it changed nothing."""
    parts = [words.format(report[key]) + (_stray_parts_text(report) if key == "stray_components" else "")
             for key, words in CLEANUP_WORDS.items() if report.get(key)]
    return [f"control mesh cleanup: {', '.join(parts)}"] if parts else []
