"""Read a USD stage as one polygon mesh: its ``UsdGeom.Mesh`` prims with their subdivision tags (issue 41).

Each mesh prim gives its points (float64 from c1surf's own ``primvars:c1surf:points`` wherever they round to the
file's float points, else the float points; through the prim's local-to-world transform unless
``UsdReadOptions.world`` is False), its faces (``faceVertexCounts``, ``faceVertexIndices``; a ``leftHanded`` mesh's
faces reversed so that every face turns counter-clockwise seen from outside, as OBJ faces do) and its subdivision
tags, mapped to ``SharpTags`` as OpenSubdiv's OBJ ``t`` lines are (``tags.obj_tags``): ``creaseIndices`` chains of
``creaseLengths`` vertices with one sharpness a crease or an edge, ``cornerIndices``/``cornerSharpnesses``,
``holeIndices``, ``interpolateBoundary`` when authored (0 none, 1 edgeAndCorner, 2 edgeOnly), and a
``triangleSubdivisionRule`` of ``smooth`` as OpenSubdiv's ``smoothtriangles``.

Several meshes become one surface (their faces grouped by prim path, as an OBJ file's ``o`` objects), each placed
by its transform; ``UsdReadOptions.prim`` takes the meshes at or below one prim path. Everything else of the stage
(materials, cameras, lights, curves, the meshes' other primvars, animation) is named in a note and not read.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ...errors import MeshInputError
from ..mesh_file import MeshFile, collapse_repeated_corners_or_refuse, refuse_repeated_vertex
from ..tags.record import SharpTags, check_tags
from ...contained import call_contained
from .transfer import mesh_arrays as _transferred, mesh_file
from .stage import (POINTS_PRIMVAR, SHARPNESS_ATTRIBUTES, UsdReadOptions, exact_where_rounded, open_stage,
                    pxr_modules, usd_message)

__all__ = ["read_usd", "read_here", "mesh_arrays", "UsdReadOptions"]

# usd-core parses the file in a child process (``io.contained``): a crash or hang in its C++ parser on a damaged file
# is one line. False: in this process (tests that look inside the reader).
CONTAINED = True
_CHILD = "c1surf.io.meshes.usd.read"  # its mesh_arrays, in the child
_LIMIT_SECONDS = (60.0, 20.0)  # a read's time limit: base and per MB of file, as the STEP reader's
BOUNDARY_MODES = {"none": 0, "edgeAndCorner": 1, "edgeOnly": 2}
# prim types that hold no geometry of their own: not named in the note on what was ignored
_CONTAINERS = {"", "Xform", "Scope", "Mesh", "GeomSubset"}
_SHOWN = 8  # mesh prims named in a message


@dataclass
class _Part:
    """One mesh prim as read: points (V, 3) float64, faces (sizes, vertices), tags, and notes."""

    name: str
    points: np.ndarray
    sizes: np.ndarray
    vertices: np.ndarray
    tags: SharpTags
    collapsed: int = 0
    notes: list = field(default_factory=list)


def read_usd(path, *, keep_degenerate: bool = False, usd: UsdReadOptions | None = None) -> MeshFile:
    """Read the ``UsdGeom.Mesh`` prims of a USD file (``.usd``, ``.usda``, ``.usdc``, ``.usdz``) as one MeshFile.

    Parameters
    ----------
    path : str or os.PathLike
    keep_degenerate : keep faces that repeat a vertex as written (``c1surf inspect``)
    usd : UsdReadOptions or None (every mesh, world transforms applied)

    Returns
    -------
    MeshFile, points (V, 3) float64 of every mesh in turn, faces likewise (vertex and face indices offset by the
    meshes before), ``face_groups``/``group_names`` the prim paths when there are several, ``tags`` as the prims
    author them, ``reader_notes`` on what was not read.

    Raises
    ------
    MeshInputError
        One line: a file usd-core cannot read, no mesh prim (or none at ``usd.prim``), a mesh without points or
        faces, NaN points, counts that do not sum, indices out of range, malformed or out-of-range tags.
    """
    path = os.fspath(path)
    options = usd or UsdReadOptions()
    if not CONTAINED:
        return read_here(path, keep_degenerate=keep_degenerate, usd=options)
    pxr_modules(path)  # usd-core missing: said here, in one line
    if not os.path.isfile(path):
        raise MeshInputError(path, "no such file")
    limit = _LIMIT_SECONDS[0] + _LIMIT_SECONDS[1] * os.path.getsize(path) / 1e6
    header, arrays = call_contained(_CHILD, "usd-core", "mesh_arrays", path, options.prim, options.world,
                                    keep_degenerate, limit=limit)
    return mesh_file(path, header, arrays)


def mesh_arrays(path: str, prim, world: bool, keep_degenerate: bool):
    """The child's side of ``read_usd``: (header, arrays) of ``read_here`` (``transfer.mesh_arrays``)."""
    return _transferred(read_here(path, keep_degenerate=keep_degenerate, usd=UsdReadOptions(prim, world)))


