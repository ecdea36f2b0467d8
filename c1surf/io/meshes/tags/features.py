"""From what a mesh file says about sharp features to the construction's ``SharpFeatures``, and the notes.

Three sources, merged (an edge or corner named twice keeps its largest sharpness):

- the file's own tags (``MeshFile.tags``: OBJ ``t`` lines, PLY edge creases and vertex corners);
- a JSON sidecar (``--creases FILE``) for files written without tags::

      {"creases": [[0, 1, 10], [4, 5, 6, 2.5]],   # a chain of vertices, then its sharpness
       "corners": [[7, 10]],                      # vertex, sharpness
       "holes": [3, 12]}                          # faces (all indices from 0)

- ``--crease-angle DEG``: every edge whose faces meet at a dihedral angle above
  DEG is infinitely sharp (``mesh.feature_edges``).

Every tag is either honoured or named in a note with what c1surf does instead.
"""
from __future__ import annotations

import json

import numpy as np

from ....construction.features import INFINITELY_SHARP, SharpFeatures
from ....mesh.feature_edges import feature_edges
from ...errors import MeshInputError
from .record import SharpTags, check_tags

__all__ = ["sharp_features", "read_creases_file", "read_sidecar_json", "feature_notes"]

OTHER_TAGS = {
    "creasemethod": "c1surf's own crease rule is used (stencils.creases)",
    "facevaryinginterpolateboundary": "c1surf carries no face-varying data",
    "facevaryingpropagatecorners": "c1surf carries no face-varying data",
    "smoothtriangles": "triangles follow A3 (or --triangles parametric)",
    "vertexedit": "hierarchical edits are not supported",
    "edgeedit": "hierarchical edits are not supported",
}


def sharp_features(mesh, creases_file=None, crease_angle: float | None = None, ignore_tags: bool = False,
                   exact_creases: bool = False):
    """The creases, corners and holes of ``mesh`` for the construction, and the notes about them.

    Parameters
    ----------
    mesh : io.meshes.mesh_file.MeshFile
    creases_file : path of a JSON sidecar, or None
    crease_angle : float degrees, or None
    ignore_tags : build the smooth surface: the file's tags are read and named in a note, not used
    exact_creases : the construction makes infinitely sharp creases C0 where it can (its own note says
        which); without it a note says they are the sharpest G1 crease

    Returns
    -------
    features : SharpFeatures or None (nothing sharp, no hole)
    notes : list of str, one line each
    """
    tags = getattr(mesh, "tags", None) or SharpTags()
    notes = feature_notes(mesh.path, tags, ignore_tags)
    features = SharpFeatures() if ignore_tags else _from_tags(tags)
    if creases_file is not None:
        features = features.merged(read_creases_file(creases_file, mesh))
    if crease_angle is not None:
        edges = feature_edges(mesh.face_sizes, mesh.face_vertices, mesh.points, crease_angle)
        features = features.merged(SharpFeatures(edges, np.full(len(edges), INFINITELY_SHARP)))
        notes.append(f"--crease-angle {crease_angle:g}: {len(edges)} edges with a dihedral angle above it are creases")
    infinite = np.any(features.crease_sharpness >= INFINITELY_SHARP) or np.any(features.corner_sharpness >= INFINITELY_SHARP)
    if infinite and not exact_creases:
        notes.append("infinitely sharp creases (sharpness >= 10) are built as the sharpest G1 crease (sharpness 10: "
                     "a narrow G1 fillet), not as a C0 edge (--g1-creases, or vertex interpolation, which C0 seams "
                     "do not take yet)")
    return (None if features.is_empty() else features), notes


def _from_tags(tags: SharpTags) -> SharpFeatures:
    return SharpFeatures(tags.crease_edges, tags.crease_sharpness, tags.corner_vertices, tags.corner_sharpness,
                         tags.hole_faces)


