"""What a mesh file says beyond its points: blend ratios, weights, normals, attributes.

``surface_data(mesh, ...)`` gathers the per-cell and per-vertex data the
extensions of the paper use (``construction.surface.Surface`` arguments):

- blend ratios per cell and per vertex (A1, section 4): PLY face / vertex
  property ``blend``, or a sidecar JSON file (``--blend-file``, read by ``io.meshes.sidecars``)::

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
  sidecar and ``--crease-angle`` (``prepare.features``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import MeshInputError
from .features import sharp_features
from .options import InputOptions

__all__ = ["SurfaceData", "Sidecars", "surface_data", "COLOUR_NAMES"]

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


@dataclass(frozen=True)
class Sidecars:
    """What the sidecar files of ``InputOptions`` say, as read by ``io.meshes.sidecars`` (checked against the mesh).

    creases : construction.features.SharpFeatures of ``--creases``, or None
    face_blend : (F,) float, NaN where unset, or None: no ``--blend-file``
    vertex_blend : (V,) float, NaN where unset, or None: the blend file names no vertices
    """

    creases: object = None
    face_blend: np.ndarray | None = None
    vertex_blend: np.ndarray | None = None


def surface_data(mesh, options: InputOptions, exact_creases: bool = False, sidecars: Sidecars | None = None) -> SurfaceData:
    """Collect the extension data of ``mesh`` (see the module docstring).

    Parameters
    ----------
    mesh : MeshFile (``io.meshes.mesh_file``)
    options : InputOptions: weights, normals, attributes, crease angle, ignore tags, non-manifold rule
    exact_creases : the construction makes infinitely sharp creases C0 (``InputOptions.surface_options``)
    sidecars : Sidecars, what the ``blend_file`` and ``creases_file`` of ``options`` say, or None

    Raises
    ------
    MeshInputError when requested data is missing or malformed.
    """
    sidecars = sidecars or Sidecars()
    data = SurfaceData(points=np.asarray(mesh.points, dtype=np.float64), non_manifold=options.non_manifold)
    data.face_blend, data.vertex_blend = _blend_ratios(mesh, sidecars)
    data.weights = _weights(mesh, options.weights)
    data.features, data.feature_notes = sharp_features(mesh, sidecars.creases, options.crease_angle, options.ignore_tags,
                                                       exact_creases)
    if options.normals:
        data.vertex_normals = _vertex_normals(mesh)
    if options.attributes:
        extra, data.attribute_names, data.colour_scale = _attribute_columns(mesh)
        data.points = np.concatenate([data.points, extra], axis=1)
    return data


def _property_ratios(mesh, values, what: str) -> np.ndarray:
    r = np.asarray(values, dtype=np.float64)
    r = np.where(r < 0, np.nan, r)
    bad = np.flatnonzero(r > 1)
    if bad.size:
        raise MeshInputError(mesh.path, f"{what} property 'blend' is {r[bad[0]]!r} at {what} {bad[0]}: blend ratios lie in [0, 1]")
    return r


def _used_vertices(mesh) -> np.ndarray:
    used = np.zeros(mesh.n_vertices, dtype=bool)
    used[mesh.face_vertices] = True
    return used


def _blend_ratios(mesh, sidecars: Sidecars):
    """(face_blend (F,), vertex_blend (V,)): the PLY ``blend`` properties, overridden where the sidecar file sets a ratio."""
    face_blend = vertex_blend = None
    if "blend" in mesh.face_attributes:
        face_blend = _property_ratios(mesh, mesh.face_attributes["blend"], "face")
    if "blend" in mesh.vertex_attributes:
        vertex_blend = _property_ratios(mesh, mesh.vertex_attributes["blend"], "vertex")
    if sidecars.face_blend is None:
        return face_blend, vertex_blend
    file_faces, file_vertices = sidecars.face_blend, sidecars.vertex_blend
    if face_blend is not None:  # the sidecar file wins where it sets a ratio
        file_faces = np.where(np.isnan(file_faces), face_blend, file_faces)
    if file_vertices is not None and vertex_blend is not None:
        file_vertices = np.where(np.isnan(file_vertices), vertex_blend, file_vertices)
    return file_faces, vertex_blend if file_vertices is None else file_vertices


def _weights(mesh, use_weights: bool | None):
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


def _vertex_normals(mesh) -> np.ndarray:
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


def _attribute_columns(mesh):
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