def read_here(path, *, keep_degenerate: bool = False, usd: UsdReadOptions | None = None) -> MeshFile:
    """``read_usd`` in this process (the child's side: ``usd_child.mesh_arrays``)."""
    path = os.fspath(path)
    options = usd or UsdReadOptions()
    Usd, UsdGeom, _, _, Tf = pxr_modules(path)
    stage, stage_notes = open_stage(path)
    try:
        prims = _mesh_prims(stage, options, path, Usd, UsdGeom)
        time = Usd.TimeCode.EarliestTime()
        xforms = UsdGeom.XformCache(time) if options.world else None
        parts = [_read_prim(UsdGeom.Mesh(prim), path, time, xforms, keep_degenerate) for prim in prims]
        ignored = _ignored_notes(stage, prims, path, Usd, UsdGeom)
    except Tf.ErrorException as error:  # a damaged value usd-core meets only when it is read
        raise MeshInputError(path, f"usd-core cannot read a value of the file ({usd_message(error)}): the file is "
                                   "damaged") from None
    notes = stage_notes + [note for part in parts for note in part.notes] + ignored
    return _combined(path, parts, notes)


def _mesh_prims(stage, options: UsdReadOptions, path: str, Usd, UsdGeom) -> list:
    """The mesh prims to read, in stage order (instance proxies included): all, or those at or below ``options.prim``."""
    everything = [p for p in stage.Traverse(Usd.TraverseInstanceProxies()) if p.IsA(UsdGeom.Mesh)]
    if options.prim is None:
        chosen = everything
    else:
        root = stage.GetPrimAtPath(options.prim) if _is_prim_path(options.prim) else None
        if not root:
            raise MeshInputError(path, f"no prim {options.prim!r} in the stage: {_listing(everything)}")
        chosen = [p for p in Usd.PrimRange(root, Usd.TraverseInstanceProxies()) if p.IsA(UsdGeom.Mesh)]
        if not chosen:
            raise MeshInputError(path, f"no UsdGeom.Mesh prim at or below {options.prim} "
                                       f"(a {root.GetTypeName() or 'typeless'} prim): {_listing(everything)}")
    if not chosen:
        kinds = sorted({p.GetTypeName() for p in stage.Traverse() if p.GetTypeName()})
        found = f" (its prims: {', '.join(kinds)})" if kinds else " (it has no typed prim)"
        raise MeshInputError(path, f"no UsdGeom.Mesh prim in the stage{found}: c1surf reads polygon meshes; export "
                                   "the geometry as a mesh")
    return chosen


def _is_prim_path(text: str) -> bool:
    from pxr import Sdf

    return Sdf.Path.IsValidPathString(text) and Sdf.Path(text).IsAbsoluteRootOrPrimPath()


def _listing(prims) -> str:
    """The mesh prims of a stage for a message: "its meshes: /a, /b" (at most ``_SHOWN``)."""
    if not prims:
        return "the stage has no UsdGeom.Mesh prim"
    names = [str(p.GetPath()) for p in prims[:_SHOWN]]
    more = f" and {len(prims) - _SHOWN} more" if len(prims) > _SHOWN else ""
    return f"its meshes: {', '.join(names)}{more} (give one of them, or an Xform above some)"


