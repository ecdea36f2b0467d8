"""What a mesh file says beyond its points: blend ratios, weights, normals, attributes.

``surface_data(mesh, ...)`` gathers the per-cell and per-vertex data the
extensions of the paper use (``core.surface.Surface`` arguments):

- blend ratios per cell and per vertex (A1, section 4): PLY face / vertex
  property ``blend``, or a sidecar JSON file (``--blend-file``)::

      {"default": 0.15,                      # cells without a ratio (else --blend)
       "faces": {"12": 0.3, "handle": 0.0},  # 0-based face index, or OBJ group (g/o) name
       "vertices": {"5": 0.0, "9": 0.5}}     # 0-based vertex index

  A vertex ratio is used for the corners at that vertex; negative or NaN
  PLY values mean "no ratio here".
- homogeneous weights (A2a): OBJ ``v x y z w``, PLY vertex property ``weight``;
- vertex normals (A1a): OBJ ``vn`` (through ``f v//vn``), PLY ``nx ny nz``;
- attributes carried through the construction as extra columns: texture
  coordinates (OBJ ``vt``, PLY ``u v`` / ``s t``) and colours (``red green
  blue`` [``alpha``]);
- sharp features: the file's crease, corner and hole tags, a ``--creases``
  sidecar and ``--crease-angle`` (``tags.features``).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import MeshInputError
from ..geometry import check_mesh_file_geometry
from ...construction.features import INFINITELY_SHARP, SharpFeatures
from ...mesh.creases.non_manifold import split_non_manifold_edges
from ...mesh.weld import coincident_representatives
from .mesh_file import MeshFile, dissolve_mesh_file, drop_repeated_faces, merge_sector_faces, weld_mesh_file
from .tags.features import read_sidecar_json, sharp_features
from .tags.record import mesh_edge_keys

COLOUR_NAMES = ("red", "green", "blue", "alpha")


@dataclass
class SurfaceData:
    """Inputs of ``Surface`` taken from a mesh file.

    points : (V, 3 + k) float, positions then the k attribute columns
    attribute_names : list of k str ("u", "v", "red", "green", "blue", "alpha")
    colour_scale : float, 255 when colours are 0..255, 1 when 0..1 (for writing them back)
    face_blend, vertex_blend : (F,) / (V,) float with NaN where unset, or None
    weights : (V,) float or None
    vertex_normals : (V, 3) float (NaN rows where unset) or None
    features : construction.features.SharpFeatures or None
    feature_notes : list of str, what was honoured or ignored of the sharp features (``tags.features``)
    non_manifold : "sheets" (edges in more than two faces cut into sheets, with exact creases) or "refuse"
    """

    points: np.ndarray
    attribute_names: list = field(default_factory=list)
    colour_scale: float = 1.0
    face_blend: np.ndarray | None = None
    vertex_blend: np.ndarray | None = None
    weights: np.ndarray | None = None
    vertex_normals: np.ndarray | None = None
    features: object = None
    feature_notes: list = field(default_factory=list)
    non_manifold: str = "sheets"

    def surface_kwargs(self) -> dict:
        """Keyword arguments of ``Surface`` (besides points and options)."""
        return {"face_blend": self.face_blend, "vertex_blend": self.vertex_blend, "weights": self.weights,
                "vertex_normals": self.vertex_normals, "features": self.features}

    def vertex_keys(self) -> np.ndarray:
        """(V, k) per-vertex inputs of the construction besides the position (attribute columns,
        weights, normals, blend ratios): vertices whose keys differ are not welded."""
        columns = [self.points[:, 3:]]
        columns += [np.reshape(c, (len(self.points), -1)) for c in (self.weights, self.vertex_normals, self.vertex_blend)
                    if c is not None]
        return np.concatenate(columns, axis=1)


def _ratio(path, where: str, value) -> float:
    try:
        r = float(value)
    except (TypeError, ValueError):
        raise MeshInputError(path, f"{where}: blend ratio {value!r} is not a number") from None
    if not (0.0 <= r <= 1.0):
        raise MeshInputError(path, f"{where}: blend ratio {r!r} is not in [0, 1]")
    return r


def read_blend_file(path, mesh: MeshFile):
    """Read a sidecar JSON of blend ratios for ``mesh``.

    Returns
    -------
    face_blend : (F,) float, NaN where unset (the "default" fills them when given)
    vertex_blend : (V,) float, NaN where unset, or None when the file names no vertices
    """
    path = str(path)
    doc = read_sidecar_json(path, "--blend-file", "a blend-ratio file")
    if not isinstance(doc, dict):
        raise MeshInputError(path, 'expected a JSON object like {"faces": {...}, "vertices": {...}}')
    unknown = set(doc) - {"default", "faces", "vertices"}
    if unknown:
        raise MeshInputError(path, f'unknown key {sorted(unknown)[0]!r}: use "default", "faces" and "vertices"')
    face_blend = np.full(mesh.n_faces, np.nan)
    if "default" in doc:
        face_blend[:] = _ratio(path, '"default"', doc["default"])
    groups = {name: k for k, name in enumerate(mesh.group_names)}
    faces = doc.get("faces", {})
    if not isinstance(faces, dict):
        raise MeshInputError(path, '"faces" must be an object {face index or group name: ratio}')
    for key, value in faces.items():
        r = _ratio(path, f'"faces" {key!r}', value)
        if key in groups and mesh.face_groups is not None:
            face_blend[mesh.face_groups == groups[key]] = r
            continue
        try:
            index = int(key)
        except ValueError:
            names = ", ".join(repr(n) for n in mesh.group_names[:8]) or "none"
            raise MeshInputError(path, f'"faces": {key!r} is neither a face index nor a group of {mesh.path} (groups: {names})') from None
        if not 0 <= index < mesh.n_faces:
            raise MeshInputError(path, f'"faces": face {index} does not exist ({mesh.path} has {mesh.n_faces} faces, numbered from 0)')
        face_blend[index] = r
    vertices = doc.get("vertices")
    if vertices is None:
        return face_blend, None
    if not isinstance(vertices, dict):
        raise MeshInputError(path, '"vertices" must be an object {vertex index: ratio}')
    vertex_blend = np.full(mesh.n_vertices, np.nan)
    for key, value in vertices.items():
        try:
            index = int(key)
        except ValueError:
            raise MeshInputError(path, f'"vertices": {key!r} is not a vertex index') from None
        if not 0 <= index < mesh.n_vertices:
            raise MeshInputError(path, f'"vertices": vertex {index} does not exist ({mesh.path} has {mesh.n_vertices} vertices, numbered from 0)')
        vertex_blend[index] = _ratio(path, f'"vertices" {key!r}', value)
    return face_blend, vertex_blend


def _property_ratios(mesh: MeshFile, values, what: str) -> np.ndarray:
    r = np.asarray(values, dtype=np.float64)
    r = np.where(r < 0, np.nan, r)
    bad = np.flatnonzero(r > 1)
    if bad.size:
        raise MeshInputError(mesh.path, f"{what} property 'blend' is {r[bad[0]]!r} at {what} {bad[0]}: blend ratios lie in [0, 1]")
    return r


def _used_vertices(mesh: MeshFile) -> np.ndarray:
    used = np.zeros(mesh.n_vertices, dtype=bool)
    used[mesh.face_vertices] = True
    return used


def surface_data(mesh: MeshFile, blend_file=None, use_weights: bool | None = None, normals: bool = False,
                 attributes: bool = False, creases_file=None, crease_angle: float | None = None,
                 ignore_tags: bool = False, exact_creases: bool = False, non_manifold: str = "sheets") -> SurfaceData:
    """Collect the extension data of ``mesh`` (see the module docstring).

    Parameters
    ----------
    blend_file : path of a sidecar JSON of blend ratios, or None
    use_weights : True / False, or None: use the file's weights when some differ from 1
    normals : use the file's vertex normals (every used vertex needs one)
    attributes : carry texture coordinates and colours as extra columns
    creases_file, crease_angle, ignore_tags : sharp features besides (or instead of) the
        file's tags (``tags.features.sharp_features``)
    non_manifold : "sheets" or "refuse" (``SurfaceData.non_manifold``)

    Raises
    ------
    MeshInputError when requested data is missing or malformed.
    """
    data = SurfaceData(points=np.asarray(mesh.points, dtype=np.float64), non_manifold=non_manifold)
    data.face_blend, data.vertex_blend = _blend_ratios(mesh, blend_file)
    data.weights = _weights(mesh, use_weights)
    data.features, data.feature_notes = sharp_features(mesh, creases_file, crease_angle, ignore_tags, exact_creases)
    if normals:
        data.vertex_normals = _vertex_normals(mesh)
    if attributes:
        extra, data.attribute_names, data.colour_scale = _attribute_columns(mesh)
        data.points = np.concatenate([data.points, extra], axis=1)
    return data


def weld_surface_input(mesh: MeshFile, data: SurfaceData | None, tolerance: float | None):
    """Weld ``mesh`` (``mesh_file.weld_mesh_file``) without merging vertices whose construction data differ.

    Parameters
    ----------
    mesh : MeshFile
    data : SurfaceData of ``mesh`` or None; its vertex keys keep apart vertices with different
        texture coordinates or colours (``--attributes``), weights, normals or blend ratios
    tolerance : float, relative to the bounding-box diagonal (0: equal positions), or None: no welding

    Returns
    -------
    (MeshFile, SurfaceData or None): per-face data follows the faces welding keeps
    """
    if tolerance is None:
        return mesh, data
    keys = None if data is None else data.vertex_keys()
    welded, kept = weld_mesh_file(mesh, tolerance, keys)
    if data is not None and data.face_blend is not None:
        data = replace(data, face_blend=data.face_blend[kept])
    if data is not None and data.features is not None and (welded.weld.welded_vertices or welded.weld.dropped_faces):
        data = _welded_features(data, mesh, welded, kept, coincident_representatives(mesh.points, mesh.face_vertices,
                                                                                     tolerance, keys))
    return welded, data


def prepare_surface_input(mesh: MeshFile, data: SurfaceData | None, weld: float | None, exact_creases: bool = False):
    """``mesh`` and ``data`` as the construction takes them: welded (``weld_surface_input``), without
    repeated faces (``drop_repeated_surface_faces``), with its interior valence-2 vertices dissolved
    (``dissolve_surface_input``) and, with ``exact_creases``, its non-manifold edges cut into sheets
    (``split_surface_sheets``, unless ``data.non_manifold`` is "refuse") and the faces of crease sectors
    too large for an exact C0 crease merged (``merge_surface_sectors``), then dissolved again where that
    left an interior vertex in two faces."""
    check_mesh_file_geometry(mesh)  # coordinates the construction can take, spanning a surface
    prepared = dissolve_surface_input(*drop_repeated_surface_faces(*weld_surface_input(mesh, data, weld)))
    if not exact_creases:
        return prepared
    sheets = data is None or data.non_manifold == "sheets"
    merged = merge_surface_sectors(*(split_surface_sheets(*prepared) if sheets else prepared))
    if merged[0].sector_merge is None:
        return merged
    # merging may leave an interior vertex next to a corner in two faces: dissolved too (not the seams')
    f = merged[1].features
    seam = np.zeros(merged[0].n_vertices, dtype=bool)
    seam[f.crease_edges[f.crease_sharpness >= INFINITELY_SHARP].ravel()] = True
    seam[f.corner_vertices] = True
    return dissolve_surface_input(*merged, keep=seam)


def split_surface_sheets(mesh: MeshFile, data: SurfaceData | None):
    """Cut the non-manifold edges of ``mesh`` into manifold sheets (``mesh.creases.non_manifold``) that
    meet along one C0 crease each: the edges become infinitely sharp creases of every sheet, the ends and
    branch points of their polylines corners, and every per-vertex value follows the vertex copies."""
    split = split_non_manifold_edges(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices)
    if split is None:
        return mesh, data
    source = split.vertex_source
    extend = lambda values: None if values is None else np.asarray(values)[source]
    mesh = replace(mesh, points=mesh.points[source], face_vertices=split.face_vertices,
                   vertex_weights=extend(mesh.vertex_weights), vertex_normals=extend(mesh.vertex_normals),
                   vertex_uvs=extend(mesh.vertex_uvs), vertex_attributes={k: v[source] for k, v in mesh.vertex_attributes.items()},
                   non_manifold_edges=split.edges, non_manifold_seams=len(split.seams))
    if data is None:
        data = SurfaceData(points=mesh.points)
    f = data.features if data.features is not None else SharpFeatures()
    n = source.size
    keys = mesh_edge_keys(mesh.face_sizes, mesh.face_vertices, n)
    edges = np.stack([keys // n, keys % n], axis=1)  # every edge of the sheets, by its copies
    key = lambda pairs: np.minimum(*pairs.T) * n + np.maximum(*pairs.T)  # of input vertex pairs
    tagged = np.r_[key(f.crease_edges), key(split.seams)]
    values = np.r_[f.crease_sharpness, np.full(len(split.seams), INFINITELY_SHARP)]
    sharpness = _lookup(key(source[edges]), tagged, values)  # each copy of a tagged edge keeps its sharpness
    creased = sharpness > 0
    line_corners = np.union1d(split.corners, _sheet_junctions(mesh, edges[sharpness >= INFINITELY_SHARP], split))
    corners = np.r_[f.corner_vertices, line_corners]
    corner_sharpness = np.r_[f.corner_sharpness, np.full(line_corners.size, INFINITELY_SHARP)]
    copies = np.isin(source, corners)
    features = SharpFeatures(edges[creased], sharpness[creased], np.flatnonzero(copies),
                             _lookup(source[copies], corners, corner_sharpness), f.hole_faces, source)
    points = data.points[source]
    data = replace(data, points=points, vertex_blend=extend(data.vertex_blend), weights=extend(data.weights),
                   vertex_normals=extend(data.vertex_normals), features=features)
    return mesh, data


def _sheet_junctions(mesh: MeshFile, sharp: np.ndarray, split) -> np.ndarray:
    """(k,) int: vertices of the non-manifold lines that some sheet holds on three or more seam edges (its
    infinitely sharp and boundary edges, e.g. a fin folded at the line): a corner there, so a corner in
    every sheet (all sheets build one curve)."""
    from ...mesh.halfedges import build_halfedges

    n = split.vertex_source.size
    halves = build_halfedges(mesh.face_sizes, mesh.face_vertices, n)
    boundary = halves.twin < 0
    ends = np.r_[sharp.ravel(), halves.origin[boundary], halves.dest[boundary]]
    pairs = np.r_[np.repeat(np.minimum(*sharp.T) * n + np.maximum(*sharp.T), 2),
                  np.tile(np.minimum(halves.origin[boundary], halves.dest[boundary]) * n
                          + np.maximum(halves.origin[boundary], halves.dest[boundary]), 2)]
    seam_edges = np.bincount(np.unique(np.stack([ends, pairs], axis=1), axis=0)[:, 0], minlength=n)  # distinct edges
    on_line = np.isin(split.vertex_source, split.seams)
    return np.unique(split.vertex_source[on_line & (seam_edges >= 3)])


def _lookup(keys: np.ndarray, table: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The largest of ``values`` whose ``table`` entry equals each key (0 where none)."""
    order = np.argsort(table, kind="stable")
    table, values = table[order], values[order]
    unique, first = np.unique(table, return_index=True)
    largest = np.maximum.reduceat(values, first) if first.size else np.zeros(0)
    slot = np.clip(np.searchsorted(unique, keys), 0, max(unique.size - 1, 0))
    hit = (unique.size > 0) & (unique[slot] == keys) if unique.size else np.zeros(len(keys), bool)
    return np.where(hit, largest[slot] if largest.size else 0.0, 0.0)


