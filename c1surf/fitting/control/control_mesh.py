"""The control mesh a scan is fitted with: a quad remesh, cleaned, with the scan's sharp edges tagged.

Remesher: Instant Meshes (Jakob et al. 2015) through ``pynanoinstantmeshes``: wheels for the
usual platforms, a field-aligned quad remesh of a 69k-triangle scan in about 2 s, crease
alignment (``creaseAngle``) and a deterministic mode. It returns pure quads: its quad-dominant
mesh of about ``vertex_count`` vertices subdivided once (each n-gon into n quads), so about four
times as many faces as its target. ``control_mesh_from_scan`` asks for a quarter of the requested
faces and, when the count lands more than ``FACE_SLACK`` off, asks once more with the target scaled
by how far it was off. What else there is: pymeshlab (a bench-only dependency here) has isotropic
triangle remeshing and pairs triangles into quad-dominant meshes, with no field alignment and no
face-count control; QuadWild and Rhino's QuadRemesh have no maintained Python wheel.

Doo-Sabin steps: a mesh (closed or open, with C0 creases or not) whose irregular vertices and non-quad
faces lie apart needs one step instead of two (``refine.fewer_steps``), a quarter of the patches. A pure-quad remesh has its
irregular vertices apart; the cleanup's doublet collapse keeps them so (``cleanup``). When the
cleaned mesh still needs two (holes the remesher left at thin parts), the remesh is tried again
with the target 4 % up, then 4 % down (``RETRY_SCALES``), and the mesh needing fewest steps is kept.

QuadriFlow (Huang et al. 2018, ``quadriflow``): the same kind of fields, its singularities then repaired by a
minimum-cost flow, so its quads have far fewer irregular vertices (each of valence n costs n CAD faces). It is asked
for a quarter of the faces and every quad split in four (``_quadriflow_layout``), as Instant Meshes' pure-quad mode
splits its quad-dominant mesh: the irregular vertices lie apart, one Doo-Sabin step. It resolves no part thinner
than its edge, so it is asked again at 1.25, 1.5 and 2 times the faces while its layout leaves part of the scan
uncovered or changes its counts (``FLOW_SCALES``; at twice the faces it keeps lionstatue's five handles and
demosthenes' rim, measured: 1,410 and 1,010 STEP faces against 3,740 and 1,801).

The choice (``--remesher auto``, ``_chosen_layout``): counts can agree by accident (a dropped horn and a closed
hole), so a candidate is held against the scan on the counts (components, Euler characteristic, rims, and the
cleanup's repairs of stray pieces, holes and pinches) and on the geometry (``coverage``: every scan vertex within
about a local control edge, every rim matched by one of about its length and position). QuadriFlow's layout is kept
when it passes both (with ``crease_angle``, aligned by its sharp flag, and only where that flag sees every line
asked for: ``_flow_sees``); else Instant Meshes' remesh when it passes both; else the decimated scan
(``decimated_quads``), which passes both on all 22 scans of ``../shared/scans``; when neither does, the one that
leaves less of the scan's area uncovered, and the note names what differs and where. The scan is made a manifold first (``manifold_scan``: pinched vertices split into fans, edges
in three or more triangles cut into sheets, as ``convert`` prepares a mesh), so the control mesh is one too.

Sharp features (``crease_angle``): the scan's edges whose faces meet at more than the angle
(``mesh.feature_edges``) are the feature lines. The remesher aligns to them; a control edge
follows a line when its two ends and its midpoint lie within a quarter of the median control edge
of the line and it runs along the line (within ``ALONG_DEGREES``); such edges are tagged
infinitely sharp (``ControlMesh.features``). A tagged line that stops short (a vertex on one tagged
edge) is extended there by the edge nearest the line within twice both allowances, for up to
``EXTEND_ROUNDS`` edges. Loose ends left are darts, which are C0 up to their end (the dart's hole,
``construction.stencils.holes.dart``): the lines are not bridged shut (until session 9 they were joined in pairs
by short paths near the line, because a dart then kept its line G1). The control faces of crease sectors
of three or more faces are merged (``mesh.creases.sectors``, as ``convert`` does), so every tagged line
is a C0 seam.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ...console import quiet_stdout
from ...construction.features import INFINITELY_SHARP, SharpFeatures
from ...mesh.creases.sectors import merge_crease_sectors
from ...mesh.valence_two import dissolve_valence_two
from ...mesh.feature_edges import feature_edges
from ...mesh.weld import weld_vertices
from .cleanup import clean_control_mesh, cleanup_notes, edge_keys
from .decimated_quads import decimated_quad_mesh, mesh_topology, projected_new_points, split_faces
from .quadriflow import available as quadriflow_available

__all__ = ["ControlMesh", "control_mesh_from_scan", "quad_remesh", "tag_feature_edges", "scan_feature_edges"]

FACES_PER_TARGET_VERTEX = 4.0  # pure-quad output: about four faces per vertex asked for
FACE_SLACK = 0.15  # a second remesh when the count lands further than this from the request
NEAR_LINE = 0.25  # of the median control edge: how near a feature line a tagged edge's points lie
ALONG_DEGREES = 25.0  # largest angle between a tagged edge and the feature line it follows
EXTEND_ROUNDS = 8  # rounds of extending tagged lines from their loose ends
QUADRIFLOW_SHARP = 60.0  # degrees between face normals: the edges QuadriFlow aligns to with its sharp flag (fixed)
FLOW_SCALES = (1.0, 1.25, 1.5, 2.0)  # QuadriFlow's face targets, in turn until its layout keeps and covers the scan
RETRY_SCALES = (1.0, 1.04, 0.96)  # remesh targets tried in turn until one Doo-Sabin step suffices
REMESHERS = ("auto", "quadriflow", "instant", "decimate", "simplify")
# the cleanup's repairs that say Instant Meshes broke the scan's topology at a thin part
TOPOLOGY_REPAIRS = {"stray_components": "stray pieces dropped", "closed_holes": "holes closed",
                    "split_vertices": "pinched vertices split", "non_manifold_faces": "faces on non-manifold edges dropped"}


@dataclass(frozen=True, eq=False)
class ControlMesh:
    """A polygon control mesh for the construction.

    face_sizes : (F,) int64
    face_vertices : (sum(face_sizes),) int64
    points : (V, 3) float
    crease_edges : (k, 2) int64, vertex pairs tagged infinitely sharp (smaller first)
    notes : list of str, ``c1surf: note:`` lines (what the cleanup changed, the creases found)
    report : dict, numbers for the fit report (requested and remeshed faces, seconds, cleanup counts)
    """

    face_sizes: np.ndarray
    face_vertices: np.ndarray
    points: np.ndarray
    crease_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    notes: list = field(default_factory=list)
    report: dict = field(default_factory=dict)

    @property
    def n_faces(self) -> int:
        return int(self.face_sizes.size)

    def features(self) -> SharpFeatures | None:
        """The crease edges as infinitely sharp ``SharpFeatures`` (None when there are none)."""
        if self.crease_edges.shape[0] == 0:
            return None
        return SharpFeatures(self.crease_edges, np.full(self.crease_edges.shape[0], INFINITELY_SHARP))

    def with_points(self, points: np.ndarray) -> "ControlMesh":
        """The same connectivity and tags at new points (the fitted ones)."""
        return ControlMesh(self.face_sizes, self.face_vertices, np.asarray(points, dtype=np.float64),
                           self.crease_edges, list(self.notes), dict(self.report))


def _merged_sectors(sizes: np.ndarray, vertices: np.ndarray, points: np.ndarray, creases: np.ndarray):
    """(face sizes, face vertices, points, crease edges, faces merged): the faces of crease sectors too large for
    an exact C0 crease merged (``mesh.creases.sectors``, as ``convert`` does), so that every tagged line, darts
    included, is a C0 seam; an interior vertex that this leaves in two faces (next to a corner) is dissolved
    (``mesh.valence_two``, never a seam's) and the points renumbered without it."""
    merge = merge_crease_sectors(sizes, vertices, points.shape[0], creases, np.zeros(0, dtype=np.int64))
    if merge is None or len(merge.lost_creases):
        return sizes, vertices, points, creases, 0
    seam = np.zeros(points.shape[0], dtype=bool)
    seam[creases.ravel()] = True
    merged_sizes, merged_vertices, _, gone = dissolve_valence_two(merge.face_sizes, merge.face_vertices, points.shape[0],
                                                                  keep=seam)
    used = np.zeros(points.shape[0], dtype=bool)
    used[merged_vertices] = True
    rank = np.cumsum(used) - 1
    return (merged_sizes.astype(np.int64), rank[merged_vertices].astype(np.int64), points[used],
            rank[creases].astype(np.int64), int(merge.merged_faces))

def _welded_scan(points: np.ndarray, triangles: np.ndarray):
    """The scan with coincident vertices welded (split texture seams would make the remesher see pieces)."""
    sizes, vertices, _, _ = weld_vertices(points, np.full(triangles.shape[0], 3), triangles.ravel())
    triangles = vertices.reshape(-1, 3) if np.all(sizes == 3) else triangles
    used = np.zeros(points.shape[0], dtype=bool)
    used[triangles] = True
    rank = np.cumsum(used) - 1
    return points[used], rank[triangles]


def manifold_scan(points: np.ndarray, triangles: np.ndarray):
    """(points, triangles, faults): the scan as a manifold, as ``convert`` prepares a mesh: edges in three or more
    triangles cut into sheets (``mesh.creases.non_manifold``), then, on the consistently oriented triangles
    (``repair.orientation_flips``: fans are followed along the orientation), pinched vertices split into one vertex
    per fan (``repair.split_pinched_vertices``); the copies sit at the same places. ``faults``: how many vertices
    were copied (0: the scan was a manifold, returned as it is). The control mesh is made of this, so that its counts
    are the manifold scan's and nothing in it is pinched."""
    from ...mesh.creases.non_manifold import split_non_manifold_edges
    from ...mesh.halfedges import build_halfedges
    from ...mesh.repair import orientation_flips, reverse_faces, split_pinched_vertices

    sizes = np.full(triangles.shape[0], 3)
    sheets = split_non_manifold_edges(sizes, triangles.ravel(), points.shape[0])
    corners, source = (triangles.ravel(), np.arange(points.shape[0])) if sheets is None else (
        sheets.face_vertices, sheets.vertex_source)
    flip, non_orientable = orientation_flips(build_halfedges(sizes, corners, source.size))
    if flip.any() and not non_orientable.size:
        corners = reverse_faces(sizes, corners, flip)
    split, fan_source, pinched = split_pinched_vertices(build_halfedges(sizes, corners, source.size))
    if sheets is None and not pinched:
        return points, triangles, 0
    source = source[fan_source]
    return points[source], split.reshape(-1, 3).astype(np.int64), int(source.size - np.unique(source).size)


def quad_remesh(points: np.ndarray, triangles: np.ndarray, faces: int, crease_angle: float | None = None):
    """Instant Meshes' pure-quad remesh of a triangle mesh with about ``faces`` faces.

    Parameters
    ----------
    points : (m, 3) float
    triangles : (t, 3) int
    faces : int > 0, the face count asked for
    crease_angle : float degrees or None, align to edges sharper than this

    Returns
    -------
    quad_points : (V, 3) float64
    quads : (F, 4) int64
    info : dict, ``target_vertices`` (the last one asked), ``remeshes``, ``seconds``
    """
    from pynanoinstantmeshes import remesh

    start = time.perf_counter()
    verts = np.ascontiguousarray(points, dtype=np.float32)
    tris = np.ascontiguousarray(triangles, dtype=np.uint32)
    target = max(4, int(round(faces / FACES_PER_TARGET_VERTEX)))
    options = dict(creaseAngle=float(crease_angle or 0.0), deterministic=True)
    remeshes = 0
    for _ in range(2):
        with quiet_stdout():
            quad_points, quads = remesh(verts, tris, target, **options)
        remeshes += 1
        got = quads.shape[0]
        if got and abs(got - faces) <= FACE_SLACK * faces:
            break
        target = max(4, int(round(target * faces / max(got, 1))))
    info = {"target_vertices": target, "remeshes": remeshes, "seconds": time.perf_counter() - start}
    return np.asarray(quad_points, dtype=np.float64), np.asarray(quads, dtype=np.int64), info


def _check_area(points: np.ndarray, triangles: np.ndarray) -> None:
    """Raise ValueError for a scan without area (Instant Meshes never returns on one: measured, collinear points)."""
    corners = points[triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0))) if points.size else 0.0
    if not area > 1e-12 * diagonal ** 2:
        raise ValueError(f"the scan's {len(triangles)} triangles have no area (its points lie on a line or in one "
                         "point): there is no surface to fit")