def _read_prim(mesh, path: str, time, xforms, keep_degenerate: bool) -> _Part:
    """One mesh prim: points, checked faces, checked tags."""
    where = f"mesh {mesh.GetPath()}"
    points, notes = _points(mesh, path, where, time, xforms)
    part = _Part(str(mesh.GetPath()), points, *_faces(mesh, path, where, time), SharpTags(), notes=notes)
    n_points = part.points.shape[0]
    bad = (part.vertices < 0) | (part.vertices >= n_points)
    if bad.any():
        corner = int(np.argmax(bad))
        face = int(np.searchsorted(np.cumsum(part.sizes), corner, side="right"))
        raise MeshInputError(path, f"{where}: face {face} refers to point {int(part.vertices[corner])} but the mesh "
                                   f"has {n_points} points (faceVertexIndices count from 0): fix the index")
    if not keep_degenerate:
        part.sizes, part.vertices, part.collapsed = _collapsed(part.sizes, part.vertices, path, where)
    part.tags = _tags(mesh, path, where, time)
    try:
        check_tags(part.tags, part.sizes, part.vertices, n_points, path)
    except MeshInputError as error:
        raise MeshInputError(path, f"{where}: {error.message.replace('the file has', 'the mesh has')}") from None
    if any(_animated(a) for a in (mesh.GetPointsAttr(), mesh.GetFaceVertexIndicesAttr())):
        part.notes.append(f"{path}: {where} is animated: read at its first time sample")
    scheme = mesh.GetSubdivisionSchemeAttr().Get()
    if scheme in ("loop", "bilinear"):
        part.notes.append(f"{path}: {where} has subdivisionScheme {scheme}: c1surf builds its own surface "
                          "(Doo-Sabin and Peters' patches) from the control mesh, as for every mesh file")
    return part


def _points(mesh, path: str, where: str, time, xforms):
    """((V, 3) float64 points, notes): c1surf's doubles where they round to the float points, then the transform."""
    value = mesh.GetPointsAttr().Get(time)
    if value is None or len(value) == 0:
        raise MeshInputError(path, f"{where} has no points: author its points attribute (point3f[])")
    primvar = mesh.GetPrim().GetAttribute("primvars:" + POINTS_PRIMVAR)
    doubles = primvar.Get(time) if primvar and primvar.HasAuthoredValue() else None
    points, same = exact_where_rounded(np.asarray(value).reshape(-1, 3), None if doubles is None else np.asarray(doubles))
    notes = []
    if doubles is not None and same is None:
        notes.append(f"{path}: {where}: primvars:{POINTS_PRIMVAR} holds {len(doubles)} points for {len(points)}: "
                     "ignored, the float32 points are read")
    elif same is not None and not same.all():
        notes.append(f"{path}: {where}: {int(np.count_nonzero(~same))} of {len(same)} points differ from c1surf's "
                     f"float64 copy (primvars:{POINTS_PRIMVAR}; moved in another tool): their float32 points are read")
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        raise MeshInputError(path, f"{where}: point {int(np.argmin(finite))} has a NaN or infinite coordinate: fix "
                                   "or remove it")
    if xforms is not None:
        matrix = np.array(xforms.GetLocalToWorldTransform(mesh.GetPrim()))
        if not np.array_equal(matrix, np.eye(4)):  # identity: the very bits (x * 1 + 0 turns -0.0 into 0.0)
            points = points @ matrix[:3, :3] + matrix[3, :3]
            if not np.isfinite(points).all():
                raise MeshInputError(path, f"{where}: its transform makes points NaN or infinite: fix the xformOps")
    return points, notes


def _faces(mesh, path: str, where: str, time):
    """(sizes (F,), vertices (sum(sizes),)) int64, a left-handed mesh's faces reversed; counts checked."""
    counts = _ints(mesh.GetFaceVertexCountsAttr(), time)
    indices = _ints(mesh.GetFaceVertexIndicesAttr(), time)
    if counts.size == 0:
        raise MeshInputError(path, f"{where} has no faces: author faceVertexCounts and faceVertexIndices (c1surf "
                                   "needs polygons, not a point cloud)")
    small = np.flatnonzero(counts < 3)
    if small.size:
        k = int(counts[small[0]])
        raise MeshInputError(path, f"{where}: face {int(small[0])} has {k} vertices in faceVertexCounts: a polygon "
                                   "needs at least 3")
    total = int(counts.sum())
    if total != indices.size:
        raise MeshInputError(path, f"{where}: faceVertexCounts sum to {total} but faceVertexIndices has "
                                   f"{indices.size} entries: the two must agree")
    if mesh.GetOrientationAttr().Get() == "leftHanded":
        offsets = np.concatenate(([0], np.cumsum(counts)))
        indices = indices[np.repeat(offsets[:-1] + offsets[1:] - 1, counts) - np.arange(total)]
    return counts, indices