def merge_surface_sectors(mesh: MeshFile, data: SurfaceData | None):
    """Merge the faces of crease sectors too large for an exact C0 crease (``mesh.creases.sectors``).

    Faces with different blend ratios, hole tags or other per-face data are not merged, nor semi-sharp
    crease edges; the first edge of a dart chain inside a corner's sector may go (its tag is dropped from
    the features and named in a note, ``MeshFile.sector_merge``); per-face data and holes follow the
    merged polygon's lowest face.
    """
    f = None if data is None else data.features
    if f is None or not np.any(f.crease_sharpness >= INFINITELY_SHARP):
        return mesh, data
    sharp = f.crease_sharpness >= INFINITELY_SHARP
    corners = f.corner_vertices[f.corner_sharpness >= INFINITELY_SHARP]
    columns = [np.isin(np.arange(mesh.n_faces), f.hole_faces).astype(np.float64)]
    if data.face_blend is not None:
        columns.append(np.where(np.isnan(data.face_blend), -1.0, data.face_blend))
    columns += [np.asarray(v, dtype=np.float64) for v in mesh.face_attributes.values()]
    if mesh.face_groups is not None:
        columns.append(mesh.face_groups.astype(np.float64))
    keys = np.unique(np.stack(columns, axis=1), axis=0, return_inverse=True)[1].ravel()
    semi_sharp = f.crease_edges[~sharp & (f.crease_sharpness > 0)]
    merged, kept = merge_sector_faces(mesh, f.crease_edges[sharp], corners, keys, semi_sharp)
    if kept is None:
        return mesh, data
    lost = merged.sector_merge[3]  # dart chains' first edges, merged away (their own note)
    if len(lost):
        n = mesh.n_vertices
        gone = np.isin(np.minimum(*f.crease_edges.T) * n + np.maximum(*f.crease_edges.T), lost[:, 0] * n + lost[:, 1])
        f = replace(f, crease_edges=f.crease_edges[~gone], crease_sharpness=f.crease_sharpness[~gone])
        data = replace(data, features=f)
    return merged, _faces_kept(data, kept)


