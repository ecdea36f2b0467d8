"""Sidecar JSON files of a mesh: sharp features (``--creases``) and blend ratios (``--blend-file``).

The creases file::

      {"creases": [[0, 1, 10], [4, 5, 6, 2.5]],   # a chain of vertices, then its sharpness
       "corners": [[7, 10]],                      # vertex, sharpness
       "holes": [3, 12]}                          # faces (all indices from 0)

The blend-ratio file (``read_blend_file``)::

      {"default": 0.15,                      # cells without a ratio (else --blend)
       "faces": {"12": 0.3, "handle": 0.0},  # 0-based face index, or OBJ group (g/o) name
       "vertices": {"5": 0.0, "9": 0.5}}     # 0-based vertex index

Both are checked against the mesh they belong to; ``prepare`` merges them with the file's own data.
"""
from __future__ import annotations

import json

import numpy as np

from ...construction.features import SharpFeatures
from ...mesh.creases.tags import SharpTags
from ..errors import MeshInputError
from .tags.record import check_tags

__all__ = ["read_sidecar_json", "read_creases_file", "read_blend_file"]


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
    return SharpFeatures(tags.crease_edges, tags.crease_sharpness, tags.corner_vertices, tags.corner_sharpness,
                         tags.hole_faces)


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


def _ratio(path, where: str, value) -> float:
    try:
        r = float(value)
    except (TypeError, ValueError):
        raise MeshInputError(path, f"{where}: blend ratio {value!r} is not a number") from None
    if not (0.0 <= r <= 1.0):
        raise MeshInputError(path, f"{where}: blend ratio {r!r} is not in [0, 1]")
    return r


def read_blend_file(path, mesh):
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
