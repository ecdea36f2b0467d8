"""The c1surf patch file (JSON): one Bezier patch per entry.

Shape (see docs/patch-format.md)::

    {"format": "c1surf-patches", "version": 1, "c1surf_version": "...",
     "options": {...}, "input": {...}, "counts": {...},
     "patches": [{"kind": "biquadratic" | "bicubic", "degree": [du, dv],
                  "points": (du+1) x (dv+1) x 3 nested lists,
                  "weights": (du+1) x (dv+1) (rational patches only, A2a),
                  "source": {"face": f} | {"vertex": v} | {"edge": [a, b]},
                  "corners": [4 ids], "edges": [4 ids], "reversed": [4 bools],
                  "neighbours": [[patch, side] x 4]}, ...]}

Floats are written with ``repr`` precision, so reading gives the same bits.
"""
from __future__ import annotations

import json

import numpy as np

from ...evaluation.adjacency import PatchAdjacency
from ..errors import MeshInputError
from ...evaluation.patch_set import FORMAT_NAME, FORMAT_VERSION, KIND_BY_DEGREE, PatchSet, degree_runs, surface_patch_set


def surface_patch_document(surface, input_path: str | None = None, adjacency=None) -> dict:
    """The JSON document (a dict) of a ``core.surface.Surface``."""
    return patch_set_document(surface_patch_set(surface, input_path, adjacency))


def patch_set_document(patch_set: PatchSet) -> dict:
    """The JSON document (a dict) of a ``PatchSet``: its header, then one entry per patch."""
    patches = []
    for group in patch_set.groups:
        du, dv = group.shape[1] - 1, group.shape[2] - 1
        kind = KIND_BY_DEGREE.get(du) if du == dv else None
        for points in group[..., :3].tolist():
            patches.append({"kind": kind or f"bezier{du}x{dv}", "degree": [du, dv], "points": points})
    if patch_set.weights is not None:  # rational patches (A2a): "weights" of shape (du+1, dv+1)
        flat_weights = [w for group in patch_set.weights for w in np.asarray(group).tolist()]
        for patch, w in zip(patches, flat_weights):
            patch["weights"] = w
    for patch, source in zip(patches, patch_set.source_dicts()):
        if source is not None:
            patch["source"] = source
    adjacency = patch_set.adjacency
    if adjacency is not None:
        neighbours = adjacency.neighbours().tolist()
        for patch, c, e, r, n in zip(patches, adjacency.corners.tolist(), adjacency.edges.tolist(),
                                     adjacency.reversed.tolist(), neighbours):
            patch["corners"], patch["edges"], patch["reversed"], patch["neighbours"] = c, e, r, n
    return {**patch_set.header, "patches": patches}


def write_patches_json(path, surface, input_path: str | None = None, adjacency=None, merged=None, **_options) -> None:
    """Write ``surface``'s patches to ``path`` as c1surf-patches JSON.

    ``adjacency``: the surface's ``PatchAdjacency`` when already computed;
    ``merged``: ``core.merge.MergedPiece`` list (``convert --merge``), written under
    the key "merged" (every patch stays in "patches"); other keyword options
    (IGES units, ...) do not apply to JSON.
    """
    patch_set = surface_patch_set(surface, input_path, adjacency)
    if not merged:
        write_patch_set_json(path, patch_set)
        return
    doc = patch_set_document(patch_set)
    doc["merged"] = [merged_piece_document(piece) for piece in merged]
    text = json.dumps(doc, separators=(",", ":"))
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
        f.write("\n")


def merged_piece_document(piece) -> dict:
    """JSON of a B-spline surface made of biquadratic patches: knots, control points
    (m+2, n+2, 3), weights when rational, and the patches (indices into "patches",
    with the quarter turns taking each patch's (u, v) to the piece's) of its m x n spans."""
    out = {"kind": "bspline", "degree": [2, 2], "knots_u": piece.knots_u.tolist(), "knots_v": piece.knots_v.tolist(),
           "points": piece.points[..., :3].tolist()}
    if piece.weights is not None:
        out["weights"] = piece.weights.tolist()
    out["patches"] = piece.patches.tolist()
    out["rotation"] = piece.rotation.tolist()
    return out


def write_patch_set_json(path, patch_set: PatchSet) -> None:
    """Write a ``PatchSet`` as c1surf-patches JSON (compact, one line, ``repr`` floats)."""
    text = json.dumps(patch_set_document(patch_set), separators=(",", ":"))  # dumps: the C encoder, unlike dump
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
        f.write("\n")


