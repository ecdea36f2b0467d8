"""The c1surf patch file (JSON): one Bezier patch per entry.

Shape (see docs/patch-format.md)::

    {"format": "c1surf-patches", "version": 1, "c1surf_version": "...",
     "options": {...}, "input": {...}, "counts": {...},
     "patches": [{"kind": "biquadratic" | "bicubic", "degree": [du, dv],
                  "points": (du+1) x (dv+1) x 3 nested lists,
                  "weights": (du+1) x (dv+1) (rational patches only, A2a),
                  "source": {"face": f} | {"vertex": v} | {"edge": [a, b]},
                  "corners": [4 ids], "edges": [4 ids], "reversed": [4 bools],
                  "neighbours": [[patch, side] x 4]}, ...],
     "merged": [{"kind": "bspline", "degree": [2, 2], "knots_u": [...], "knots_v": [...],
                 "points": (m+2) x (n+2) x 3, "weights": (rational only),
                 "patches": m x n, "rotation": m x n}, ...]}      (convert --merge only)

Floats are written with ``repr`` precision, so reading gives the same bits.
``write_patch_stream_json`` writes the same bytes from a ``PatchStream``
(the streamed conversion), by blocks of patches.
"""
from __future__ import annotations

import json

import numpy as np

from ...evaluation.patch_set import KIND_BY_DEGREE, SOURCE_KINDS, PatchSet, degree_runs, surface_patch_set
from ..errors import MeshInputError
from ..finite import refuse_non_finite, refuse_non_finite_patch_set
from .checks import check_crease_sides, check_header, checked_adjacency, checked_piece, checked_weights

_PIECE_KEYS = ("points", "knots_u", "knots_v", "patches", "rotation")  # and "weights" when rational
_SEPARATORS = (",", ":")  # compact, one line
_STREAM_BLOCK = 1 << 12  # patches per block of a streamed file: some MB of Python lists and text


def surface_patch_document(surface, input_path: str | None = None, adjacency=None) -> dict:
    """The JSON document (a dict) of a ``core.surface.Surface``."""
    return patch_set_document(surface_patch_set(surface, input_path, adjacency))


def patch_set_document(patch_set: PatchSet) -> dict:
    """The JSON document (a dict) of a ``PatchSet``: its header, then one entry per patch."""
    sources = patch_set.source_dicts()
    adjacency = _adjacency_rows(patch_set.adjacency)
    patches, start = [], 0
    for k, group in enumerate(patch_set.groups):
        stop = start + len(group)
        weights = None if patch_set.weights is None else np.asarray(patch_set.weights[k])
        patches += patch_entries(group, sources[start:stop], None if adjacency is None else [a[start:stop] for a in adjacency],
                                 weights)
        start = stop
    doc = {**patch_set.header, "patches": patches}
    if patch_set.merged:  # convert --merge: B-spline pieces standing for rectangles of patches
        doc["merged"] = [merged_piece_document(piece) for piece in patch_set.merged]
    return doc


def _adjacency_rows(adjacency) -> list | None:
    """[corners (P, 4), edges (P, 4), reversed (P, 4), neighbours (P, 4, 2)] of a PatchAdjacency, or None."""
    return None if adjacency is None else [adjacency.corners, adjacency.edges, adjacency.reversed, adjacency.neighbours()]


def patch_entries(points: np.ndarray, sources: list | None = None, adjacency: list | None = None,
                  weights: np.ndarray | None = None) -> list:
    """The "patches" entries of c patches of one degree, keys in file order.

    Parameters
    ----------
    points : (c, du+1, dv+1, >= 3) float (x, y, z are written)
    sources : c dicts ({"face": f}, ...) or None each, or None
    adjacency : [corners (c, 4), edges (c, 4), reversed (c, 4), neighbours (c, 4, 2)] arrays, or None
    weights : (c, du+1, dv+1) float (rational patches), or None
    """
    du, dv = points.shape[1] - 1, points.shape[2] - 1
    kind = (KIND_BY_DEGREE.get(du) if du == dv else None) or f"bezier{du}x{dv}"
    patches = [{"kind": kind, "degree": [du, dv], "points": p} for p in points[..., :3].tolist()]
    if weights is not None:  # rational patches (A2a): "weights" of shape (du+1, dv+1)
        for patch, w in zip(patches, weights.tolist()):
            patch["weights"] = w
    for patch, source in zip(patches, sources or []):
        if source is not None:
            patch["source"] = source
    if adjacency is not None:
        for patch, c, e, r, n in zip(patches, *(np.asarray(a).tolist() for a in adjacency)):
            patch["corners"], patch["edges"], patch["reversed"], patch["neighbours"] = c, e, r, n
    return patches


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


def write_patch_set_json(path, patch_set: PatchSet, **_options) -> None:
    """Write a ``PatchSet`` as c1surf-patches JSON (compact, one line, ``repr`` floats).

    Weights (rational patches) and merged pieces are kept; the options of other
    formats (IGES units, ...) do not apply.
    """
    refuse_non_finite_patch_set(patch_set, path)  # json.dumps would write NaN, which no JSON reader takes
    text = json.dumps(patch_set_document(patch_set), separators=_SEPARATORS)  # dumps: the C encoder, unlike dump
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
        f.write("\n")


