"""Python API: the one road from a file to a Surface, and tessellating and checking it.

    >>> from c1surf.api import load_surface, InputOptions, SurfaceOptions
    >>> surface, report = load_surface("sample_meshes/cube.obj", SurfaceOptions(blend=0.5), InputOptions(weld=0.0))
    >>> surface.bicubic.shape            # (Nc, 4, 4, 3) Bezier coefficients
    >>> report.notes                     # what was repaired or ignored, one line each
    >>> surface.update_points(report.mesh.points * 2)   # same connectivity, new geometry
    >>> S = surface.stencil()            # the whole construction as one sparse matrix: S @ points

``load_surface`` reads the mesh (``io``), reads its sidecar files, prepares it (``prepare``: welding, repeated faces,
valence-2 vertices, sheets, crease sectors, sharp features) and builds the ``Surface`` (``construction``); every
command that builds a surface from a mesh file goes through it. ``load_patches`` gives the patches of either a patch
file or a mesh file (``check``, ``measure``, ``render``).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from .construction.features import INFINITELY_SHARP
from .construction.surface import Surface, SurfaceOptions, build_surface
from .errors import MeshInputError
from .evaluation.adjacency import patch_adjacency
from .evaluation.patch_set import PatchSet, surface_patch_set
from .evaluation.smoothness import measure_smoothness
from .evaluation.stream import StreamedSurface
from .evaluation.stream.patches import StreamedPatchSet
from .evaluation.tessellate import tessellate
from .evaluation.tolerance import tessellate_to_tolerance
from .io.meshes.read import read_mesh
from .io.meshes.sidecars import read_blend_file, read_creases_file
from .io.patches.formats import load_patch_set
from .io.registry import PATCH_READERS
from .mesh.errors import TopologyError
from .mesh.points.geometry_checks import GeometryError, check_geometry
from .prepare.extension_data import Sidecars, SurfaceData
from .prepare.mesh_edits import weld_mesh_file
from .prepare.notes import repair_notes, seam_notes
from .prepare.options import NON_MANIFOLD_RULES, InputOptions
from .prepare.pipeline import prepare_mesh

__all__ = ["load_surface", "load_patches", "prepared_input", "surface_from_file", "fit_surface", "read_scan",
           "FitReport", "cage_options", "write_fit_cage", "tessellate_surface", "check_surface",
           "build_surface", "Surface", "SurfaceOptions", "InputOptions", "LoadReport", "PreparedInput",
           "NON_MANIFOLD_RULES", "repair_notes", "seam_notes", "topology_error"]

@dataclass
class PreparedInput:
    """A mesh file read and prepared for the construction (``prepared_input``).

    path : str, the file
    mesh : io.meshes.mesh_file.MeshFile, as prepared (its report fields say what the preparation changed)
    data : prepare.extension_data.SurfaceData, the construction's points and extension data
    options : SurfaceOptions as the input options resolve them (``InputOptions.surface_options``)
    """

    path: str
    mesh: object
    data: SurfaceData
    options: SurfaceOptions

@dataclass
class LoadReport:
    """What ``load_surface`` did besides building the surface.

    path : str; mesh : the prepared MeshFile; data : its SurfaceData (attribute names, colour scale, ...)
    notes : list of str, one line each on what was repaired or ignored (``c1surf: note:`` on the command line)
    """

    path: str
    mesh: object
    data: SurfaceData
    notes: list = field(default_factory=list)

def prepared_input(path, surface_options: SurfaceOptions | None = None, input_options: InputOptions | None = None,
                   keep_degenerate: bool = False) -> PreparedInput:
    """Read the mesh file ``path`` and its sidecar files and prepare it (``prepare.pipeline.prepare_mesh``).

    ``keep_degenerate``: the reader's (faces that repeat a vertex kept as written, for ``inspect``).
    Raises MeshInputError (one line: FILE[:LINE]: what and why) for a file that cannot be used, OptionError (a
    ValueError) for options that contradict each other.
    """
    input_options = (input_options or InputOptions()).check()
    options = input_options.surface_options(surface_options or SurfaceOptions())
    options.check(vertex_normals=True if input_options.normals else None)  # before reading: OptionError
    mesh = read_mesh(path, keep_degenerate=keep_degenerate, usd=input_options.usd)
    sidecars = Sidecars()
    if input_options.creases_file is not None:
        sidecars = Sidecars(creases=read_creases_file(input_options.creases_file, mesh))
    if input_options.blend_file is not None:
        face_blend, vertex_blend = read_blend_file(input_options.blend_file, mesh)
        sidecars = Sidecars(sidecars.creases, face_blend, vertex_blend)
    mesh, data = prepare_mesh(mesh, input_options, options.exact_creases, sidecars)
    return PreparedInput(str(path), mesh, data, options)

def load_surface(path, surface_options: SurfaceOptions | None = None, input_options: InputOptions | None = None, *,
                 lazy_patches: bool = False, progress=None):
    """Read, prepare and build the surface of the mesh file ``path`` (OBJ, PLY, OFF, STL).

    Parameters
    ----------
    path : str or os.PathLike
    surface_options : SurfaceOptions (default: the paper's), shape of the construction
    input_options : InputOptions (default: weld equal positions, the file's tags, C0 creases), what to read and repair
    lazy_patches : the patch arrays are made on first use (``Surface``; a polynomial surface only)
    progress : callable(str) or None, told the name of each phase ("reading cube.obj", ...)

    Returns
    -------
    (Surface, LoadReport)

    Raises
    ------
    MeshInputError, one line, for a file or mesh the construction cannot use (topology problems name the file's line)
    """
    tell = progress or (lambda phase: None)
    tell(f"reading {path}")
    prepared = prepared_input(path, surface_options, input_options)
    mesh, data = prepared.mesh, prepared.data
    tell(f"building the surface of {mesh.n_faces} faces")
    kwargs = data.surface_kwargs()
    lazy = lazy_patches and kwargs["weights"] is None  # a rational surface checks its patch weights when built
    try:
        surface = Surface(mesh.face_sizes, mesh.face_vertices, data.points, prepared.options, lazy_patches=lazy, **kwargs)
    except TopologyError as e:
        raise topology_error(e, mesh) from None
    except ValueError as e:  # extension data the construction cannot use (e.g. weights making a patch weight <= 0)
        raise MeshInputError(mesh.path, str(e)) from None
    return surface, LoadReport(prepared.path, mesh, data, repair_notes(surface, mesh, data))

def load_patches(path, surface_options: SurfaceOptions | None = None, input_options: InputOptions | None = None,
                 progress=None, streamed: bool = False):
    """The patches of a patch file (JSON, NPZ, IGES, STEP: read as they are) or of the surface of a mesh file.

    ``streamed``: a polynomial surface of a mesh file is kept as an ``evaluation.stream.patches.StreamedPatchSet``
    (its patches computed by blocks when read, never all held: ``check`` and ``measure``).

    Returns
    -------
    (PatchSet, notes): the notes of ``load_surface`` for a mesh file, [] for a patch file
    """
    if Path(path).suffix.lower() in PATCH_READERS:
        if progress is not None:
            progress(f"reading {path}")
        return load_patch_set(path), []
    surface, report = load_surface(path, surface_options, input_options, lazy_patches=streamed, progress=progress)
    if surface.lazy_patches:  # polynomial: by blocks
        return StreamedPatchSet(StreamedSurface(surface)), report.notes
    return surface_patch_set(surface, str(path)), report.notes

def topology_error(error: TopologyError, mesh_file) -> MeshInputError:
    """A construction TopologyError as ``FILE:LINE: message``, with the file's face lines and vertex numbers."""
    obj = str(mesh_file.path).lower().endswith(".obj")
    message = error.describe(vertex_base=1 if obj else 0)
    if obj and error.vertices:
        message += " (vertex numbers as in the OBJ file, from 1)"
    lines = []
    if mesh_file.face_lines is not None and error.faces.size:
        lines = sorted({int(mesh_file.face_lines[f]) for f in error.faces if 0 <= f < mesh_file.n_faces})
    if len(lines) > 1:
        shown = ", ".join(str(x) for x in lines[:8]) + (", ..." if len(lines) > 8 else "")
        message += f"; faces on lines {shown}"
    elif error.faces.size and not lines:
        message += f"; faces {', '.join(str(int(f)) for f in error.faces[:8])} (0-based)"
    return MeshInputError(mesh_file.path, message, lines[0] if lines else None)

_SURFACE_FIELDS = {f.name for f in fields(SurfaceOptions)}
_INPUT_FIELDS = {f.name for f in fields(InputOptions)}

def surface_from_file(path, **options):
    """``load_surface`` with the options as keywords, each a field of SurfaceOptions or InputOptions.

    ``surface_from_file("part.obj", blend=0.3, crease_angle=40, weld=None)``; returns (Surface, MeshFile as prepared).
    """
    unknown = set(options) - _SURFACE_FIELDS - _INPUT_FIELDS
    if unknown:
        raise TypeError(f"surface_from_file() got unknown options {sorted(unknown)}: fields of SurfaceOptions or "
                        "InputOptions")
    surface_options = SurfaceOptions(**{k: v for k, v in options.items() if k in _SURFACE_FIELDS and k != "exact_creases"})
    input_options = InputOptions(**{k: v for k, v in options.items() if k in _INPUT_FIELDS})
    surface, report = load_surface(os.fspath(path), surface_options, input_options)
    return surface, report.mesh

def read_scan(path):
    """The scan of ``c1surf fit``: (points (m, 3), triangles (t, 3), MeshFile as read), welded at equal positions
    (scans split at texture seams close up), polygons cut into triangle fans, unused vertices left out.

    Raises MeshInputError for a file without faces or spanning no surface.
    """
    from .fitting.scan_fit import check_scan  # the fitting (and scipy) only where a scan is fitted

    mesh, _ = weld_mesh_file(read_mesh(path), 0.0)
    sizes, corners = np.asarray(mesh.face_sizes, dtype=np.int64), np.asarray(mesh.face_vertices, dtype=np.int64)
    fans = np.maximum(sizes - 2, 0)  # triangles (v0, v_j, v_j+1) of each face, j = 1 .. k - 2
    first = np.repeat(np.cumsum(sizes) - sizes, fans)
    j = 1 + np.arange(first.size) - np.repeat(np.cumsum(fans) - fans, fans)
    triangles = corners[np.stack([first, first + j, first + j + 1], axis=1)].reshape(-1, 3)
    used, triangles = np.unique(triangles, return_inverse=True)
    points, triangles = np.asarray(mesh.points, dtype=np.float64)[used], triangles.reshape(-1, 3)
    try:
        check_geometry(points)
        check_scan(points, triangles, "the file")
    except GeometryError as e:
        raise MeshInputError(mesh.path, e.message) from None
    except ValueError as e:
        raise MeshInputError(mesh.path, str(e)) from None
    return points, triangles, mesh


def control_mesh_input(path, surface_options: SurfaceOptions, input_options: InputOptions | None = None):
    """A user's control mesh for ``fit_surface``: (ControlMesh, SharpFeatures or None, PreparedInput), read and
    prepared as every mesh file is (``prepared_input``: tags honoured), its unused vertices left out."""
    from .fitting.control.control_mesh import ControlMesh

    prepared = prepared_input(path, surface_options, input_options)
    mesh, data = prepared.mesh, prepared.data
    used = np.unique(mesh.face_vertices)
    number = np.full(mesh.n_vertices, -1, dtype=np.int64)
    number[used] = np.arange(used.size)
    features = data.features
    if features is not None:
        edges = number[features.crease_edges]
        keep_edges, keep_corners = (edges >= 0).all(axis=1), number[features.corner_vertices] >= 0
        features = replace(features, crease_edges=edges[keep_edges],
                           crease_sharpness=features.crease_sharpness[keep_edges],
                           corner_vertices=number[features.corner_vertices[keep_corners]],
                           corner_sharpness=features.corner_sharpness[keep_corners],
                           vertex_identity=None if features.vertex_identity is None else features.vertex_identity[used])
    control = ControlMesh(np.asarray(mesh.face_sizes, dtype=np.int64), number[mesh.face_vertices],
                          np.asarray(data.points[used, :3], dtype=np.float64))
    return control, features, prepared


def fit_surface(scan_path, options=None, surface_options: SurfaceOptions | None = None, *,
                control_path=None, input_options: InputOptions | None = None, progress=None):
    """Fit a surface of the paper's construction to the dense mesh ``scan_path`` (``c1surf fit``).

    Parameters
    ----------
    scan_path : a mesh file (OBJ, PLY, STL, OFF), read by ``read_scan``
    options : fitting.scan_fit.ScanFitOptions or None (faces, tolerance, face cap, crease angle, the fit's weights)
    surface_options : SurfaceOptions (default: refinements "auto", the fewest Doo-Sabin steps the control mesh allows)
    control_path : the user's control mesh (any polygons, tags honoured, read with ``input_options``), or None:
        a quad remesh of the scan
    progress : callable(label, amount, total) or None

    Returns
    -------
    (Surface, FitReport): the fitted surface (G1 by construction) and what was done, measured and noted

    Raises MeshInputError (one line) for a scan or control mesh that cannot be fitted.
    """
    from .fitting.scan_fit import ScanFitOptions, fit_scan

    options = options or ScanFitOptions()
    surface_options = (input_options or InputOptions()).surface_options(surface_options or
                                                                         SurfaceOptions(refinements="auto"))
    scan_points, scan_triangles, scan_mesh = read_scan(scan_path)
    control = features = prepared = None
    if control_path is not None:
        control, features, prepared = control_mesh_input(control_path, surface_options, input_options)
    try:
        result = fit_scan(scan_points, scan_triangles, options, surface_options, control, features, progress)
    except TopologyError as e:
        raise MeshInputError(str(control_path or scan_path), f"the control mesh cannot be built: {e.describe()}") from None
    except ValueError as e:
        raise MeshInputError(str(control_path or scan_path), str(e)) from None
    notes = [] if prepared is None else repair_notes(result.surface, prepared.mesh, prepared.data)
    return result.surface, FitReport(str(scan_path), scan_points, scan_triangles, result, notes + result.notes)


@dataclass
class FitReport:
    """What ``fit_surface`` did: the scan as fitted (points, triangles), the ``fitting.scan_fit.ScanFit`` (control
    mesh, fit, deviation, rounds, timings) and the notes."""

    path: str
    scan_points: np.ndarray
    scan_triangles: np.ndarray
    fit: object
    notes: list = field(default_factory=list)


def cage_options(surface: Surface) -> tuple:
    """(SurfaceOptions, InputOptions) with which ``load_surface`` builds a fitted ``surface`` again from its cage
    (``write_fit_cage``): the Doo-Sabin steps it took (``refinements="auto"`` chooses them from the same mesh,
    the number says it without the choice), and ``exact_creases=False`` where its infinitely sharp creases
    made no C0 seam (no crease sheet: every one is the sharpest G1 crease), so that the preparation of a mesh
    file does not merge crease sectors the fit's mesh kept (``prepare.pipeline.prepare_surface_input``)."""
    options = replace(surface.options, refinements=int(surface.refinements))
    features = surface.features
    sharp = features is not None and bool(np.any(features.crease_sharpness >= INFINITELY_SHARP))
    exact = options.exact_creases and not (sharp and surface.topology.crease_sheets is None)
    return replace(options, exact_creases=exact), InputOptions(exact_creases=exact)


def write_fit_cage(path, surface: Surface, report: "FitReport", comments=(), name=None) -> list:
    """Write the fitted control mesh of ``report`` (``fit_surface``) as a cage with its crease, corner and hole
    tags (``io.registry.CAGE_WRITERS``: OBJ ``t`` lines, USD mesh attributes), read it back as ``convert`` does with ``cage_options`` and
    compare the patches with ``surface``'s, array by array. ``name``: the file the notes name (default ``path``).

    Returns a list of notes: empty when the cage gives the very same bits, else one line saying what differs (and
    the cage is written again with a first line that says so instead of ``comments``' first).
    """
    from .io.registry import CAGE_WRITERS, suffix_of

    write_cage = CAGE_WRITERS[suffix_of(path, CAGE_WRITERS)].function  # OBJ with `t` lines, or USD
    control = report.fit.control
    write_cage(path, control.points, control.face_sizes, control.face_vertices, surface.features, comments)
    again, _ = load_surface(path, *cage_options(surface))
    same = [a.shape == b.shape and np.array_equal(a, b) for a, b in
            ((surface.biquadratic, again.biquadratic), (surface.bicubic, again.bicubic))]
    if all(same):
        return []
    note = (f"--cage: {name or path} builds a different surface than the fit's ({again.n_patches} patches, "
            f"{again.refinements} Doo-Sabin steps against {surface.n_patches} and {surface.refinements}): the "
            "preparation of a mesh file changed the cage (creases merged, welded or dissolved vertices)")
    write_cage(path, control.points, control.face_sizes, control.face_vertices, surface.features,
               [f"c1surf fit cage: the fitted control mesh; convert does NOT rebuild the fitted surface from it bit "
                f"for bit ({note[8:]})", *list(comments)[1:]])
    return [note]


def tessellate_surface(surface: Surface, resolution: int = 8, tolerance: float | None = None):
    """Welded N x N sampling of every patch of ``surface`` (a ``Tessellation``); with ``tolerance``, a
    ``ToleranceTessellation`` whose chordal error is at most that fraction of the bounding-box diagonal."""
    groups = [surface.biquadratic, surface.bicubic]
    if tolerance is not None:
        return tessellate_to_tolerance(groups, patch_adjacency(surface.refined, surface.frames), tolerance,
                                       surface.patch_weights)
    return tessellate(groups, surface.refined, surface.frames, resolution, surface.patch_weights)

def check_surface(surface: Surface, samples: int = 11):
    """Independent G1 measurement of ``surface`` (a ``SmoothnessReport``); C0 crease pieces are measured for
    their gap, G1 everywhere else."""
    return measure_smoothness([surface.biquadratic, surface.bicubic], samples=samples, weights=surface.patch_weights,
                              crease_sides=surface.crease_sides)
