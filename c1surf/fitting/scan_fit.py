"""From a dense scan to a fitted surface: control mesh, fit, deviation, and refinement to a tolerance.

``fit_scan`` is the whole workflow of ``c1surf fit`` on plain arrays (the files are ``api.fit_surface``'s):

1. a control mesh: the user's (``control``), or a quad remesh of the scan sized by ``ScanFitOptions.faces``
   (``control_mesh.control_mesh_from_scan``: cleaned, creases tagged with ``crease_angle``);
2. the paper's construction over it with the fewest Doo-Sabin steps it allows (``refinements="auto"``);
3. the fit (``iterate.fit_surface_points``): only the control points move, so the result is G1 (C0 on
   exact creases) by construction;
4. with ``tolerance``: while the largest scan-to-surface distance exceeds it, a larger remesh
   (``local_refine.next_face_count``: cheaper than splitting faces, which makes pentagons that need the
   second Doo-Sabin step everywhere), up to ``face_cap`` faces; a note says when the cap stops it;
5. the two-sided deviation of the final surface (``deviation.two_sided_deviation``);
6. the topology of the scan and of the surface side by side (``mesh.topology_counts``; the surface's is its
   control mesh's, less the faces tagged as holes: the construction covers every other face once), with a
   note on what differs. A component of the scan that no control point lies near (its nearest scan vertex on
   another component: the remesher made nothing there, or the cleanup dropped it) is remeshed on its own and
   added to the control mesh (``remesh_missing_parts``, a note says so); one too small for that is named in a
   note and left out of the fit, whose samples would otherwise pull the rest of the surface towards it; its
   distances stay in the deviation (``unfitted_components``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..construction.surface import Surface, SurfaceOptions
from ..mesh.halfedges import component_roots
from ..mesh.topology_counts import compare_topology, counts_as_read, topology_counts
from .control.control_mesh import FACE_SLACK, REMESHERS, ControlMesh, control_mesh_from_scan, manifold_scan
from .deviation import bounding_diagonal, distance_stats, two_sided_deviation
from .iterate import fit_surface_points, project_scan
from .control.local_refine import next_face_count
from .options import FitOptions
from .system import vertex_normals

__all__ = ["ScanFitOptions", "ScanFit", "fit_scan", "default_face_count", "check_scan", "fitting_samples",
           "curved_midpoints", "unfitted_components", "remesh_missing_parts", "fit_topology"]

# control faces when neither --faces nor a control mesh is given. Measured (bench/fit.py, docs/fit.md; RMS / max of
# the diagonal, scan to surface): 1,000 faces leave the small faceted scans short (goathead 6.4e-4 / 7.0e-3 with
# flat midpoint samples); 3,000 give 1,060-1,300 packed CAD faces (spot 1,063, within issue 29's 1,500) and
# koala 1.8e-4 / 1.8e-3, spot 5.8e-5 / 1.4e-3 (fit 11-15 s on the loaded 2-core machine)
DEFAULT_FACES = 3000
MIN_FACES, FACE_CAP = 8, 6000
# fit samples a control face at least (4 patches a face after one Doo-Sabin step). Measured at 2,500 faces (scan to
# surface RMS / max, surface to scan max): 4 (one subdivision of the small scans, none of spot): spot 5.8e-5 /
# 1.1e-3, 4.2e-3 (bulges between samples), wingnut 1.5e-4 / 1.8e-3, 3.6e-3; 8: spot 6.3e-5 / 1.3e-3, 2.4e-3,
# wingnut 1.8e-4 / 2.6e-3, 2.2e-3, goathead 2.1e-4 / 1.5e-3, 3.9e-3 (4: 1.8e-4 / 1.2e-3, 3.9e-3)
SAMPLES_PER_FACE = 8
# parts of the scan the remesh of the whole misses, remeshed on their own (``remesh_missing_parts``): at least this
# many triangles, this many control faces (a 320-triangle sphere of a twentieth of the diagonal: 28 quads, one
# Doo-Sabin step, scan to surface max 1e-3 of its own size), the largest this many
MIN_PART_TRIANGLES, MIN_PART_FACES, MAX_PARTS = 16, 24, 16
# what the defaults aim for (scan to surface, relative to the bounding-box diagonal; issue 34): a note says what was
# reached when a default fit misses it
DEFAULT_AIM = {"relative_rms": 3e-4, "relative_p99": 1e-3, "relative_max": 3e-3}
# at the defaults a decimated control mesh (``control_mesh``: where Instant Meshes breaks the scan's topology) starts at
# this share of the default faces, and grows once (at least 1.5 times, at most to the default) when the fit misses
# DEFAULT_AIM: its irregular layout costs about 1.3 CAD faces a control face against Instant Meshes' 0.4-0.9, and the
# fine-to-coarse mesh puts its faces where the scan bends and where it is thin. Measured (control faces, CAD faces,
# RMS / p99 / max scan to surface, surface to scan p99 / max): penguin 1,126, 1,473, 1.5e-4 / 5.8e-4 / 9.5e-4,
# 1.3e-3 / 2.0e-3 (3,060: 4,942, 5.9e-5 / 1.9e-4 / 6.4e-4, 1.2e-3 / 1.9e-3); human_man 1,866, 2,393, 2.4e-4 / 8.7e-4 /
# 2.8e-3, 9.1e-4 / 3.6e-3 (2,968: 3,914, 1.5e-4 / 5.7e-4 / 2.6e-3, 8.0e-4 / 1.7e-3)
DECIMATED_START = 0.4
DECIMATED_GROWTH = 1.5
# QuadriFlow's layout (about 0.2 CAD faces a control face on the shared scans) is remeshed once more when a default fit
# over it misses DEFAULT_AIM, at least 1.5 times and at most FLOW_MOST times the default faces: its uniform density
# spends fewer faces where the scan has detail (koala at 2,700 faces: max 6.3e-3) and more faces cost few CAD faces.
# No default layout of QuadriFlow's has more (its larger scales included: springer's second remesh, asked at 4,452
# faces, was taken at twice that, 10,124 faces, 86 s, shape ratio 1.60); a second remesh it refuses is not fitted
FLOW_MOST = 2.0


@dataclass(frozen=True)
class ScanFitOptions:
    """What ``fit_scan`` makes.

    faces : int or None, control faces of the remesh (None: ``default_face_count``)
    tolerance : float or None, the largest scan-to-surface distance wanted, relative to the scan's bounding-box
        diagonal: the control mesh grows until it holds or ``face_cap`` is reached
    face_cap : int, the most control faces a tolerance may ask for
    crease_angle : float degrees or None: scan edges sharper than this become C0 creases of the surface
    fit : FitOptions, the least-squares fit's weights and rounds
    remesher : "auto" (Instant Meshes' field-aligned remesh where it keeps the scan's topology, else the scan
        decimated), "instant" or "decimate" (``control_mesh.control_mesh_from_scan``)
    """

    faces: int | None = None
    tolerance: float | None = None
    face_cap: int = FACE_CAP
    crease_angle: float | None = None
    fit: FitOptions = field(default_factory=FitOptions)
    remesher: str = "auto"

    def check(self) -> "ScanFitOptions":
        """Raise ValueError for what ``fit_scan`` cannot take; else return self."""
        if self.faces is not None and not (MIN_FACES <= self.faces <= self.face_cap):
            raise ValueError(f"faces must be an integer in [{MIN_FACES}, {self.face_cap}], got {self.faces}")
        if self.tolerance is not None and not (np.isfinite(self.tolerance) and 0 < self.tolerance < 1):
            raise ValueError(f"the tolerance is a fraction of the bounding-box diagonal in (0, 1), got {self.tolerance}")
        if not (MIN_FACES <= self.face_cap <= 10 * FACE_CAP):
            raise ValueError(f"the face cap must be an integer in [{MIN_FACES}, {10 * FACE_CAP}], got {self.face_cap}")
        if self.crease_angle is not None and not (np.isfinite(self.crease_angle) and 0 < self.crease_angle < 180):
            raise ValueError(f"the crease angle must be in (0, 180) degrees, got {self.crease_angle}")
        if self.remesher not in REMESHERS:
            raise ValueError(f"the remesher must be one of {', '.join(REMESHERS)}, got {self.remesher!r}")
        self.fit.check()
        return self


@dataclass
class ScanFit:
    """What ``fit_scan`` returns.

    surface : Surface at the fitted control points (``update_points``, ``stencil()`` and every writer work)
    control : ControlMesh at the fitted points (the unfitted points are ``report["control"]``'s)
    fit : iterate.FitResult of the last fit; deviation : deviation.Deviation of the final surface
    rounds : list of dict, one per control mesh tried (faces, patches, scan-to-surface max, seconds)
    notes : list of str, ``c1surf: note:`` lines; timings : dict, seconds per stage
    topology : dict, ``fit_topology``: the scan's and the surface's counts and what differs
    """

    surface: Surface
    control: ControlMesh
    fit: object
    deviation: object
    rounds: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    topology: dict = field(default_factory=dict)


def default_face_count(n_triangles: int) -> int:
    """Control faces for a scan of ``n_triangles`` without --faces: ``DEFAULT_FACES``, fewer for a small scan
    (at least two scan triangles, about one scan vertex, per control face: ``fitting_samples`` adds samples on the
    scan's curved-up facets; goathead's 5,522 triangles take 2,761 faces, koala's 7,116 the default)."""
    return int(max(MIN_FACES, min(DEFAULT_FACES, n_triangles // 2)))


def check_scan(points: np.ndarray, triangles: np.ndarray, what: str = "the scan") -> float:
    """The scan's bounding-box diagonal; ValueError for a scan without triangles or spanning no surface."""
    if triangles.shape[0] == 0:
        raise ValueError(f"{what} has no faces: c1surf fit needs a surface mesh (a point cloud has no surface to fit)")
    used = points[np.unique(triangles)]
    centred = used - used.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False) if len(used) >= 3 else np.zeros(3)
    diagonal = bounding_diagonal(used)
    if not (np.isfinite(diagonal) and diagonal > 0) or singular.size < 2 or singular[1] <= 1e-9 * singular[0]:
        raise ValueError(f"{what} spans no surface: all its points lie on one line or in one point")
    return diagonal


def fitting_samples(points: np.ndarray, triangles: np.ndarray, faces: int):
    """(points, triangles) the fit samples: the scan, its triangles cut into four until there are
    ``SAMPLES_PER_FACE`` samples a control face (twice at most). A scan with fewer vertices than patches leaves
    the surface between samples to the fairness term alone: it bulges there.

    The new samples are the edge midpoints lifted off the scan's flat facets towards the smooth surface through
    its vertices (``curved_midpoints``): a midpoint on a facet lies a sagitta (edge^2 / 8R) inside a surface of
    radius R through the edge's ends, and those samples pull the fit off the scan's own vertices. Measured on
    goathead (2,763 vertices, 1,510 control faces, two subdivisions; RMS / p99 / max of the diagonal at the
    scan's vertices): flat midpoints 6.4e-4 / 1.9e-3 / 7.0e-3, lifted 3.6e-4 / 1.2e-3 / 2.3e-3 (fairness 1e-3,
    16 samples a face; docs/fit.md)."""
    for _ in range(2):
        if points.shape[0] >= SAMPLES_PER_FACE * faces:
            break
        edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middle = points.shape[0] + inverse.reshape(-1, 3)  # the midpoints of edges 01, 12, 20
        points = np.concatenate([points, curved_midpoints(points, vertex_normals(points, triangles), unique)])
        a, b, c = triangles.T
        ab, bc, ca = middle.T
        triangles = np.concatenate([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return points, triangles


def curved_midpoints(points: np.ndarray, normals: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(k, 3) float: the midpoints of ``edges`` (k, 2) moved off the chord onto the circle-like curve through
    the ends that is tangent there to the planes of the unit vertex ``normals`` (m, 3).

    With d_a = (m - a) . n_a the midpoint m's height over a's tangent plane, Phong tessellation (Boubekeur and
    Alexa 2008) moves m by -(d_a n_a + d_b n_b) / 2; on a circle of radius R through an edge of length c that
    is c^2 / 4R, twice the sagitta c^2 / 8R, so half of it is taken (Phong's shape factor 1/2): the midpoint
    lands on the circle to second order in c / R. Zero normals (undefined) leave the midpoint on the chord."""
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    na, nb = normals[edges[:, 0]], normals[edges[:, 1]]
    m = 0.5 * (a + b)
    da = np.einsum("ij,ij->i", m - a, na)
    db = np.einsum("ij,ij->i", m - b, nb)
    return m - 0.25 * (da[:, None] * na + db[:, None] * nb)


def _surface(control: ControlMesh, options: SurfaceOptions, features=None) -> Surface:
    return Surface(control.face_sizes, control.face_vertices, control.points, options,
                   features=control.features() if features is None else features)


def fit_scan(points, triangles, options: ScanFitOptions, surface_options: SurfaceOptions | None = None,
             control: ControlMesh | None = None, features=None, progress=None) -> ScanFit:
    """Fit a surface of the paper's construction to the scan (module docstring).

    Parameters
    ----------
    points : (m, 3) float, the scan's vertices (welded; every one on a triangle)
    triangles : (t, 3) int
    options : ScanFitOptions; surface_options : SurfaceOptions (default: refinements "auto")
    control : ControlMesh or None, the user's control mesh (then ``options.faces`` and the tolerance's
        remeshing do not apply); features : its SharpFeatures (tags), or None
    progress : callable(label, amount, total) or None, told each round of each fit and each stage

    Raises ValueError (one line) for a scan or control mesh that cannot be fitted.
    """
    options.check()
    points, triangles = np.asarray(points, dtype=np.float64), np.asarray(triangles, dtype=np.int64)
    diagonal = check_scan(points, triangles)
    surface_options = surface_options or SurfaceOptions(refinements="auto")
    tell = progress or (lambda label, amount, total: None)
    notes, rounds, timings = [], [], {}
    mesh, result, left_out = _fit_rounds(points, triangles, options, (surface_options, control, features), diagonal,
                                         (notes, rounds, timings, tell))
    notes += left_out  # the last control mesh's
    # a fresh construction at the fitted points: the bits ``convert`` makes of the cage (``update_points``'s
    # reused stages, the Doo-Sabin step's matrix form, round differently in the last bit: 4e-16 on a cylinder)
    start = time.perf_counter()
    surface = _surface(mesh.with_points(result.points), surface_options, features if mesh is control else None)
    _clock(timings, "construction", start)
    start = time.perf_counter()
    tell("measuring the deviation", 0, 1)
    deviation = two_sided_deviation(surface, points, triangles, result.footpoints)
    _clock(timings, "deviation", start)
    topology = fit_topology(triangles, points.shape[0], mesh, surface.features)
    notes += as_read_note(topology)
    if topology["differences"]:
        notes.append("the surface's topology differs from the scan's: " + "; ".join(topology["differences"]))
    return ScanFit(surface, mesh.with_points(result.points), result, deviation, rounds, notes, timings, topology)


def _best_round(best: tuple, notes: list):
    """(ControlMesh, FitResult, left out) of the default's better round (``best``: its miss first), its aim noted."""
    _, mesh, result, left_out = best
    notes += _aim_note(result.history[-1], mesh.n_faces)
    return mesh, result, left_out


def _default_again(mesh: ControlMesh, reached: dict, miss: float, state: tuple):
    """The default's one more round after a fit that missed ``DEFAULT_AIM`` (``miss`` > 1): (remesher, faces,
    share, regrown, note), or None when there is none. ``state``: this round's (remesher, faces, share, regrown).

    A decimated control mesh made at ``DECIMATED_START`` of the faces is decimated again, up to all of them; a
    QuadriFlow layout is remeshed once more at up to ``FLOW_MOST`` times the faces, unless it already had them (taken
    at a larger scale, ``FLOW_SCALES``: within the remesh's slack, a second remesh is the same size).
    """
    remesher, faces, share, regrown = state
    layout = mesh.report.get("remesher")
    if share < 1 and layout == "decimate":
        grown = min(faces, int(np.ceil(mesh.n_faces * max(DECIMATED_GROWTH, miss))))
        return "decimate", grown, 1.0, regrown, (f"the decimated control mesh of {mesh.n_faces} faces fits the scan "
                                                 f"to {_reached(reached)}: decimated again to about {grown} faces")
    grown = min(int(FLOW_MOST * faces), int(np.ceil(mesh.n_faces * max(DECIMATED_GROWTH, miss))))
    if not regrown and layout == "quadriflow" and grown > (1 + FACE_SLACK) * mesh.n_faces:
        return remesher, grown, share, True, (f"QuadriFlow's control mesh of {mesh.n_faces} faces fits the scan to "
                                              f"{_reached(reached)}: remeshed again at about {grown} faces")
    return None


def _fit_rounds(points, triangles, options: ScanFitOptions, plan: tuple, diagonal: float, record: tuple):
    """The rounds of ``fit_scan``: a control mesh, its components covered, a fit; again with more faces while a
    tolerance is missed, or once more (``_default_again``) when a default fit misses ``DEFAULT_AIM`` (the better round
    kept; a second QuadriFlow remesh that is refused is not fitted).

    plan : (SurfaceOptions, the user's ControlMesh or None, its SharpFeatures or None)
    record : (notes, rounds, timings, tell): the lists and dict the rounds append to, the progress callback
    Returns (ControlMesh, FitResult, notes of the components the last control mesh leaves out).
    """
    surface_options, control, features = plan
    notes, rounds, timings, tell = record
    faces = options.faces or default_face_count(triangles.shape[0])
    defaults = options.faces is None and options.tolerance is None and control is None
    remesher, share, best, regrown = options.remesher, DECIMATED_START if defaults else 1.0, None, False
    most = int(FLOW_MOST * faces) if defaults else None  # QuadriFlow's layout at most (its scales and second round)
    while True:
        start = time.perf_counter()
        if control is None or rounds:
            tell(f"remeshing the scan to about {int(faces * share) if remesher == 'decimate' else faces} quads", 0, 1)
            mesh = control_mesh_from_scan(points, triangles, faces, options.crease_angle, remesher, share, most)
            if regrown and mesh.report.get("remesher") != "quadriflow":  # its second remesh refused: no second fit
                notes.append(f"not taken: {mesh.report.get('quadriflow_refused', '')}; the first control mesh stays")
                return _best_round(best, notes)
            notes += [n for n in mesh.notes if n not in notes]
        else:
            mesh = control
            _check_encloses(mesh.points, points, diagonal)
        _clock(timings, "control mesh", start)
        mesh, keep, parts, left_out = _cover_components(points, triangles, mesh, mesh is not control,
                                                        (faces, options.crease_angle), diagonal)
        notes += [n for n in parts if n not in notes]  # left_out: noted after the last round
        fit_options = options.fit if options.tolerance is None else replace(options.fit, max_within=options.tolerance)
        surface, result = _fit_round(points, triangles, (mesh, features if mesh is control else None),
                                     (surface_options, fit_options), timings, tell, keep)
        worst = result.history[-1]["relative_max"]
        rounds.append({"faces": mesh.n_faces, "patches": surface.n_patches, "refinements": surface.refinements,
                       "relative_max": worst, "relative_rms": result.history[-1]["relative_rms"],
                       "iterations": result.iterations, "stopped": result.stopped})
        if defaults:
            miss = _aim_miss(result.history[-1])
            if best is None or miss < best[0]:
                best = (miss, mesh, result, left_out)
            again = miss > 1 and _default_again(mesh, result.history[-1], miss, (remesher, faces, share, regrown))
            if again:
                remesher, faces, share, regrown, note = again
                notes.append(note)
                continue
            return _best_round(best, notes)
        stop = _tolerance_stop(options, worst, faces, control is not None)
        if stop is not None:
            notes += [stop] if stop else []
            return mesh, result, left_out
        faces = next_face_count(faces, worst / options.tolerance, options.face_cap)


def _cover_components(points, triangles, mesh: ControlMesh, remesh: bool, plan: tuple, diagonal: float):
    """(ControlMesh, keep, notes of parts remeshed, notes of parts left out): the scan's components the control
    mesh misses remeshed on their own when ``remesh`` (``remesh_missing_parts``; ``plan``: faces, crease angle),
    and those still missed (``unfitted_components``: ``keep`` (t,) bool or None)."""
    keep, left_out = unfitted_components(points, triangles, mesh.points, diagonal, mesh.n_faces)
    parts = []
    if keep is not None and remesh:
        mesh, parts = remesh_missing_parts(points, triangles, mesh, keep, *plan, diagonal)
        keep, left_out = unfitted_components(points, triangles, mesh.points, diagonal, mesh.n_faces)
    return mesh, keep, parts, left_out


def fit_topology(triangles: np.ndarray, n_points: int, control: ControlMesh, features=None) -> dict:
    """The ``topology`` of the fit report: ``{"scan": counts, "surface": counts, "differences": [phrases],
    "scan_as_read": counts}`` (``mesh.topology_counts``): the scan's as a manifold (``control_mesh.manifold_scan``:
    edges in three or more triangles cut into sheets, pinched vertices split into fans, as ``convert`` prepares a
    mesh; the control mesh is made of that), its counts as read beside them (``counts_as_read``: vertex-connected
    components, V - E + F, rims, pinched vertices and non-manifold edges), and the surface's from its control mesh
    less the faces ``features`` tags as holes (the construction makes a surface homeomorphic to the mesh it covers).

    triangles : (t, 3) int, the scan's; n_points : its vertices; control : ControlMesh; features : SharpFeatures
    """
    as_read = counts_as_read(np.full(triangles.shape[0], 3), triangles.ravel(), n_points)
    _, manifold, _ = manifold_scan(np.zeros((n_points, 3)), triangles)
    scan = topology_counts(np.full(manifold.shape[0], 3), manifold.ravel(), int(manifold.max(initial=-1)) + 1)
    sizes, vertices = control.face_sizes, control.face_vertices
    if features is not None and features.hole_faces.size:
        kept = np.ones(sizes.size, dtype=bool)
        kept[features.hole_faces] = False
        sizes, vertices = sizes[kept], vertices[np.repeat(kept, sizes)]
    surface = topology_counts(sizes, vertices, control.points.shape[0])
    return {"scan": scan.as_dict(), "surface": surface.as_dict(), "differences": compare_topology(scan, surface),
            "scan_as_read": as_read}


def as_read_note(topology: dict) -> list:
    """A note when the scan's counts as read differ from its counts as a manifold (``fit_topology``), else []."""
    read, manifold = topology["scan_as_read"], topology["scan"]
    keys = ("components", "euler_characteristic", "rims")
    if all(read[k] == manifold[k] for k in keys) and not read["pinched_vertices"] and not read["non_manifold_edges"]:
        return []
    text = lambda c: f"{c['components']} components, Euler characteristic {c['euler_characteristic']}, {c['rims']} rims"
    return [f"the scan is not a manifold ({read['pinched_vertices']} pinched vertices, {read['non_manifold_edges']} "
            f"edges in three or more triangles): as read it has {text(read)}; as a manifold (pinched vertices split "
            f"into fans, those edges cut into sheets, as convert does) {text(manifold)}, the counts the control mesh "
            "and the surface keep"]


def unfitted_components(points: np.ndarray, triangles: np.ndarray, control_points: np.ndarray, diagonal: float,
                        faces: int, shown: int = 4):
    """The scan's components that no control point lies near, to leave out of the fit (module docstring, 6).

    A component (vertex-connected triangles) is near the control mesh when it holds the nearest scan vertex of
    some control point.

    Parameters
    ----------
    points : (m, 3) float; triangles : (t, 3) int, the scan
    control_points : (V, 3) float; diagonal : the scan's bounding-box diagonal; faces : the control faces (notes)
    shown : how many components a note names (the largest first)

    Returns
    -------
    keep : (t,) bool, the triangles to fit, or None when every component is near the control mesh
    notes : list of str, one line naming the components left out (vertices, triangles, bounding-box centre, size)
    """
    from scipy.spatial import cKDTree

    count, label = _scan_components(points, triangles)
    if count == 1 or control_points.shape[0] == 0:
        return None, []
    vertex_label = np.full(points.shape[0], -1, dtype=np.int64)
    vertex_label[triangles.ravel()] = np.repeat(label, 3)
    near = np.zeros(count, dtype=bool)
    near[vertex_label[cKDTree(points).query(control_points)[1]]] = True
    if near.all():
        return None, []
    missing = _largest_first(np.flatnonzero(~near), label)
    parts = _component_phrases(points, triangles, label, missing[:shown], diagonal)
    more = f" and {missing.size - shown} more" if missing.size > shown else ""
    note = (f"{missing.size} of the scan's {count} components got no control mesh at {faces} control faces and "
            f"are left out of the fit (their distances stay in the deviation): {'; '.join(parts)}{more}; fit such a "
            "part on its own, or ask for more --faces")
    return ~np.isin(label, missing), [note]


def remesh_missing_parts(points: np.ndarray, triangles: np.ndarray, mesh: ControlMesh, keep: np.ndarray,
                         faces: int, crease_angle: float | None, diagonal: float):
    """The control mesh with the scan's components that ``keep`` leaves out remeshed on their own and added.

    Instant Meshes resolves nothing below its scale (a sphere of a twentieth of the diagonal at 120 faces comes
    back as nothing, or as a piece the cleanup removes), but remeshes such a part well alone. Each missing
    component of at least ``MIN_PART_TRIANGLES`` triangles (the ``MAX_PARTS`` largest) gets its share of
    ``faces`` by area, at least ``MIN_PART_FACES``; the rest stay left out (``unfitted_components`` names them).

    Returns (ControlMesh, notes): the union (``report["parts"]``: the faces of each part added) and one line
    naming the parts remeshed on their own.
    """
    count, label = _scan_components(points, triangles)
    missing = _largest_first(np.unique(label[~keep]), label)
    missing = missing[np.bincount(label, minlength=count)[missing] >= MIN_PART_TRIANGLES][:MAX_PARTS]
    corners = points[triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    share = np.bincount(label, weights=area, minlength=count) / max(float(area.sum()), 1e-300)
    pieces, added = [mesh], []
    for k in missing:  # the few parts the remesh of the whole missed
        sub_points, sub_triangles = _compact_scan(points, triangles[label == k])
        try:
            part = control_mesh_from_scan(sub_points, sub_triangles, max(MIN_PART_FACES, int(round(faces * share[k]))),
                                          crease_angle)
        except ValueError:
            continue
        pieces.append(part)
        added.append(k)
    if not added:
        return mesh, []
    union = _union(pieces)
    phrases = _component_phrases(points, triangles, label, np.array(added), diagonal)
    note = (f"{len(added)} of the scan's {count} components got no control mesh in the remesh of the whole at "
            f"{mesh.n_faces} faces and were remeshed on their own: "
            + "; ".join(f"{p}, {piece.n_faces} control faces" for p, piece in zip(phrases, pieces[1:])))
    return union, [note]


def _union(meshes: list) -> ControlMesh:
    """The disjoint union of ControlMeshes (vertices and faces in order; the first one's notes and report, with
    ``faces`` the union's and ``parts`` the faces of the others)."""
    offsets = np.cumsum([0] + [m.points.shape[0] for m in meshes])
    first = meshes[0]
    notes = list(first.notes) + [n for m in meshes[1:] for n in m.notes if n not in first.notes]
    return ControlMesh(np.concatenate([m.face_sizes for m in meshes]),
                       np.concatenate([m.face_vertices + o for m, o in zip(meshes, offsets)]),
                       np.concatenate([m.points for m in meshes]),
                       np.concatenate([m.crease_edges + o for m, o in zip(meshes, offsets)]).reshape(-1, 2),
                       notes, {**first.report, "faces": int(sum(m.n_faces for m in meshes)),
                               "parts": [m.n_faces for m in meshes[1:]]})


def _scan_components(points: np.ndarray, triangles: np.ndarray):
    """(count, (t,) int label 0 .. count - 1 of each triangle): the scan's vertex-connected components."""
    root = component_roots(points.shape[0], triangles[:, [0, 1, 2]].ravel(), triangles[:, [1, 2, 0]].ravel())
    labels, label = np.unique(root[triangles[:, 0]], return_inverse=True)
    return int(labels.size), label.ravel()


def _largest_first(components: np.ndarray, label: np.ndarray) -> np.ndarray:
    """``components`` ordered by their triangles, the most first."""
    sizes = np.bincount(label)[components]
    return components[np.argsort(-sizes, kind="stable")]


def _component_phrases(points, triangles, label, components, diagonal: float) -> list:
    """One phrase per component of ``components`` (few): vertices, triangles, bounding-box centre and size."""
    phrases = []
    for k in components:
        part = triangles[label == k]
        box = points[np.unique(part)]
        low, high = box.min(axis=0), box.max(axis=0)
        phrases.append(f"{box.shape[0]} vertices and {part.shape[0]} triangles around "
                       f"({', '.join(f'{c:.4g}' for c in 0.5 * (low + high))}), "
                       f"{np.linalg.norm(high - low) / diagonal:.2g} of the diagonal across")
    return phrases


def _aim_miss(reached: dict) -> float:
    """The largest ratio of a distance the fit ``reached`` (relative RMS, p99, max) to ``DEFAULT_AIM``'s."""
    return max(reached[key] / aim for key, aim in DEFAULT_AIM.items())


def _reached(reached: dict) -> str:
    return (f"RMS {reached['relative_rms']:.2g}, 99th percentile {reached['relative_p99']:.2g} and max "
            f"{reached['relative_max']:.2g} of the diagonal")


def _aim_note(reached: dict, faces: int) -> list:
    """A note when the default fit misses ``DEFAULT_AIM`` (``reached``: the last round's relative distances)."""
    if _aim_miss(reached) <= 1:
        return []
    return [f"the defaults aim for a scan-to-surface RMS of {DEFAULT_AIM['relative_rms']:g}, 99th percentile "
            f"{DEFAULT_AIM['relative_p99']:g} and max {DEFAULT_AIM['relative_max']:g} of the diagonal; reached "
            f"{reached['relative_rms']:.2g}, {reached['relative_p99']:.2g} and {reached['relative_max']:.2g} with "
            f"{faces} control faces, the best of the default face budget (give --faces or --tolerance for more)"]


def _clock(timings: dict, name: str, start: float) -> None:
    timings[name] = timings.get(name, 0.0) + time.perf_counter() - start


def _fit_round(points, triangles, control: tuple, options: tuple, timings: dict, tell, keep=None):
    """(Surface, FitResult) of one control mesh: the construction over (ControlMesh, SharpFeatures or None) with
    (SurfaceOptions, FitOptions), fitted to samples of the scan (of its triangles ``keep`` ((t,) bool) when not
    None); the result's deviation is the scan vertices', all of them."""
    (mesh, features), (surface_options, fit_options) = control, options
    start = time.perf_counter()
    surface = _surface(mesh, surface_options, features)
    _clock(timings, "construction", start)
    start = time.perf_counter()
    part = (points, triangles) if keep is None else _compact_scan(points, triangles[keep])
    samples, sample_triangles = fitting_samples(*part, mesh.n_faces)
    result = fit_surface_points(surface, samples, sample_triangles, fit_options,
                                progress=lambda label, amount, total: tell(f"fitting {mesh.n_faces} faces", amount,
                                                                           total), measured=part[0].shape[0])
    if keep is not None or samples.shape[0] > points.shape[0]:  # the deviation is the scan's own vertices'
        result.footpoints = project_scan(surface, points, fit_options, None)
        diagonal = bounding_diagonal(points)
        result.history[-1] = {**result.history[-1], **distance_stats(result.footpoints.distance, diagonal)}
    _clock(timings, "fit", start)
    return surface, result


def _compact_scan(points: np.ndarray, triangles: np.ndarray):
    """(points, triangles) of the vertices ``triangles`` use, renumbered."""
    used, triangles = np.unique(triangles, return_inverse=True)
    return points[used], triangles.reshape(-1, 3)


def _tolerance_stop(options: ScanFitOptions, worst: float, faces: int, given_control: bool):
    """None: remesh finer and fit again; "" : done; a note: done, and why the tolerance is not met."""
    if options.tolerance is None or worst <= options.tolerance:
        return ""
    if given_control:
        return (f"--tolerance {options.tolerance:g}: the given control mesh is fitted as it is (its largest distance "
                f"{worst:.3g} of the diagonal): give a finer control mesh, or none to let c1surf remesh the scan")
    if faces >= options.face_cap:
        return (f"--tolerance {options.tolerance:g} not reached within the face cap of {options.face_cap} control "
                f"faces: the largest scan-to-surface distance is {worst:.3g} of the diagonal (raise --face-cap, or "
                "look for thin parts and holes where the scan has no surface)")
    return None


def _check_encloses(control_points: np.ndarray, scan_points: np.ndarray, diagonal: float) -> None:
    """ValueError when the control mesh's bounding box lies away from the scan's (more than half a diagonal apart
    at a corner): the fit would have to move every point across space, with footpoints that mean nothing."""
    gap = np.abs(np.r_[control_points.min(axis=0) - scan_points.min(axis=0),
                       control_points.max(axis=0) - scan_points.max(axis=0)])
    if gap.max() > 0.5 * diagonal:
        raise ValueError(f"the control mesh does not enclose the scan: their bounding boxes are {gap.max():.3g} apart "
                         f"at a side ({gap.max() / diagonal:.2f} of the scan's diagonal); give a control mesh around "
                         "the scan, in its units and position")