def _ints(attr, time) -> np.ndarray:
    value = attr.Get(time) if attr else None
    return np.zeros(0, dtype=np.int64) if value is None else np.asarray(value, dtype=np.int64).ravel()


def _sharpness(mesh, attr, kind: str, time) -> np.ndarray:
    """(N,) float64 sharpness of ``attr``, c1surf's float64 copy (``SHARPNESS_ATTRIBUTES``) where it rounds to it."""
    value = attr.Get(time) if attr else None
    if value is None:
        return np.zeros(0)
    exact = mesh.GetPrim().GetAttribute(SHARPNESS_ATTRIBUTES[kind])
    doubles = exact.Get(time) if exact and exact.HasAuthoredValue() else None
    return exact_where_rounded(np.asarray(value).ravel(), None if doubles is None else np.asarray(doubles).ravel())[0]


def _animated(attr) -> bool:
    return bool(attr) and attr.GetNumTimeSamples() > 1


def _collapsed(sizes, vertices, path: str, where: str):
    """Repeated consecutive corners dropped (``f a b c c``), then a face visiting a vertex twice refused."""
    try:
        sizes, vertices, _, collapsed = collapse_repeated_corners_or_refuse(sizes, vertices, path, lambda f: None)
    except MeshInputError as error:
        raise MeshInputError(path, f"{where}: {error.message}") from None
    refuse_repeated_vertex(sizes, vertices, path, lambda f: None, lambda f: f"{where}: face {f}")
    return sizes, vertices, collapsed


def _tags(mesh, path: str, where: str, time) -> SharpTags:
    """The subdivision tags of one mesh prim as a SharpTags (not yet checked against the mesh)."""
    tags = SharpTags()
    tags.crease_edges, tags.crease_sharpness = _creases(mesh, path, where, time)
    corners = _ints(mesh.GetCornerIndicesAttr(), time)
    corner_sharpness = _sharpness(mesh, mesh.GetCornerSharpnessesAttr(), "corner", time)
    if corners.size != corner_sharpness.size:
        raise MeshInputError(path, f"{where}: {corners.size} cornerIndices but {corner_sharpness.size} "
                                   "cornerSharpnesses: give one sharpness a corner")
    tags.corner_vertices, tags.corner_sharpness = corners, corner_sharpness
    tags.hole_faces = _ints(mesh.GetHoleIndicesAttr(), time)
    boundary = mesh.GetInterpolateBoundaryAttr()
    if boundary.HasAuthoredValue():
        tags.interpolate_boundary = BOUNDARY_MODES.get(boundary.Get(time), 1)
    triangles = mesh.GetTriangleSubdivisionRuleAttr()
    if triangles.HasAuthoredValue() and triangles.Get(time) == "smooth":
        tags.other = [("smoothtriangles", None)]
    return tags


def _creases(mesh, path: str, where: str, time):
    """(edges (E, 2) int64, sharpness (E,)) of the crease chains: ``creaseLengths`` vertices each, one sharpness a
    crease (repeated along its edges) or one an edge."""
    indices, lengths = _ints(mesh.GetCreaseIndicesAttr(), time), _ints(mesh.GetCreaseLengthsAttr(), time)
    sharpness = _sharpness(mesh, mesh.GetCreaseSharpnessesAttr(), "crease", time)
    if (lengths < 2).any():
        raise MeshInputError(path, f"{where}: crease {int(np.argmax(lengths < 2))} has creaseLengths "
                                   f"{int(lengths[np.argmax(lengths < 2)])}: a crease chain needs 2 vertices or more")
    if int(lengths.sum()) != indices.size:
        raise MeshInputError(path, f"{where}: creaseLengths sum to {int(lengths.sum())} but creaseIndices has "
                                   f"{indices.size} entries: the two must agree")
    n_edges = int((lengths - 1).sum())
    if sharpness.size == lengths.size:
        sharpness = np.repeat(sharpness, lengths - 1)
    elif sharpness.size != n_edges:
        raise MeshInputError(path, f"{where}: {sharpness.size} creaseSharpnesses for {lengths.size} creases of "
                                   f"{n_edges} edges: give one sharpness a crease or one an edge")
    keep = np.ones(max(indices.size - 1, 0), dtype=bool)
    keep[np.cumsum(lengths)[:-1] - 1] = False  # the step from one crease's last vertex to the next one's first
    edges = np.stack([indices[:-1][keep], indices[1:][keep]], axis=1) if indices.size else np.zeros((0, 2), np.int64)
    return edges.astype(np.int64), sharpness