def write_patch_stream_json(path, stream, **_options) -> None:
    """Write a ``evaluation.patch_set.PatchStream`` by blocks of patches: the bytes ``write_patch_set_json``
    writes for the surface's ``PatchSet`` (no weights, no merged pieces), never holding all entries.

    The document is the header's keys, then ``"patches"``: its text is the header's without the closing
    brace, then the entries of each block (``patch_entries``, dumped as ``json.dumps`` dumps them in a list).
    """
    head = json.dumps(stream.header, separators=_SEPARATORS)
    with open(path, "w", encoding="utf-8") as f:
        f.write(head[:-1] + ("," if stream.header else "") + '"patches":[')
        separator, offset = "", 0
        for kind, count in enumerate(stream.counts):
            for a, points in stream.blocks(kind, _STREAM_BLOCK):
                refuse_non_finite(points, "control point coordinates", path)
                lo, hi = offset + a, offset + a + len(points)
                adjacency = [stream.integers(name, lo, hi) for name in ("corners", "edges", "reversed", "neighbours")]
                entries = patch_entries(points, stream.source_dicts(lo, hi), adjacency)
                f.write(separator + json.dumps(entries, separators=_SEPARATORS)[1:-1])
                separator = ","
            offset += count
        f.write("]}\n")


def read_patch_set_json(path) -> PatchSet:
    """Read a c1surf-patches JSON file: patches in file order, weights, sources, adjacency, merged pieces, header.

    Adjacency is returned only when every patch has "corners", "edges" and
    "reversed" ("neighbours" is derived from them and not read).
    """
    doc = _load_document(path)
    entries = doc.get("patches", [])
    patches = [_patch_points(path, k, patch) for k, patch in enumerate(entries)]
    source_kind, source = _sources(path, entries)
    adjacency = None
    if entries and all(all(key in patch for key in ("corners", "edges", "reversed")) for patch in entries):
        adjacency = checked_adjacency(path, *([patch[key] for patch in entries] for key in ("corners", "edges", "reversed")),
                                      len(entries))
    header = {key: value for key, value in doc.items() if key not in ("patches", "merged")}
    check_crease_sides(path, header, len(entries))
    return PatchSet(degree_runs(patches), adjacency, source_kind, source, header, _weights(path, entries, patches),
                    _merged(path, doc.get("merged", []), patches))


def _weights(path, entries, patches) -> list | None:
    """Runs of the patches' "weights" (all or none), parallel to ``degree_runs(patches)``."""
    weights = [checked_weights(path, f"patch {k}", patch["weights"], points.shape[:2])
               for k, (patch, points) in enumerate(zip(entries, patches)) if "weights" in patch]
    if weights and len(weights) != len(patches):
        raise MeshInputError(str(path), f'only {len(weights)} of {len(patches)} patches have "weights": give all or none')
    return degree_runs(weights) if weights else None


def _sources(path, entries):
    """(source_kind (P,) str, source (P, 2) int64) of the patches, or (None, None) unless every patch has one."""
    kinds, sources = [], []
    for k, patch in enumerate(entries):
        source = patch.get("source")
        if not (isinstance(source, dict) and len(source) == 1):
            return None, None
        (kind, value), = source.items()
        if kind not in SOURCE_KINDS:
            raise MeshInputError(str(path), f"patch {k}: the source is a {', '.join(SOURCE_KINDS[:-1])} or "
                                 f"{SOURCE_KINDS[-1]}, not {str(kind)[:40]!r}")
        try:
            sources.append([int(value[0]), int(value[1])] if kind == "edge" else [int(value), -1])
        except (TypeError, ValueError, IndexError, OverflowError):  # OverflowError: int(Infinity)
            raise MeshInputError(str(path), f"patch {k}: malformed source {str(source)[:80]}") from None
        kinds.append(kind)
    if not entries:
        return None, None
    try:
        return np.array(kinds), np.asarray(sources, dtype=np.int64).reshape(-1, 2)
    except OverflowError:
        raise MeshInputError(str(path), "a patch's source is an integer beyond any face or edge index") from None


def _merged(path, documents, patches) -> list:
    """The MergedPiece of every "merged" entry (``merged_piece_document``)."""
    if not isinstance(documents, list):
        raise MeshInputError(str(path), '"merged" must be a list')
    n_biquadratic = sum(points.shape[:2] == (3, 3) for points in patches)
    pieces = []
    for k, piece in enumerate(documents):
        if not isinstance(piece, dict) or any(key not in piece for key in _PIECE_KEYS):
            raise MeshInputError(str(path), f"merged piece {k}: needs {', '.join(_PIECE_KEYS)}")
        points, knots_u, knots_v, patches_, rotation = (piece[key] for key in _PIECE_KEYS)
        pieces.append(checked_piece(path, k, points, piece.get("weights"), (knots_u, knots_v), patches_, rotation,
                                    n_biquadratic))
    return pieces


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
    except RecursionError:  # json's decoder recurses once per level
        raise MeshInputError(str(path), "not a c1surf patch file: its JSON is nested too deeply to read (a patch file "
                                        "nests 4 levels)") from None
    check_header(path, doc)
    if not isinstance(doc.get("patches", []), list):
        raise MeshInputError(str(path), '"patches" must be a list')
    return doc


def _patch_points(path, k: int, patch) -> np.ndarray:
    try:
        du, dv = (int(x) for x in patch["degree"])
        points = np.asarray(patch["points"], dtype=np.float64)
    except (KeyError, TypeError, ValueError, OverflowError) as e:  # OverflowError: a degree of 1e309
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