def drop_repeated_surface_faces(mesh: MeshFile, data: SurfaceData | None):
    """Drop faces that repeat an earlier one (``mesh_file.drop_repeated_faces``); per-face data and holes follow."""
    dropped, kept = drop_repeated_faces(mesh)
    if dropped is mesh:
        return mesh, data
    return dropped, _faces_kept(data, kept)


def _faces_kept(data: SurfaceData | None, kept: np.ndarray) -> SurfaceData | None:
    """``data`` for the faces ``kept`` (F,) bool: per-face blend ratios and hole faces follow them."""
    if data is None:
        return None
    if data.face_blend is not None:
        data = replace(data, face_blend=data.face_blend[kept])
    f = data.features
    if f is not None and f.hole_faces.size:
        holes = f.hole_faces[kept[f.hole_faces]]
        f = replace(f, hole_faces=(np.cumsum(kept) - 1)[holes])
        data = replace(data, features=None if f.is_empty() else f)
    return data


def dissolve_surface_input(mesh: MeshFile, data: SurfaceData | None, keep: np.ndarray | None = None):
    """Dissolve the interior valence-2 vertices of ``mesh`` (``mesh_file.dissolve_mesh_file``); ``data`` follows.

    Per-face data follows the faces kept; a crease on either edge of a dissolved vertex
    becomes a crease of the edge that replaces them (the larger sharpness); a hole on a
    dropped face and a corner on a dissolved vertex are named in a note.
    """
    dissolved, kept = dissolve_mesh_file(mesh, keep)
    if dissolved is mesh:
        return mesh, data
    if data is not None and data.face_blend is not None:
        data = replace(data, face_blend=data.face_blend[kept])
    if data is not None and data.features is not None:
        data = _dissolved_features(data, mesh, dissolved, kept)
    return dissolved, data