def _ignored_notes(stage, prims, path: str, Usd, UsdGeom) -> list[str]:
    """One note on the prims that are not meshes (by type) and one on the primvars of the meshes not read."""
    kinds: dict[str, int] = {}
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        name = prim.GetTypeName()
        if name not in _CONTAINERS:
            kinds[name] = kinds.get(name, 0) + 1
    notes = []
    if kinds:
        listed = ", ".join(f"{count} {name}" for name, count in sorted(kinds.items()))
        notes.append(f"{path}: ignored {listed} prim{'s' if sum(kinds.values()) != 1 else ''}: c1surf reads the "
                     "UsdGeom.Mesh prims only")
    primvars = sorted({pv.GetPrimvarName() for prim in prims for pv in UsdGeom.PrimvarsAPI(prim).GetAuthoredPrimvars()}
                      - {POINTS_PRIMVAR})
    if primvars:
        notes.append(f"{path}: ignored the meshes' primvars {', '.join(primvars)}: c1surf builds the surface from "
                     "the points, faces and subdivision tags")
    if stage.HasAuthoredTimeCodeRange() and not any(_animated(UsdGeom.Mesh(p).GetPointsAttr()) for p in prims):
        notes.append(f"{path}: the stage is animated (time codes {stage.GetStartTimeCode():g} to "
                     f"{stage.GetEndTimeCode():g}): read at the first time sample of each value")
    return notes


def _combined(path: str, parts: list, notes: list) -> MeshFile:
    """One MeshFile of the mesh parts: indices offset by the parts before, faces grouped by prim when several."""
    vertex_base = np.cumsum([0] + [p.points.shape[0] for p in parts])
    face_base = np.cumsum([0] + [p.sizes.size for p in parts])
    tags = SharpTags(
        crease_edges=np.concatenate([p.tags.crease_edges + b for p, b in zip(parts, vertex_base)]).reshape(-1, 2),
        crease_sharpness=np.concatenate([p.tags.crease_sharpness for p in parts]),
        corner_vertices=np.concatenate([p.tags.corner_vertices + b for p, b in zip(parts, vertex_base)]),
        corner_sharpness=np.concatenate([p.tags.corner_sharpness for p in parts]),
        hole_faces=np.concatenate([p.tags.hole_faces + b for p, b in zip(parts, face_base)]),
        interpolate_boundary=next((p.tags.interpolate_boundary for p in parts
                                   if p.tags.interpolate_boundary is not None), None),
        other=[tag for p in parts for tag in p.tags.other])
    groups, names = None, []
    if len(parts) > 1:
        groups = np.repeat(np.arange(len(parts), dtype=np.int64), [p.sizes.size for p in parts])
        names = [p.name for p in parts]
        shown = ", ".join(f"{p.name} ({p.sizes.size} faces)" for p in parts[:_SHOWN])
        more = f" and {len(parts) - _SHOWN} more" if len(parts) > _SHOWN else ""
        notes = [f"{path}: {len(parts)} meshes read as one surface: {shown}{more}; --usd-prim PATH reads one"] + notes
    return MeshFile(path=path, points=np.concatenate([p.points for p in parts]),
                    face_sizes=np.concatenate([p.sizes for p in parts]),
                    face_vertices=np.concatenate([p.vertices + b for p, b in zip(parts, vertex_base)]),
                    face_groups=groups, group_names=names, tags=tags, reader_notes=notes,
                    collapsed_corners=sum(p.collapsed for p in parts))
