"""A pure-quad control mesh with the scan's topology: decimate, pair, split (fine to coarse).

``decimated_quad_mesh`` makes the control mesh ``c1surf fit`` starts from where Instant Meshes' remesh breaks the
scan's topology (``control_mesh``, ``--remesher auto``), or always with ``--remesher decimate``:

1. **Decimate.** Quadric-error edge collapses (Garland and Heckbert 1997, pymeshlab's
   ``meshing_decimation_quadric_edge_collapse``) of the welded scan down to ``TRIANGLES_PER_FACE`` triangles
   per control face wanted, refusing every collapse that breaks the link condition (``preservetopology``):
   components, Euler characteristic and boundary loops should stay the scan's (Hoppe 1994; the control meshes of
   Ma et al. 2004 are made so). pymeshlab's flag alone does not promise it (measured: a holed sheet's weighted
   decimation pinched 5 vertices, 3 components instead of 1), so every result is checked: the scan's counts, no
   pinched vertex, no edge in three triangles (``_keeps_topology``); where one is pinched, the decimation is redone
   with the scan's region around each pinch weighted ``REDO_WEIGHT`` times more (finer there), then without the
   weights, at larger targets, with the rims kept whole (``keep_rims``), and at worst the scan itself is the mesh. The quadric error puts
   the triangles where the scan bends: a thin leg keeps a ring of edges around it, a flat side gives
   them up. Thin parts weigh more (``thin_part_weights``: the squared ratio of the control edge wanted to 0.6
   times the local thickness, one inward ray per vertex), so a limb keeps control edges below about 0.6 of its
   diameter where the budget allows. Measured (3,000 faces asked; RMS / p99 / max scan to surface, max surface
   to scan, CAD faces): human_man unweighted 1.9e-4 / 7.3e-4 / 2.6e-3, 2.9e-3, 3,657; weighted 1.5e-4 / 5.7e-4 /
   2.6e-3, 1.7e-3, 3,914 (at 1,900 faces asked: 2.4e-4 / 8.7e-4 / 2.8e-3, 3.6e-3, 2,393); scorpion unweighted
   3.3e-4 / 1.1e-3 / 2.6e-3, 5.0e-3, 3,638; weighted 3.1e-4 / 1.0e-3 / 2.7e-3, 5.2e-3, 3,869.
2. **Pair.** Triangles sharing an edge become quads where the quad is good enough (its corner angles within
   ``PAIR_DEGREES`` of 90 degrees, its triangles' normals within 90 degrees), best first, in rounds of a matching that is
   greedy in each neighbourhood (``pair_triangles``). An edge is never removed at a vertex it would leave
   with two edges (an interior valence-2 vertex the construction refuses).
   After the split (3.), a scan vertex farther than a local control edge from the quads (a horn's tip the
   collapses cut off: ``coverage``) has its region redone finer the same way (``decimated_quad_mesh``).
3. **Split.** Every n-gon into n quads at its centroid and edge midpoints (``split_faces``): pure quads,
   and every vertex that is not a face centre or an edge midpoint has only those around it, so the
   irregular vertices lie apart and one Doo-Sabin step suffices on a closed mesh (four patches a quad). The new
   points are projected onto the scan, except a midpoint over a hole or across a thin part (moved more than half its
   distance to the nearest decimated vertex) or one landing on another point: the cleanup would weld those into a
   pinch (``projected_new_points``).

Measured (welded scans of ``../shared/scans``, 3,000 faces asked: 2,924-2,976 quads): components, Euler
characteristic and rims of all fifteen kept (boot: genus 12, Euler -22; plane_holes: 27 rims, Euler -25);
1.3-7.5 s on the loaded 2-core machine, decimation, pairing, split, projection and cleanup (hammer's 60k
triangles the longest). Instant Meshes' cleaned remesh at 3,000 faces changes boot's (Euler 2) and
plane_holes' (Euler -1, 3 rims), and needs stray pieces dropped or pinches split on scorpion and human_man
(docs/fit.md).
"""
from __future__ import annotations

import time

import numpy as np

from ...mesh.topology_counts import topology_counts
from .cleanup import edge_keys