def feature_notes(path, tags: SharpTags, ignore_tags: bool) -> list[str]:
    """One note on the file's tags: what is honoured, and every tag that is not, with what c1surf does instead."""
    if tags.is_empty():
        return []
    if ignore_tags:
        return [f"{path}: sharp-feature tags ignored (--ignore-tags), the surface is smooth: {tags.summary()}"]
    ignored = []
    if tags.interpolate_boundary is not None:
        ignored.append(f"interpolateboundary {tags.interpolate_boundary} (c1surf's boundary rule, a ghost layer, "
                       "always ends the surface on a curve along the boundary polygon)")
    names: dict[str, int] = {}
    for name, _ in tags.other:
        names[name] = names.get(name, 0) + 1
    for name, count in names.items():
        instead = OTHER_TAGS.get(name, "c1surf does not know this tag")
        ignored.append(f"{name} ({count} tag{'s' if count != 1 else ''}: {instead})")
    honoured = SharpTags(tags.crease_edges, tags.crease_sharpness, None, tags.corner_vertices, tags.corner_sharpness,
                         None, tags.hole_faces).summary()
    parts = [f"sharp-feature tags honoured: {honoured}"] if honoured else []
    if ignored:
        parts.append("not honoured: " + "; ".join(ignored))
    return [f"{path}: " + "; ".join(parts)]


def read_sidecar_json(path: str, option: str, what: str):
    """The JSON document of a sidecar file given with ``option``; one-line MeshInputError when unreadable."""
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except FileNotFoundError:
        raise MeshInputError(path, f"no such file: check the {option} path") from None
    except IsADirectoryError:
        raise MeshInputError(path, f"is a directory, not {what}") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise MeshInputError(path, f"not a JSON file ({e})", getattr(e, "lineno", None)) from None
    except RecursionError:  # json's decoder recurses once per level
        raise MeshInputError(path, f"not {what}: its JSON is nested too deeply to read") from None


def read_creases_file(path, mesh) -> SharpFeatures:
    """Read a JSON sidecar of creases, corners and holes for ``mesh`` (module docstring), checked against it.

    Raises
    ------
    MeshInputError, one line naming the entry that is wrong
    """
    path = str(path)
    doc = read_sidecar_json(path, "--creases", "a creases file")
    if not isinstance(doc, dict) or set(doc) - {"creases", "corners", "holes"}:
        raise MeshInputError(path, 'expected a JSON object with the keys "creases", "corners" and "holes" only')
    edges, edge_sharpness = [], []
    for k, chain in enumerate(_entries(path, doc, "creases")):
        vertices, sharpness = _numbers(path, f"creases[{k}]", chain, 3)
        edges += list(zip(vertices[:-1], vertices[1:]))
        edge_sharpness += [sharpness] * (len(vertices) - 1)
    corners, corner_sharpness = [], []
    for k, entry in enumerate(_entries(path, doc, "corners")):
        vertices, sharpness = _numbers(path, f"corners[{k}]", entry, 2, exact=True)
        corners.append(vertices[0])
        corner_sharpness.append(sharpness)
    holes = _entries(path, doc, "holes")
    if not all(isinstance(f, int) and not isinstance(f, bool) for f in holes):
        raise MeshInputError(path, '"holes" must be a list of face indices (from 0)')
    tags = SharpTags(np.array(edges, dtype=np.int64).reshape(-1, 2), np.array(edge_sharpness, dtype=float), None,
                     np.array(corners, dtype=np.int64), np.array(corner_sharpness, dtype=float), None,
                     np.array(holes, dtype=np.int64))
    check_tags(tags, mesh.face_sizes, mesh.face_vertices, mesh.n_vertices, path)
    return _from_tags(tags)


def _entries(path: str, doc: dict, key: str) -> list:
    value = doc.get(key, [])
    if not isinstance(value, list):
        raise MeshInputError(path, f'"{key}" must be a list')
    return value


def _numbers(path: str, where: str, entry, least: int, exact: bool = False):
    """(vertex indices, sharpness) of one ``[v0, v1, ..., s]`` entry."""
    ok = isinstance(entry, list) and (len(entry) == least if exact else len(entry) >= least)
    ok = ok and all(isinstance(v, int) and not isinstance(v, bool) for v in entry[:-1])
    ok = ok and isinstance(entry[-1], (int, float)) and not isinstance(entry[-1], bool)
    if not ok:
        shape = "[vertex, sharpness]" if exact else "[vertex, vertex, ..., sharpness]"
        raise MeshInputError(path, f"{where}: expected {shape} (vertex indices from 0), got {json.dumps(entry)}")
    return [int(v) for v in entry[:-1]], float(entry[-1])
