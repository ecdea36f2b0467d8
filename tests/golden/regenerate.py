"""Golden reference outputs for the sample meshes: build, compare, regenerate.

    python tests/golden/regenerate.py      # or: make golden

writes, for every mesh in GOLDEN_MESHES (sample_meshes/, default options):

    tests/golden/<name>.json       the patch file, exactly as `convert --patches` writes it
    tests/golden/<name>.r3.json    (TESSELLATED only) the welded tessellation at
                                   resolution 3: points, normals, triangles, triangle_patch

tests/test_golden.py compares fresh results with these files. Structure
(counts, sources, adjacency, triangles) must match exactly; coordinates may
move by at most TOLERANCE times the bounding-box diagonal (floating-point
noise is ~1e-16; real changes are far above 1e-12), and a failure names the
patch and coefficient that moved and by how much.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = Path(__file__).resolve().parent
if str(ROOT) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(ROOT))

from c1surf.evaluation.adjacency import patch_adjacency  # noqa: E402
from c1surf.construction.surface import Surface, SurfaceOptions  # noqa: E402
from c1surf.evaluation.tessellate import tessellate_patches  # noqa: E402
from c1surf.io.meshes.obj import read_obj  # noqa: E402
from c1surf.io.patches.json_patches import surface_patch_document  # noqa: E402

# torus.obj (1536 patches, 1 MB of JSON) is left out to keep the files small;
# double_torus covers higher genus.
GOLDEN_MESHES = [
    "cube", "tetrahedron", "octahedron", "icosahedron", "dodecahedron", "triangular_prism",
    "hexagonal_prism", "twisted", "double_torus", "high_valence", "hexagon_six_valent", "hexagon_all_six_valent",
]
TESSELLATED = ["cube", "tetrahedron", "triangular_prism", "twisted"]
RESOLUTION = 3
TOLERANCE = 1e-12  # relative to the bounding-box diagonal
IGNORED_HEADER = ("c1surf_version",)  # may change without the surface changing


def build(name: str):
    """(surface, patch document, tessellation document) of sample_meshes/<name>.obj, default options."""
    relative = f"sample_meshes/{name}.obj"
    mesh = read_obj(ROOT / relative)
    surface = Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions())
    adjacency = patch_adjacency(surface.refined, surface.frames)
    doc = surface_patch_document(surface, relative, adjacency)
    tess = tessellate_patches([surface.biquadratic, surface.bicubic], adjacency, RESOLUTION)
    tess_doc = {
        "mesh": relative,
        "resolution": RESOLUTION,
        "points": tess.points[:, :3].tolist(),
        "normals": tess.normals.tolist(),
        "triangles": tess.triangles.tolist(),
        "triangle_patch": tess.triangle_patch.tolist(),
    }
    return surface, doc, tess_doc


def dump(doc: dict) -> str:
    return json.dumps(doc, separators=(",", ":")) + "\n"


def patch_path(name: str) -> Path:
    return GOLDEN / f"{name}.json"


def tessellation_path(name: str) -> Path:
    return GOLDEN / f"{name}.r{RESOLUTION}.json"


def _describe(doc: dict, k: int) -> str:
    patch = doc["patches"][k]
    source = patch.get("source", {})
    where = ", ".join(f"{key} {value}" for key, value in source.items())
    return f"patch {k} ({patch['kind']}{', source ' + where if where else ''})"


def compare_patch_documents(new: dict, old: dict, tolerance: float = TOLERANCE, show: int = 8) -> list[str]:
    """Differences between two patch documents, as readable lines (empty: the same up to noise)."""
    problems = []
    for key in sorted(set(new) | set(old)):
        if key in ("patches", *IGNORED_HEADER):
            continue
        a, b = new.get(key), old.get(key)
        if key == "options" and isinstance(a, dict) and isinstance(b, dict):
            # an option added since (with its default) does not change the surface
            a = {k: v for k, v in a.items() if k in b}
        if a != b:
            problems.append(f"header {key!r}: {b!r} -> {a!r}")
    a, b = new["patches"], old["patches"]
    if len(a) != len(b):
        return problems + [f"number of patches: {len(b)} -> {len(a)}"]
    for field in ("kind", "degree", "source", "corners", "edges", "reversed", "neighbours"):
        changed = [k for k in range(len(a)) if a[k].get(field) != b[k].get(field)]
        for k in changed[:show]:
            problems.append(f"{_describe(old, k)}: {field} {b[k].get(field)!r} -> {a[k].get(field)!r}")
        if len(changed) > show:
            problems.append(f"... {field} differs in {len(changed)} patches")
    if problems:
        return problems
    old_pts = [np.asarray(p["points"], dtype=np.float64) for p in b]
    new_pts = [np.asarray(p["points"], dtype=np.float64) for p in a]
    flat = np.concatenate([p.reshape(-1, 3) for p in old_pts])
    diagonal = float(np.linalg.norm(flat.max(axis=0) - flat.min(axis=0))) or 1.0
    moved = []  # (relative move, patch, index, coordinate, old, new)
    for k, (p, q) in enumerate(zip(new_pts, old_pts)):
        d = np.abs(p - q) / diagonal
        for idx in zip(*np.nonzero(d > tolerance)):
            moved.append((float(d[idx]), k, idx[:2], "xyz"[idx[2]], float(q[idx]), float(p[idx])))
    moved.sort(key=lambda m: -m[0])
    for rel, k, (i, j), axis, before, after in moved[:show]:
        problems.append(f"{_describe(old, k)}: points[{i}][{j}].{axis} {before!r} -> {after!r} "
                        f"(moved {abs(after - before):.3e}, {rel:.3e} of the bounding-box diagonal > {tolerance:g})")
    if len(moved) > show:
        problems.append(f"... {len(moved)} coefficients moved by more than {tolerance:g} of the bounding-box diagonal "
                        f"in {len({m[1] for m in moved})} patches")
    return problems


def max_relative_change(new: dict, old: dict) -> float:
    """Largest coefficient move between two patch documents of the same structure, relative to the diagonal."""
    old_pts = np.concatenate([np.asarray(p["points"], dtype=np.float64).reshape(-1, 3) for p in old["patches"]])
    new_pts = np.concatenate([np.asarray(p["points"], dtype=np.float64).reshape(-1, 3) for p in new["patches"]])
    diagonal = float(np.linalg.norm(old_pts.max(axis=0) - old_pts.min(axis=0))) or 1.0
    return float(np.abs(new_pts - old_pts).max() / diagonal)


def compare_tessellations(new: dict, old: dict, tolerance: float = TOLERANCE, show: int = 8) -> list[str]:
    """Differences between two tessellation documents, as readable lines."""
    problems = []
    for key in ("mesh", "resolution"):
        if new[key] != old[key]:
            problems.append(f"{key}: {old[key]!r} -> {new[key]!r}")
    for key in ("triangles", "triangle_patch"):
        if new[key] != old[key]:
            problems.append(f"{key} changed ({len(old[key])} -> {len(new[key])} entries)")
    if len(new["points"]) != len(old["points"]):
        problems.append(f"number of vertices: {len(old['points'])} -> {len(new['points'])}")
    if problems:
        return problems
    p, q = np.asarray(new["points"]), np.asarray(old["points"])
    diagonal = float(np.linalg.norm(q.max(axis=0) - q.min(axis=0))) or 1.0
    for key, scale in (("points", diagonal), ("normals", 1.0)):
        a, b = np.asarray(new[key]), np.asarray(old[key])
        d = np.abs(a - b).max(axis=1) / scale
        bad = np.flatnonzero(d > tolerance)
        for v in bad[np.argsort(-d[bad])][:show]:
            problems.append(f"vertex {v} {key}: {b[v].tolist()} -> {a[v].tolist()} ({d[v]:.3e} relative > {tolerance:g})")
        if bad.size > show:
            problems.append(f"... {bad.size} vertices' {key} moved")
    return problems


def main() -> int:
    total = 0
    for name in GOLDEN_MESHES:
        _, doc, tess_doc = build(name)
        outputs = [(patch_path(name), doc)] + ([(tessellation_path(name), tess_doc)] if name in TESSELLATED else [])
        for path, content in outputs:
            text = dump(content)
            path.write_text(text, encoding="utf-8")
            total += len(text)
            print(f"wrote {path.relative_to(ROOT)} ({len(text) / 1024:.0f} KiB)")
    print(f"total {total / 2**20:.2f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