__all__ = ["mesh_topology", "decimate_scan", "pair_triangles", "split_faces", "decimated_quad_mesh"]

# a pair of triangles becomes a quad when every corner angle is within PAIR_DEGREES of 90 degrees and the two
# triangles' normals differ by less than 90 degrees (cosine above PAIR_PLANAR). Each triangle left alone becomes three
# quads around a valence-3 vertex: three bicubic patches, three CAD faces. Measured on scorpion at 3,000 faces
# (1,320 decimated triangles; control faces, CAD faces, scan-to-surface RMS): 50 degrees and cosine 0.5: 368 alone,
# 3,008 faces, 4,632 CAD faces (fitted at 3,058 faces: 5,052 CAD faces, RMS 3.05e-4); 70 and 0: 214 alone, 3,773 CAD
# faces; 85 and 0: 192 alone, 2,832 faces, 3,638 CAD faces, RMS 3.29e-4
PAIR_DEGREES = 85.0
PAIR_PLANAR = 0.0
PAIR_ROUNDS = 30  # rounds of the local matching at most
THIN_EDGE = 0.6  # a limb of diameter d wants a control edge below 0.6 d (a closed quadratic B-spline: 1e-3 of d)
THIN_MOST = 10.0  # the largest ratio of control edge to that the weights follow
RIM_TRIES = 3  # decimations with the rims collapsed too, at 1, 1.5 and 2.25 times the target
TRIANGLES_PER_FACE = 0.46  # decimated triangles per control face wanted (a pair gives 4 quads, a lone triangle 3)
REDO_ROUNDS = 3  # decimations redone finer where the last one pinched the scan or left it uncovered
# the last redo also decimates to this many times the triangles. Measured at 3,000 faces asked: scorpion with the
# weights alone (three redos) 2,952 faces, one vertex 1.02 edges away; growing by 1.25 from the second redo on,
# 3,690 faces (more CAD faces); boot at 1,200 needs two redos of the weights alone, hand_closed and koala one
REDO_GROWTH = 1.1
REDO_WEIGHT = 100.0  # how much more the scan's vertices weigh in a region redone finer


def mesh_topology(face_sizes, face_vertices, n_vertices: int) -> dict:
    """``components``, ``euler`` (V - E + F over the vertices faces use) and ``rims`` (boundary loops) of a polygon
    mesh: ``mesh.topology_counts``' counts, the ones the fit report compares."""
    counts = topology_counts(face_sizes, face_vertices, n_vertices)
    return {"components": counts.components, "euler": counts.euler_characteristic, "rims": counts.rims}


def decimate_scan(points: np.ndarray, triangles: np.ndarray, target: int, quality=None, keep_rims: bool = True):
    """Quadric-error decimation of a triangle mesh that keeps its topology (module docstring, step 1).

    Parameters
    ----------
    points : (m, 3) float; triangles : (t, 3) int, a manifold triangle mesh
    target : int > 0, the triangles wanted
    quality : (m,) float > 0 or None, a weight per vertex: collapses at vertices of large weight cost more
    keep_rims : bool, no collapse of a boundary edge (else the rims are decimated too, and a rim may close up)

    Returns
    -------
    points : (m', 3) float64; triangles : (t', 3) int64, t' about ``target`` (more when the topology
    forbids going lower)
    """
    import pymeshlab

    from ...console import quiet_stdout

    arrays = [np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(triangles, dtype=np.int32)]
    mesh = pymeshlab.Mesh(*arrays) if quality is None else pymeshlab.Mesh(
        *arrays, v_scalar_array=np.ascontiguousarray(quality, dtype=np.float64))
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(mesh)
    with quiet_stdout():
        meshes.meshing_decimation_quadric_edge_collapse(
            targetfacenum=int(target), preservetopology=True, preserveboundary=keep_rims, boundaryweight=1.0,
            qualitythr=0.5, optimalplacement=True, planarquadric=True, autoclean=True,
            qualityweight=quality is not None)
    out = meshes.current_mesh()
    return np.asarray(out.vertex_matrix(), dtype=np.float64), np.asarray(out.face_matrix(), dtype=np.int64)