def _doo_sabin_steps(sizes, vertices, n_vertices) -> int:
    """The fewest Doo-Sabin steps the construction needs on this mesh (``refinements="auto"``, open meshes too)."""
    from ...construction.topology import fewest_refinements

    return fewest_refinements(sizes, vertices, n_vertices)


def scan_feature_edges(points: np.ndarray, triangles: np.ndarray, crease_angle: float) -> np.ndarray:
    """(k, 2) int: the scan's edges whose triangles meet at more than ``crease_angle`` degrees."""
    return feature_edges(np.full(triangles.shape[0], 3), triangles.ravel(), points, crease_angle)


def tag_feature_edges(face_sizes, face_vertices, points, line_points, line_edges) -> np.ndarray:
    """The control edges that follow a feature line (module docstring).

    Parameters
    ----------
    face_sizes, face_vertices, points : the control mesh
    line_points : (m, 3) float, the scan's points
    line_edges : (k, 2) int, the feature edges on them

    Returns
    -------
    (e, 2) int64, control edges (smaller vertex first), in increasing order
    """
    from scipy.spatial import cKDTree

    a, b, key, _ = edge_keys(face_sizes, face_vertices, points.shape[0])
    key, first = np.unique(key, return_index=True)
    a, b = np.minimum(a[first], b[first]), np.maximum(a[first], b[first])
    if line_edges.shape[0] == 0 or a.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    typical = float(np.median(np.linalg.norm(points[a] - points[b], axis=1)))
    near = NEAR_LINE * typical
    # the feature lines, sampled at a spacing of a fifth of the distance allowed
    p, q = line_points[line_edges[:, 0]], line_points[line_edges[:, 1]]
    steps = np.maximum(1, np.ceil(np.linalg.norm(q - p, axis=1) / (0.2 * near)).astype(np.int64))
    segment = np.repeat(np.arange(p.shape[0]), steps + 1)
    t = (np.arange(segment.size) - np.repeat(np.cumsum(steps + 1) - (steps + 1), steps + 1)) / steps[segment]
    samples = p[segment] + t[:, None] * (q - p)[segment]
    direction = (q - p) / np.maximum(np.linalg.norm(q - p, axis=1, keepdims=True), 1e-300)
    tree = cKDTree(samples)
    ends = np.stack([points[a], points[b], 0.5 * (points[a] + points[b])])
    distance, nearest = tree.query(ends.reshape(-1, 3))
    distance, nearest = distance.reshape(3, -1), nearest.reshape(3, -1)
    edge_direction = points[b] - points[a]
    edge_direction /= np.maximum(np.linalg.norm(edge_direction, axis=1, keepdims=True), 1e-300)
    along = np.abs(np.einsum("ij,ij->i", edge_direction, direction[segment[nearest[2]]]))
    tagged = np.all(distance < near, axis=0) & (along > np.cos(np.radians(ALONG_DEGREES)))
    # close gaps: from a line's loose end (a vertex on one tagged edge) the untagged edge nearest the line
    # and along it, within twice the allowance, until the lines meet or stop
    loose_ok = np.all(distance < 2 * near, axis=0) & (along > np.cos(np.radians(2 * ALONG_DEGREES)))
    for _ in range(EXTEND_ROUNDS):
        degree = np.bincount(np.r_[a[tagged], b[tagged]], minlength=points.shape[0])
        loose = degree == 1
        grow = ~tagged & loose_ok & (loose[a] | loose[b])
        if not grow.any():
            break
        # one edge per loose end: the one whose far end is nearest the line
        end = np.where(loose[a[grow]], a[grow], b[grow])
        edge = np.flatnonzero(grow)
        order = np.lexsort((distance[:, edge].max(axis=0), end))
        first = order[np.r_[True, end[order][1:] != end[order][:-1]]]
        tagged[edge[first]] = True
    return np.stack([a[tagged], b[tagged]], axis=1).astype(np.int64)