def read_patch_set_json(path) -> PatchSet:
    """Read a c1surf-patches JSON file: patches in file order, sources, adjacency, header.

    Adjacency is returned only when every patch has "corners", "edges" and
    "reversed" ("neighbours" is derived from them and not read).
    """
    doc = _load_document(path)
    patches, kinds, sources, corners, edges, flags, weights = [], [], [], [], [], [], []
    has_source, has_adjacency = True, True
    for k, patch in enumerate(doc.get("patches", [])):
        points = _patch_points(path, k, patch)
        patches.append(points)
        if isinstance(patch, dict) and "weights" in patch:
            weights.append(_patch_weights(path, k, patch, points.shape[:2]))
        source = patch.get("source") if isinstance(patch, dict) else None
        if isinstance(source, dict) and len(source) == 1:
            (kind, value), = source.items()
            try:
                pair = [int(value[0]), int(value[1])] if kind == "edge" else [int(value), -1]
            except (TypeError, ValueError, IndexError):
                raise MeshInputError(str(path), f"patch {k}: malformed source {source!r}") from None
            kinds.append(kind)
            sources.append(pair)
        else:
            has_source = False
        if all(key in patch for key in ("corners", "edges", "reversed")):
            corners.append(patch["corners"])
            edges.append(patch["edges"])
            flags.append(patch["reversed"])
        else:
            has_adjacency = False
    n = len(patches)
    adjacency = None
    if has_adjacency and n:
        try:
            adjacency = PatchAdjacency(np.asarray(corners, dtype=np.int64), np.asarray(edges, dtype=np.int64),
                                       np.asarray(flags, dtype=bool))
            adjacency.validate(n)
        except (TypeError, ValueError) as e:
            raise MeshInputError(str(path), f"malformed patch adjacency ({e})") from None
    header = {key: value for key, value in doc.items() if key != "patches"}
    source_kind = np.array(kinds) if has_source and n else None
    source = np.asarray(sources, dtype=np.int64).reshape(-1, 2) if has_source and n else None
    if weights and len(weights) != n:
        raise MeshInputError(str(path), f'only {len(weights)} of {n} patches have "weights": give all or none')
    return PatchSet(degree_runs(patches), adjacency, source_kind, source, header, degree_runs(weights) if weights else None)


def _patch_weights(path, k: int, patch, shape) -> np.ndarray:
    try:
        w = np.asarray(patch["weights"], dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise MeshInputError(str(path), f"patch {k}: malformed weights ({e})") from None
    if w.shape != tuple(shape) or not np.all(np.isfinite(w) & (w > 0)):
        raise MeshInputError(str(path), f"patch {k}: weights must be positive with shape {tuple(shape)}, got {w.shape}")
    return w


def _load_document(path) -> dict:
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except FileNotFoundError:
        raise MeshInputError(str(path), "no such file") from None
    except IsADirectoryError:
        raise MeshInputError(str(path), "is a directory, not a patch file") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise MeshInputError(str(path), f"not a JSON patch file ({e})", getattr(e, "lineno", None)) from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT_NAME:
        raise MeshInputError(str(path), f'not a c1surf patch file (missing "format": "{FORMAT_NAME}")')
    if doc.get("version") != FORMAT_VERSION:
        raise MeshInputError(str(path), f"patch file version {doc.get('version')} is not supported (this c1surf reads version {FORMAT_VERSION})")
    if not isinstance(doc.get("patches", []), list):
        raise MeshInputError(str(path), '"patches" must be a list')
    return doc


def _patch_points(path, k: int, patch) -> np.ndarray:
    try:
        du, dv = (int(x) for x in patch["degree"])
        points = np.asarray(patch["points"], dtype=np.float64)
    except (KeyError, TypeError, ValueError) as e:
        raise MeshInputError(str(path), f"patch {k} is malformed ({e})") from None
    if du < 1 or dv < 1 or points.shape != (du + 1, dv + 1, 3) or not np.all(np.isfinite(points)):
        raise MeshInputError(str(path), f"patch {k}: points must be finite with shape ({du + 1}, {dv + 1}, 3), got {points.shape}")
    return points


def read_patches_json(path) -> list[np.ndarray]:
    """Read a c1surf-patches JSON file.

    Returns
    -------
    list of (p, du+1, dv+1, 3) float arrays, one per distinct degree, in file order of first appearance
    """
    doc = _load_document(path)
    groups: dict[tuple, list] = {}
    for k, patch in enumerate(doc.get("patches", [])):
        points = _patch_points(path, k, patch)
        groups.setdefault(points.shape, []).append(points)
    return [np.stack(v) for v in groups.values()]