def thickness(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(m,) float: the scan's thickness at each vertex, the distance along the inward vertex normal to the first
    triangle hit (a one-ray shape diameter; the bounding-box diagonal where the ray leaves the mesh).

    points : (m, 3) float; triangles : (t, 3) int, outward
    """
    import trimesh

    from ..system import vertex_normals

    normals = vertex_normals(points, triangles)
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    mesh = trimesh.Trimesh(points, triangles, process=False)
    origins = points - 1e-6 * diagonal * normals
    where, ray, _ = mesh.ray.intersects_location(origins, -normals, multiple_hits=False)
    out = np.full(points.shape[0], diagonal)
    hit = np.linalg.norm(where - origins[ray], axis=1)
    np.minimum.at(out, ray, np.maximum(hit, 1e-9 * diagonal))
    return out


def thin_part_weights(points: np.ndarray, triangles: np.ndarray, faces: int) -> np.ndarray:
    """(m,) float >= 1: the decimation's vertex weights, (edge / (THIN_EDGE x thickness))^2 where the scan is
    thinner than the control edge wants (``edge``: the control edge of ``faces`` squares over the scan's area), else 1.
    """
    corners = points[triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    edge = np.sqrt(area / max(faces, 1))
    ratio = edge / (THIN_EDGE * thickness(points, triangles))
    return np.clip(ratio, 1.0, THIN_MOST) ** 2


def manifold_faults(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(k,) int: the vertices of a triangle mesh where it is not a manifold: pinched vertices (more than one fan of
    triangles) and the ends of edges in three or more triangles (what a collapse across a thin part leaves)."""
    from ...mesh.halfedges import build_halfedges
    from ...mesh.repair import split_pinched_vertices

    n = points.shape[0]
    a, b, key, _ = edge_keys(np.full(triangles.shape[0], 3), triangles.ravel(), n)
    unique, counts = np.unique(key, return_counts=True)
    crowded = unique[counts > 2]
    faults = [crowded // n, crowded % n]
    if crowded.size == 0:
        _, source, split = split_pinched_vertices(build_halfedges(np.full(triangles.shape[0], 3), triangles.ravel(), n))
        if split:
            faults.append(np.flatnonzero(np.bincount(source, minlength=n) > 1))
    return np.unique(np.concatenate(faults)).astype(np.int64)


def _keeps_topology(want: dict, points: np.ndarray, triangles: np.ndarray):
    """(kept, faults): whether a decimation has the counts ``want`` with no pinched vertex and no edge in three
    triangles, and the vertices where it is not a manifold (``manifold_faults``)."""
    faults = manifold_faults(points, triangles)
    got = mesh_topology(np.full(triangles.shape[0], 3), triangles.ravel(), points.shape[0])
    return got == want and faults.size == 0, faults


def heavier_near(quality: np.ndarray, scan_points: np.ndarray, where: np.ndarray, radius: float) -> np.ndarray:
    """``quality`` (m,) with the scan vertices within ``radius`` of any of ``where`` (k, 3) weighted
    ``REDO_WEIGHT`` times more: the decimation redone finer in that region."""
    from scipy.spatial import cKDTree

    heavier = np.array(quality, dtype=np.float64)
    where = np.asarray(where, dtype=np.float64).reshape(-1, 3)
    if where.shape[0] == 0:
        return heavier
    # each scan vertex's nearest fault within the radius (the bound inclusive): O(m log k), where the balls around
    # k faults overlap (measured: boot at 300 faces, 18 s of a 42 s fit listing the balls' vertices one by one)
    distance = cKDTree(where).query(scan_points, distance_upper_bound=np.nextafter(radius, np.inf))[0]
    heavier[np.isfinite(distance)] *= REDO_WEIGHT
    return heavier


def _mean_edge(points: np.ndarray, triangles: np.ndarray) -> float:
    a, b, _, _ = edge_keys(np.full(triangles.shape[0], 3), triangles.ravel(), points.shape[0])
    return float(np.mean(np.linalg.norm(points[a] - points[b], axis=1))) if a.size else 0.0


def _decimate_keeping_topology(points, triangles, target: int, quality):
    """``decimate_scan`` at ``target`` triangles whose result has the scan's components, Euler characteristic and
    rims, no pinched vertex and no edge in three triangles (``_keeps_topology``; pymeshlab's ``preservetopology``
    alone does not promise it: measured, a holed sheet's weighted decimation pinched 5 vertices). Tried in turn: the
    weights and the rims decimated too, redone up to ``REDO_ROUNDS`` times with the scan's region within two mean
    decimated edges of each pinch weighted ``REDO_WEIGHT`` times more (finer there); without the weights (measured:
    pymeshlab's weighted collapses can break an open mesh's topology, a cut twisted torus to Euler 6 instead of 1);
    at 1.5 and 2.25 times the target; with no boundary edge collapsed (``keep_rims``); at 1.5 ** k times the target
    (k = 3 .. 6) with no boundary edge collapsed; the scan itself, which has its own topology."""
    want = mesh_topology(np.full(triangles.shape[0], 3), triangles.ravel(), points.shape[0])
    weights = quality
    for _ in range(REDO_ROUNDS if quality is not None else 0):
        decimated = decimate_scan(points, triangles, target, weights, False)
        kept, faults = _keeps_topology(want, *decimated)
        if kept:
            return decimated
        if faults.size == 0:
            break  # the counts differ, but nowhere to point at: the tries below
        weights = heavier_near(weights, points, decimated[0][faults], 2 * _mean_edge(*decimated))
    tries = [(None, 1.5 ** k, False) for k in range(RIM_TRIES)] + [(None, 1.5 ** k, True) for k in (0, 3, 4, 5, 6)]
    for weights, scale, keep_rims in tries:
        if target * scale >= triangles.shape[0]:
            break
        decimated = decimate_scan(points, triangles, int(target * scale), weights, keep_rims)
        if _keeps_topology(want, *decimated)[0]:
            return decimated
    return points, triangles


def _corner_cosines(quads: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(k, 4) float: the cosine of each corner angle of quads (k, 4)."""
    p = points[quads]
    before = np.roll(p, 1, axis=1) - p
    after = np.roll(p, -1, axis=1) - p
    norm = np.linalg.norm(before, axis=2) * np.linalg.norm(after, axis=2)
    return np.einsum("ijk,ijk->ij", before, after) / np.maximum(norm, 1e-300)


def _candidate_pairs(triangles: np.ndarray, points: np.ndarray):
    """The pairs of triangles across an interior edge that make a good quad (corner angles within ``PAIR_DEGREES`` of
    90, normals within 90 degrees): (f, e) their triangles, (u, v) the edge's ends, (k, 4) quads, (k,) score (the
    largest corner angle off 90 degrees), and every corner's edge key (``edge_keys``)."""
    t, n = triangles.shape[0], points.shape[0]
    a, b, key, face = edge_keys(np.full(t, 3), triangles.ravel(), n)
    order = np.argsort(key, kind="stable")
    same = key[order][1:] == key[order][:-1]
    h, g = order[:-1][same], order[1:][same]  # the two corners of an interior edge: a[h] -> b[h], a[g] -> b[g]
    keep = a[h] == b[g]  # consistently oriented
    h, g = h[keep], g[keep]
    # triangle face[h] runs a -> b -> x, face[g] runs b -> a -> y: the quad a -> y -> b -> x
    x = triangles.ravel()[3 * face[h] + (h - 3 * face[h] + 2) % 3]
    y = triangles.ravel()[3 * face[g] + (g - 3 * face[g] + 2) % 3]
    quads = np.stack([a[h], y, b[h], x], axis=1)
    angle_off = np.abs(np.degrees(np.arccos(np.clip(_corner_cosines(quads, points), -1, 1))) - 90.0).max(axis=1)
    normal = np.cross(points[b[h]] - points[a[h]], points[x] - points[a[h]])
    other = np.cross(points[a[h]] - points[b[h]], points[y] - points[b[h]])
    planar = np.einsum("ij,ij->i", normal, other) / np.maximum(
        np.linalg.norm(normal, axis=1) * np.linalg.norm(other, axis=1), 1e-300)
    good = (angle_off < PAIR_DEGREES) & (planar > PAIR_PLANAR)
    return face[h][good], face[g][good], a[h][good], b[h][good], quads[good], angle_off[good], key


def pair_triangles(triangles: np.ndarray, points: np.ndarray):
    """Triangles paired into quads (module docstring, step 2).

    Parameters
    ----------
    triangles : (t, 3) int, a consistently oriented manifold mesh; points : (m, 3) float

    Returns
    -------
    quads : (q, 4) int64, counter-clockwise as the triangles; lone : (t - 2q, 3) int64, the triangles left
    """
    t, n = triangles.shape[0], points.shape[0]
    f, e, u, v, quads, score, key = _candidate_pairs(triangles, points)
    valence = _vertex_degrees(key, n)
    taken = np.zeros(t, dtype=bool)
    chosen = np.zeros(score.size, dtype=bool)
    rank = np.empty(score.size, dtype=np.int64)
    # first the edges between vertices with the most edges beyond four (removing one brings both nearer valence 4,
    # regular after the split), then the best quads: scorpion at 3,000 faces 3,683 CAD faces instead of 3,869, spot
    # 3,126 instead of 3,524
    excess = np.maximum(valence - 4, 0)
    rank[np.lexsort((np.arange(score.size), score, -(excess[u] + excess[v])))] = np.arange(score.size)
    for floor in (4, 3):  # first only where both ends keep four edges or more, then where they keep three
        for _ in range(PAIR_ROUNDS):
            open_ = ~chosen & ~taken[f] & ~taken[e] & (valence[u] > floor) & (valence[v] > floor)
            if not open_.any():
                break
            idx = np.flatnonzero(open_)
            # an edge is taken when it ranks first among the open edges of both its triangles and both its ends
            best_face = np.full(t, np.iinfo(np.int64).max)
            np.minimum.at(best_face, f[idx], rank[idx])
            np.minimum.at(best_face, e[idx], rank[idx])
            best_vertex = np.full(n, np.iinfo(np.int64).max)
            np.minimum.at(best_vertex, u[idx], rank[idx])
            np.minimum.at(best_vertex, v[idx], rank[idx])
            r = rank[idx]
            win = idx[(best_face[f[idx]] == r) & (best_face[e[idx]] == r) & (best_vertex[u[idx]] == r)
                      & (best_vertex[v[idx]] == r)]
            if win.size == 0:
                break
            chosen[win] = True
            taken[f[win]] = taken[e[win]] = True
            np.subtract.at(valence, u[win], 1)
            np.subtract.at(valence, v[win], 1)
    return quads[chosen].astype(np.int64), triangles[~taken].astype(np.int64)


def _vertex_degrees(key: np.ndarray, n: int) -> np.ndarray:
    """(n,) int: edges at each vertex, from the half-edge keys (min * n + max) of a mesh."""
    unique = np.unique(key)
    return np.bincount(np.r_[unique // n, unique % n], minlength=n)


def split_faces(face_sizes: np.ndarray, face_vertices: np.ndarray, points: np.ndarray):
    """Every n-gon split into n quads at its centroid and edge midpoints (module docstring, step 3).

    Parameters
    ----------
    face_sizes : (F,) int; face_vertices : (sum(face_sizes),) int; points : (V, 3) float

    Returns
    -------
    quads : (sum(face_sizes), 4) int64, corner i of face f -> (v_i, m_i, c_f, m_{i-1}); points : the old
    points, then one per edge (its midpoint, edges in increasing key order), then one per face (its centroid)
    """
    sizes = np.asarray(face_sizes, dtype=np.int64)
    vertices = np.asarray(face_vertices, dtype=np.int64)
    n = points.shape[0]
    a, b, key, face = edge_keys(sizes, vertices, n)
    unique, edge = np.unique(key, return_inverse=True)
    midpoint = n + edge
    centre = n + unique.size + face
    centroid = np.zeros((sizes.size, 3))
    np.add.at(centroid, face, points[vertices])
    centroid /= sizes[:, None]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    corner = np.arange(vertices.size)
    previous = offsets[face] + (corner - offsets[face] - 1) % sizes[face]
    quads = np.stack([vertices, midpoint, centre, midpoint[previous]], axis=1)
    new_points = np.concatenate([points, 0.5 * (points[unique // n] + points[unique % n]), centroid])
    return quads, new_points


def projected_new_points(new_points: np.ndarray, old_points: np.ndarray, scan_points, scan_triangles) -> np.ndarray:
    """``new_points`` (edge midpoints and face centroids of the decimated mesh) moved onto the scan, except where
    that moves one more than half its distance to the nearest decimated vertex (a midpoint over a hole or across a
    thin part, whose projection lands on the far rim or the far side) or onto the place of another point (the
    cleanup would weld the two into a pinch): those stay where they are."""
    from scipy.spatial import cKDTree

    from ..deviation import closest_on_triangles

    moved, closest = closest_on_triangles(new_points, scan_points, scan_triangles)
    room = cKDTree(old_points).query(new_points)[0]
    out = np.where((moved <= 0.5 * room)[:, None], closest, new_points)
    diagonal = float(np.linalg.norm(np.ptp(scan_points, axis=0)))
    every = np.concatenate([old_points, out])
    pairs = cKDTree(every).query_pairs(1e-5 * diagonal, output_type="ndarray")
    clash = pairs[pairs >= old_points.shape[0]] - old_points.shape[0]
    out[clash] = new_points[clash]
    return out


def _quads(points, triangles, scan):
    """(quad points, quads, paired, lone): the decimated triangles paired and split (steps 2 and 3), the new points
    on the scan (``projected_new_points``)."""
    quads, lone = pair_triangles(triangles, points)
    sizes = np.r_[np.full(quads.shape[0], 4), np.full(lone.shape[0], 3)]
    split, split_points = split_faces(sizes, np.r_[quads.ravel(), lone.ravel()], points)
    n = points.shape[0]
    split_points[n:] = projected_new_points(split_points[n:], points, *scan)
    return split_points, split, quads.shape[0], lone.shape[0]


def decimated_quad_mesh(points: np.ndarray, triangles: np.ndarray, faces: int, quality=None):
    """A pure-quad mesh of about ``faces`` quads with the topology of the triangle mesh (module docstring).

    Where the quad mesh leaves a scan vertex farther than a local control edge (``coverage``: a horn's tip cut off
    by the collapses), the decimation is redone with the scan weighted ``REDO_WEIGHT`` times more within two mean
    decimated edges of those vertices, ``REDO_ROUNDS`` times at most, the last to ``REDO_GROWTH`` times the triangles.

    Parameters
    ----------
    points : (m, 3) float; triangles : (t, 3) int, the welded scan, a manifold
    faces : int > 0, the quads wanted
    quality : (m,) float > 0 or None, the decimation's per-vertex weight (``decimate_scan``; None:
        ``thin_part_weights``)

    Returns
    -------
    points : (V, 3) float64; quads : (F, 4) int64; info : dict, ``decimated_triangles``, ``paired``,
    ``lone_triangles``, ``redone`` (decimations redone for coverage), ``seconds``
    """
    from .coverage import mesh_coverage

    start = time.perf_counter()
    scan = (points, triangles)
    target = max(4, int(round(TRIANGLES_PER_FACE * faces)))
    if quality is None:
        quality = thin_part_weights(points, triangles, faces)
    redone = 0
    while True:
        decimated = _decimate_keeping_topology(points, triangles, target, quality) if target < triangles.shape[0] \
            else scan
        quad_points, quads, paired, lone = _quads(*decimated, scan)
        far = mesh_coverage(*scan, np.full(quads.shape[0], 4), quads.ravel(), quad_points, rims=False).far
        if not far.any() or redone >= REDO_ROUNDS or decimated is scan:
            break
        quality = heavier_near(quality, points, points[far], 2 * _mean_edge(*decimated))
        redone += 1
        target = int(target * (REDO_GROWTH if redone == REDO_ROUNDS else 1.0))  # the last redo: a larger budget too
    info = {"decimated_triangles": int(decimated[1].shape[0]), "paired": int(paired), "lone_triangles": int(lone),
            "redone": redone, "seconds": time.perf_counter() - start}
    return quad_points, quads, info