def _dissolved_features(data: SurfaceData, mesh: MeshFile, dissolved: MeshFile, kept: np.ndarray) -> SurfaceData:
    """``data``'s sharp features on the mesh without its dissolved vertices (``dissolve_surface_input``)."""
    f = data.features
    gone = np.zeros(mesh.n_vertices, dtype=bool)
    gone[np.setdiff1d(dissolved.dissolved_vertices, mesh.dissolved_vertices)] = True  # this pass's
    edges, sharpness = f.crease_edges, f.crease_sharpness
    touched = gone[edges].any(axis=1)
    # a dissolved vertex's two edges a - v - b: replace each creased one by a - b
    ends = _chain_ends(mesh, gone, edges[touched])
    edges = np.concatenate([edges[~touched], ends])
    sharpness = np.concatenate([sharpness[~touched], sharpness[touched]])
    valid = (edges >= 0).all(axis=1)
    corners = ~gone[f.corner_vertices]
    holes = f.hole_faces[kept[f.hole_faces]]
    features = replace(f, crease_edges=edges[valid], crease_sharpness=sharpness[valid],
                       corner_vertices=f.corner_vertices[corners], corner_sharpness=f.corner_sharpness[corners],
                       hole_faces=(np.cumsum(kept) - 1)[holes])
    notes = list(data.feature_notes)
    lost = int((~corners).sum()), int(f.hole_faces.size - holes.size)
    if any(lost):
        notes.append(f"{mesh.path}: {lost[0]} corners on dissolved valence-2 vertices and {lost[1]} holes on "
                     "faces they left with two corners are not used")
    return replace(data, features=None if features.is_empty() else features, feature_notes=notes)