def _instant_layout(scan, faces: int, crease_angle, check_topology: bool = False):
    """Instant Meshes' remesh, cleaned, retried at ``RETRY_SCALES`` while a closed mesh needs two Doo-Sabin steps.

    Returns (steps, remeshed faces, sizes, vertices, points, cleanup report, info) of the mesh needing fewest steps;
    info: ``remesher``, ``target_vertices``, ``remeshes``, ``seconds`` (all tries) and, with ``check_topology``,
    ``topology_change`` (``_topology_change`` of the last try: the tries end at the first that changes it).
    """
    best, seconds, remeshes, change = None, 0.0, 0, ""
    for scale in RETRY_SCALES:
        quad_points, quads, info = quad_remesh(*scan, int(round(faces * scale)), crease_angle)
        seconds, remeshes = seconds + info["seconds"], remeshes + info["remeshes"]
        layout = _cleaned_quads(quads, quad_points, scan, info)
        steps = layout[0]
        change = _topology_change(layout, scan) if check_topology else ""
        if best is None or steps < best[0]:
            best = layout
        if steps <= 1 or change:
            break
    info = {"remesher": "instant", "target_vertices": best[-1]["target_vertices"], "remeshes": remeshes,
            "seconds": seconds, "topology_change": change}
    return best[:-1] + (info,)


