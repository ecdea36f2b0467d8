"""The c1surf patch file (JSON): one Bezier patch per entry.

Shape (see docs/patch-format.md)::

    {"format": "c1surf-patches", "version": 1, "c1surf_version": "...",
     "options": {...}, "input": {...}, "counts": {...},
     "patches": [{"kind": "biquadratic" | "bicubic", "degree": [du, dv],
                  "points": (du+1) x (dv+1) x 3 nested lists,
                  "source": {"face": f} | {"vertex": v} | {"edge": [a, b]}}, ...]}

Floats are written with ``repr`` precision, so reading gives the same bits.
"""
from __future__ import annotations

import json

import numpy as np

from .. import __version__
from ..core.doo_sabin import FACE_FROM_EDGE, FACE_FROM_FACE
from .errors import MeshInputError

FORMAT_NAME = "c1surf-patches"
FORMAT_VERSION = 1
KIND_BY_DEGREE = {2: "biquadratic", 3: "bicubic"}


def surface_patch_document(surface, input_path: str | None = None) -> dict:
    """The JSON document (a dict) of a ``core.surface.Surface``."""
    kind, index, edge = surface.patch_sources()
    a, b = edge[:, 0], edge[:, 1]
    sources = [
        {"face": int(i)} if k == FACE_FROM_FACE else ({"edge": [int(x), int(y)]} if k == FACE_FROM_EDGE else {"vertex": int(i)})
        for k, i, x, y in zip(kind.tolist(), index.tolist(), a.tolist(), b.tolist())
    ]
    patches = []
    for group in (surface.biquadratic, surface.bicubic):
        degree = group.shape[1] - 1
        for points in group[..., :3].tolist():
            patches.append({"kind": KIND_BY_DEGREE[degree], "degree": [degree, degree], "points": points})
    for patch, source in zip(patches, sources):
        patch["source"] = source
    o = surface.options
    return {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "c1surf_version": __version__,
        "options": {"blend": o.blend, "alpha": o.alpha, "beta": o.beta, "tangent_rule": o.tangent_rule},
        "input": {"path": input_path, "vertices": int(surface.n_input_vertices), "faces": int(surface.n_input_faces)},
        "counts": {"biquadratic": int(len(surface.biquadratic)), "bicubic": int(len(surface.bicubic))},
        "patches": patches,
    }


def write_patches_json(path, surface, input_path: str | None = None) -> None:
    """Write ``surface``'s patches to ``path`` as c1surf-patches JSON."""
    with open(path, "w", encoding="utf-8") as f:
        json.dump(surface_patch_document(surface, input_path), f, separators=(",", ":"))
        f.write("\n")


def read_patches_json(path) -> list[np.ndarray]:
    """Read a c1surf-patches JSON file.

    Returns
    -------
    list of (p, du+1, dv+1, 3) float arrays, one per distinct degree, in file order of first appearance
    """
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except FileNotFoundError:
        raise MeshInputError(str(path), "no such file") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise MeshInputError(str(path), f"not a JSON patch file ({e})", getattr(e, "lineno", None)) from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT_NAME:
        raise MeshInputError(str(path), f'not a c1surf patch file (missing "format": "{FORMAT_NAME}")')
    if doc.get("version") != FORMAT_VERSION:
        raise MeshInputError(str(path), f"patch file version {doc.get('version')} is not supported (this c1surf reads version {FORMAT_VERSION})")
    groups: dict[tuple, list] = {}
    for k, patch in enumerate(doc.get("patches", [])):
        try:
            du, dv = (int(x) for x in patch["degree"])
            points = np.asarray(patch["points"], dtype=np.float64)
        except (KeyError, TypeError, ValueError) as e:
            raise MeshInputError(str(path), f"patch {k} is malformed ({e})") from None
        if points.shape != (du + 1, dv + 1, 3) or not np.all(np.isfinite(points)):
            raise MeshInputError(str(path), f"patch {k}: points must be finite with shape ({du + 1}, {dv + 1}, 3), got {points.shape}")
        groups.setdefault((du, dv), []).append(points)
    return [np.stack(v) for v in groups.values()]