def _chain_ends(mesh: MeshFile, gone: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(k, 2) int, sorted rows: for each edge with a dissolved end, the kept ends a, b of its run a - v.. - b."""
    sizes = np.asarray(mesh.face_sizes, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    face = np.repeat(np.arange(sizes.size), sizes)
    local = np.arange(offsets[-1]) - offsets[face]
    following = offsets[face] + (local + 1) % sizes[face]
    before = offsets[face] + (local - 1) % sizes[face]
    fv = np.asarray(mesh.face_vertices, dtype=np.int64)
    ahead, back = following.copy(), before.copy()  # the next and previous kept corner of every corner
    for _ in range(int(sizes.max(initial=0))):  # a run is shorter than its face
        ahead = np.where(gone[fv[ahead]], following[ahead], ahead)
        back = np.where(gone[fv[back]], before[back], back)
    run = np.zeros((mesh.n_vertices, 2), dtype=np.int64)
    corners = np.flatnonzero(gone[fv])
    run[fv[corners]] = np.sort(np.stack([fv[back[corners]], fv[ahead[corners]]], axis=1), axis=1)
    dissolved_end = np.where(gone[edges[:, 1]], edges[:, 1], edges[:, 0])
    return run[dissolved_end]


def _welded_features(data: SurfaceData, mesh: MeshFile, welded: MeshFile, kept: np.ndarray, representative: np.ndarray):
    """``data`` with its sharp features renumbered for the welded mesh, and a note on any that welding lost.

    Crease and corner vertices move to the vertex they were welded into; hole faces follow
    the faces welding keeps. A crease pair that is no edge of the welded mesh any more
    (welding kept its position as several vertices) and a hole on a dropped face are named.
    """
    f = data.features
    new_face = np.cumsum(kept) - 1
    holes = f.hole_faces[kept[f.hole_faces]]
    edges = representative[f.crease_edges]
    n = welded.n_vertices
    present = np.isin(np.minimum(*edges.T) * n + np.maximum(*edges.T),
                      mesh_edge_keys(welded.face_sizes, welded.face_vertices, n))
    features = SharpFeatures(edges[present], f.crease_sharpness[present], representative[f.corner_vertices],
                             f.corner_sharpness, new_face[holes])
    notes = list(data.feature_notes)
    lost = int((~present).sum()) + int(f.hole_faces.size - holes.size)
    if lost:
        notes.append(f"{mesh.path}: welding left {int((~present).sum())} crease edges and "
                     f"{int(f.hole_faces.size - holes.size)} hole faces without their edge or face: they are not used")
    return replace(data, features=None if features.is_empty() else features, feature_notes=notes)


def _blend_ratios(mesh: MeshFile, blend_file):
    """(face_blend (F,), vertex_blend (V,)): the PLY ``blend`` properties, overridden where the sidecar file sets a ratio."""
    face_blend = vertex_blend = None
    if "blend" in mesh.face_attributes:
        face_blend = _property_ratios(mesh, mesh.face_attributes["blend"], "face")
    if "blend" in mesh.vertex_attributes:
        vertex_blend = _property_ratios(mesh, mesh.vertex_attributes["blend"], "vertex")
    if blend_file is None:
        return face_blend, vertex_blend
    file_faces, file_vertices = read_blend_file(blend_file, mesh)
    if face_blend is not None:  # the sidecar file wins where it sets a ratio
        file_faces = np.where(np.isnan(file_faces), face_blend, file_faces)
    if file_vertices is not None and vertex_blend is not None:
        file_vertices = np.where(np.isnan(file_vertices), vertex_blend, file_vertices)
    return file_faces, vertex_blend if file_vertices is None else file_vertices


def _weights(mesh: MeshFile, use_weights: bool | None):
    """(V,) positive weights of the used vertices (1 elsewhere), or None when not asked for or all 1."""
    weights = mesh.vertex_weights
    if use_weights and weights is None:
        raise MeshInputError(mesh.path, "has no vertex weights (OBJ `v x y z w`, PLY property `weight`) for --weights")
    if weights is None or not (use_weights or (use_weights is None and np.any(weights != 1.0))):
        return None
    used = _used_vertices(mesh)
    bad = np.flatnonzero(used & ~(weights > 0))
    if bad.size:
        raise MeshInputError(mesh.path, f"vertex {bad[0]} has weight {weights[bad[0]]!r}: rational weights must be positive")
    return np.where(used, weights, 1.0)


def _vertex_normals(mesh: MeshFile) -> np.ndarray:
    """(V, 3) normals of the used vertices (NaN elsewhere); every used vertex needs one."""
    if mesh.vertex_normals is None:
        raise MeshInputError(mesh.path, "has no vertex normals (OBJ `vn` with `f v//vn`, PLY `nx ny nz`) to interpolate")
    used = _used_vertices(mesh)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    length = np.linalg.norm(n, axis=1)
    missing = np.flatnonzero(used & ~(length > 0))
    if missing.size:
        raise MeshInputError(mesh.path, f"vertex {missing[0]} has no (or a zero) normal ({missing.size} such vertices)")
    return np.where(used[:, None], n, np.nan)


def _attribute_columns(mesh: MeshFile):
    """(columns (V, k), names, colour scale): texture coordinates "u" "v", then the colours; 0 on unused vertices."""
    columns, names, colour_scale = [], [], 1.0
    if mesh.vertex_uvs is not None:
        columns.append(np.asarray(mesh.vertex_uvs, dtype=np.float64))
        names += ["u", "v"]
    colours = [c for c in COLOUR_NAMES if c in mesh.vertex_attributes]
    if colours:
        values = np.stack([np.asarray(mesh.vertex_attributes[c], dtype=np.float64) for c in colours], axis=1)
        columns.append(values)
        names += colours
        colour_scale = 1.0 if np.nanmax(values, initial=0.0) <= 1.0 else 255.0
    if not columns:
        raise MeshInputError(mesh.path, "has no texture coordinates or vertex colours to carry (--attributes)")
    extra = np.concatenate(columns, axis=1)
    used = _used_vertices(mesh)
    missing = np.flatnonzero(used & ~np.all(np.isfinite(extra), axis=1))
    if missing.size:
        raise MeshInputError(mesh.path, f"vertex {missing[0]} has no texture coordinate ({missing.size} such vertices): "
                             "--attributes needs one per vertex")
    return np.where(used[:, None], extra, 0.0), names, colour_scale


__all__ = ["SurfaceData", "surface_data", "weld_surface_input", "dissolve_surface_input", "merge_surface_sectors", "prepare_surface_input", "read_blend_file", "COLOUR_NAMES"]