def _quadriflow_layout(scan, faces: int, sharp: bool = False):
    """QuadriFlow's remesh at a quarter of ``faces`` (asked once more, scaled, when it lands further than
    ``FACE_SLACK`` off), every quad split in four at its centre and edge midpoints (``split_faces``; the new points
    on the scan where that is safe, ``projected_new_points``), cleaned: its few irregular vertices lie apart, so one
    Doo-Sabin step suffices on a closed mesh; the tuple of ``_instant_layout``."""
    from .quadriflow import quadriflow_remesh

    want = max(8, faces // 4)
    asked, seconds, remeshes = want, 0.0, 0
    for _ in range(2):
        coarse_points, coarse, took = quadriflow_remesh(*scan, asked, sharp)
        seconds, remeshes = seconds + took, remeshes + 1
        if coarse.shape[0] and abs(coarse.shape[0] - want) <= FACE_SLACK * want:
            break
        asked = max(8, int(round(asked * want / max(coarse.shape[0], 1))))
    quads, quad_points = split_faces(np.full(coarse.shape[0], 4), coarse.ravel(), coarse_points)
    n = coarse_points.shape[0]
    quad_points[n:] = projected_new_points(quad_points[n:], coarse_points, *scan)
    return _cleaned_quads(quads, quad_points, scan,
                          {"remesher": "quadriflow", "target_vertices": 0, "remeshes": remeshes, "seconds": seconds})


def _cleaned_quads(quads: np.ndarray, quad_points: np.ndarray, scan, info: dict):
    """A remesher's quads (F, 4) over ``quad_points`` cleaned against the scan (``clean_control_mesh``), with the
    Doo-Sabin steps they need: the tuple of ``_instant_layout`` (``info`` its last item)."""
    sizes, vertices, control_points, cleanup = clean_control_mesh(
        np.full(quads.shape[0], 4), quads.ravel(), quad_points, scan=scan)
    steps = _doo_sabin_steps(sizes, vertices, control_points.shape[0])
    return steps, quads.shape[0], sizes, vertices, control_points, cleanup, info


def _decimated_layout(scan, faces: int):
    """The scan decimated, paired and split (``decimated_quads``), cleaned; the tuple of ``_instant_layout``."""
    quad_points, quads, info = decimated_quad_mesh(*scan, faces)
    return _cleaned_quads(quads, quad_points, scan, {
        "remesher": "decimate", "target_vertices": 0, "remeshes": 1, "seconds": info["seconds"],
        "decimated_triangles": info["decimated_triangles"], "redone": info["redone"]})


def _simplified_layout(scan, faces: int):
    """The scan turned into quads and simplified to a quarter of ``faces`` (``quads.simplify``), every quad then
    split in four (its edge midpoints and centre put on the scan), so that its irregular vertices lie apart and one
    Doo-Sabin step suffices on a closed mesh, as ``decimated_quads`` does; cleaned; ``_instant_layout``'s tuple."""
    from ..deviation import closest_on_triangles
    from .quads.simplify import SimplifyOptions, simplify_scan

    quads, quad_points, info = simplify_scan(*scan, SimplifyOptions(faces=max(8, faces // 4)))
    quads, split_points = split_faces(np.full(quads.shape[0], 4), quads.ravel(), quad_points)
    new = np.arange(quad_points.shape[0], split_points.shape[0])
    split_points[new] = closest_on_triangles(split_points[new], *scan)[1]
    return _cleaned_quads(quads, split_points, scan,
                          {"remesher": "simplify", "target_vertices": 0, "remeshes": 1, "seconds": info["seconds"]})


def _topology_change(layout, scan) -> str:
    """What the cleaned remesh changed of the scan's topology (components, Euler characteristic, rims, or the
    cleanup's repairs of stray pieces, holes and pinches the remesher left at thin parts); "" when nothing."""
    _, _, sizes, vertices, control_points, cleanup, _ = layout
    scan_points, scan_triangles = scan
    want = mesh_topology(np.full(scan_triangles.shape[0], 3), scan_triangles.ravel(), scan_points.shape[0])
    got = mesh_topology(sizes, vertices, control_points.shape[0]) if sizes.size else dict.fromkeys(want, 0)
    changed = [f"{got[k]} {k} instead of {want[k]}" for k in want if got[k] != want[k]]
    changed += [f"{cleanup[k]} {words}" for k, words in TOPOLOGY_REPAIRS.items() if cleanup.get(k)]
    return ("changed the scan's topology (" + ", ".join(changed) + ")") if changed else ""


def _coverage(layout, scan):
    """``coverage.mesh_coverage`` of a layout's cleaned mesh over the scan."""
    from .coverage import mesh_coverage

    _, _, sizes, vertices, control_points, _, _ = layout
    return mesh_coverage(*scan, sizes, vertices, control_points)


def _faults(layout, scan):
    """(what the layout changed or lost, one phrase or "", its Coverage): the counts and repairs
    (``_topology_change``) and the geometry (nothing lost, every rim matched: ``coverage``)."""
    if layout[2].size == 0:
        return "made no faces", None
    change, coverage = _topology_change(layout, scan), _coverage(layout, scan)
    lost = coverage.phrases(scan[0])
    if lost:
        change = (change + "; " if change else "") + "left " + "; ".join(lost)
    return change, coverage


def _loss(coverage, change: str) -> tuple:
    """What a faulty candidate loses, to compare: whether its counts changed (a candidate that keeps them wins), then
    the scan's area it leaves uncovered."""
    return (1, np.inf) if coverage is None else (int("topology (" in change), coverage.uncovered_area)


def _chosen_layout(scan, faces: tuple, crease_angle, remesher: str, decimated_faces: int):
    """(layout, notes, coverage): the remesher's layout (``_instant_layout``'s tuple) and its ``Coverage``
    (``faces``: the faces wanted, and the most QuadriFlow is asked for or None); with ``auto`` (with ``crease_angle``,
    only where QuadriFlow's sharp flag sees every line: ``_flow_sees``), QuadriFlow's coarse layout split once
    (``_quadriflow_layout``: fewest irregular vertices, so fewest CAD faces) where it keeps the scan's counts and
    covers it (``_faults``); else Instant Meshes' remesh where it does; else the decimated scan where that keeps and
    covers everything; else the one of the last two that loses least (``_loss``), a note saying which, what differs
    and where (the issue's rule: when no candidate keeps the topology, the one that loses least). Why QuadriFlow's
    was not taken is the report's ``quadriflow_refused``.
    """
    faces, most = faces
    if remesher == "decimate":
        layout = _decimated_layout(scan, decimated_faces)
        change, coverage = _faults(layout, scan)
        return layout, [], coverage
    if remesher == "simplify":  # opt-in: the scan as quads, simplified (quads/, docs/layout.md)
        layout = _simplified_layout(scan, faces)
        change, coverage = _faults(layout, scan)
        return layout, [], coverage
    if remesher == "quadriflow" or remesher == "auto" and quadriflow_available() and _flow_sees(scan, crease_angle):
        took = 0.0
        # finer while it changes the counts or leaves part of the scan (a horn, a handle), up to ``most``
        for scale in [s for s in FLOW_SCALES if most is None or faces * s <= most] or FLOW_SCALES[:1]:
            flow = _quadriflow_layout(scan, int(round(faces * scale)), crease_angle is not None)
            why, coverage = _faults(flow, scan)
            took += flow[-1]["seconds"]
            if not why:
                flow[-1]["seconds"] = took
                return flow, [], coverage
        if remesher == "quadriflow":
            return flow, [], coverage
        refused = f"QuadriFlow's remesh {why}"  # in the report
    else:
        refused, took = "", 0.0
    layout, notes, coverage = _instant_or_decimated(scan, faces, crease_angle, remesher, decimated_faces)
    layout[-1]["quadriflow_refused"] = refused
    layout[-1]["seconds"] += took
    return layout, notes, coverage


def _flow_sees(scan, crease_angle) -> bool:
    """Whether QuadriFlow's layout aligns to every feature line ``crease_angle`` asks for (always without one).

    QuadriFlow's sharp-feature flag aligns its quads to the edges whose faces' normals differ by more than a fixed
    ``QUADRIFLOW_SHARP`` degrees (its ``ComputeSharpEdges``), the measure ``scan_feature_edges`` takes. Below that
    angle, a line between the two would be crossed by its quads and lost as a crease, so Instant Meshes (which takes
    the angle) remeshes instead, unless the scan has no edge between the two angles.
    """
    if crease_angle is None or crease_angle >= QUADRIFLOW_SHARP:
        return True
    return scan_feature_edges(*scan, crease_angle).shape[0] == scan_feature_edges(*scan, QUADRIFLOW_SHARP).shape[0]


def _instant_or_decimated(scan, faces: int, crease_angle, remesher: str, decimated_faces: int):
    """``_chosen_layout`` for Instant Meshes' remesh and the decimated scan (its docstring)."""
    layout = _instant_layout(scan, faces, crease_angle, check_topology=remesher == "auto")
    why, coverage = _faults(layout, scan)
    if not why or remesher == "instant":  # a remesher asked for by name: its coverage is in the report
        return layout, [], coverage
    decimated = _decimated_layout(scan, decimated_faces)
    decimated[-1]["seconds"] += layout[-1]["seconds"]
    also, covered = _faults(decimated, scan)
    if not also:
        return decimated, [f"Instant Meshes' remesh {why}: the control mesh is the scan decimated instead "
                           "(topology kept, the scan covered; irregular, so more CAD faces)"], covered
    if _loss(covered, also) <= _loss(coverage, why):
        return decimated, [f"Instant Meshes' remesh {why}; the decimated scan {also}, and loses less: it is the "
                           "control mesh"], covered
    return layout, [f"Instant Meshes' remesh {why}; the decimated scan {also}, and loses more: Instant Meshes' "
                    "remesh is kept"], coverage


def _tagged_creases(scan, mesh: tuple, crease_angle, notes: list, report: dict):
    """(sizes, vertices, points, (c, 2) crease edges): the control edges along the scan's feature lines tagged,
    crease sectors of three or more faces merged (as ``convert`` merges them); ``notes`` and ``report`` told."""
    sizes, vertices, control_points = mesh
    if crease_angle is None:
        return sizes, vertices, control_points, np.zeros((0, 2), dtype=np.int64)
    lines = scan_feature_edges(*scan, crease_angle)
    creases = tag_feature_edges(sizes, vertices, control_points, scan[0], lines)
    report["feature_edges"] = int(lines.shape[0])
    notes.append(f"--crease-angle {crease_angle:g}: {lines.shape[0]} scan edges sharper than that; "
                 f"{creases.shape[0]} control edges follow them and are tagged infinitely sharp")
    sizes, vertices, control_points, creases, merged = _merged_sectors(sizes, vertices, control_points, creases)
    if merged:
        report["merged_sector_faces"] = merged
        notes.append(f"merged {merged} control faces in crease sectors of three or more faces, so that the "
                     "crease lines are C0 seams (docs/sharp-features.md, \"Sectors of many faces\")")
    return sizes, vertices, control_points, creases


def control_mesh_from_scan(points, triangles, faces: int, crease_angle: float | None = None,
                           remesher: str = "auto", decimated_share: float = 1.0,
                           most_faces: int | None = None) -> ControlMesh:
    """A quad control mesh of about ``faces`` faces for a dense triangle scan (module docstring).

    Parameters
    ----------
    points : (m, 3) float, the scan's vertices
    triangles : (t, 3) int
    faces : int > 0, the control faces wanted
    crease_angle : float degrees or None: tag the control edges along the scan's sharper edges
    remesher : "auto", "instant" or "decimate" (module docstring)
    decimated_share : float in (0, 1], a decimated control mesh gets this share of ``faces`` (its irregular layout
        costs more CAD faces a control face: ``scan_fit.DECIMATED_START``)
    most_faces : int or None, QuadriFlow is asked for no more (its larger scales, ``FLOW_SCALES``, stop there)

    Raises ValueError for a scan without area and when the remesher makes no face.

    Returns
    -------
    ControlMesh, cleaned so that ``Surface`` builds it without repairs; its ``report`` holds
    ``requested_faces``, ``remeshed_faces``, ``faces``, ``remesh_seconds``, ``remeshes``,
    ``target_vertices``, ``doo_sabin_steps`` (what ``refinements="auto"`` takes), ``feature_edges`` (on the scan), ``crease_edges`` and the cleanup's counts
    """
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if remesher not in REMESHERS:
        raise ValueError(f"the remesher must be one of {', '.join(REMESHERS)}, got {remesher!r}")
    scan_points, scan_triangles = _welded_scan(points, triangles)
    _check_area(scan_points, scan_triangles)
    scan_points, scan_triangles, faults = manifold_scan(scan_points, scan_triangles)
    scan = (scan_points, scan_triangles)
    layout, notes, coverage = _chosen_layout(scan, (faces, most_faces), crease_angle, remesher,
                                             max(8, int(round(faces * decimated_share))))
    steps, remeshed, sizes, vertices, control_points, cleanup, info = layout
    seconds, remeshes = info["seconds"], info["remeshes"]
    if sizes.size == 0:
        raise ValueError(f"the quad remesher made no faces of this scan ({len(triangles)} triangles, {faces} faces "
                         "asked): it needs a surface, not points on a line or in one point")
    notes = cleanup_notes(cleanup) + notes
    report = {"requested_faces": int(faces), "remeshed_faces": int(remeshed), "faces": int(sizes.size),
              "remesher": info["remesher"], "remesh_seconds": seconds, "remeshes": remeshes,
              "target_vertices": info["target_vertices"],
              "doo_sabin_steps": int(steps), **cleanup}
    if info.get("quadriflow_refused"):
        report["quadriflow_refused"] = info["quadriflow_refused"]
    sizes, vertices, control_points, creases = _tagged_creases(scan, (sizes, vertices, control_points), crease_angle,
                                                                notes, report)
    report["crease_edges"] = int(creases.shape[0])
    report["scan_topology"] = mesh_topology(np.full(scan_triangles.shape[0], 3), scan_triangles.ravel(),
                                            scan_points.shape[0])
    report["topology"] = mesh_topology(sizes, vertices, control_points.shape[0])
    report["coverage"] = coverage.as_dict() if coverage is not None else {}
    report["scan_faults"] = faults
    return ControlMesh(sizes, vertices, control_points, creases, notes, report)
