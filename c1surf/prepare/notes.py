"""The ``c1surf: note:`` lines of a prepared input: what c1surf changed or ignored to make the input usable.

Text only (the command line prints them; the Python API returns them in ``api.LoadReport.notes``).
"""
from __future__ import annotations

import numpy as np

from ..construction.features import INFINITELY_SHARP

__all__ = ["repair_notes", "refinement_notes", "file_notes", "crease_notes", "seam_notes", "dissolve_notes", "weld_notes", "input_notes"]


def file_notes(mesh_file) -> list[str]:
    """Notes on what reading ``mesh_file`` ignored (``MeshFile.reader_notes``: OBJ ``l``/``p`` records, ...)."""
    return list(getattr(mesh_file, "reader_notes", None) or [])


def repair_notes(surface, mesh_file, data=None) -> list[str]:
    """One-line notes on what c1surf changed or ignored to make the input usable (the sharp features first).

    ``data``: the ``prepare.extension_data.SurfaceData`` the surface was built from (its
    ``feature_notes`` say which tags were honoured and which not), or None.
    """
    r = getattr(surface, "repairs", {}) or {}
    notes = list(getattr(data, "feature_notes", [])) + crease_notes(surface) + file_notes(mesh_file)
    if getattr(mesh_file, "collapsed_corners", 0):
        notes.append(f"dropped {mesh_file.collapsed_corners} repeated corners (zero-length edges such as 'f a b c c')")
    notes += weld_notes(getattr(mesh_file, "weld", None)) + dissolve_notes(mesh_file)
    if r.get("flipped_faces"):
        notes.append(f"flipped {r['flipped_faces']} faces to orient each connected component consistently")
    if r.get("non_orientable"):
        notes.append("the surface is not orientable: built on its orientation double cover; normals flip across a seam "
                     "(use `c1surf check --unoriented`)")
    if r.get("split_vertices"):
        notes.append(f"split {r['split_vertices']} pinched vertices into one vertex per fan of faces")
    # welding leaves the merged vertices unused: only the file's own unused vertices are news
    unused = (r.get("unused_vertices", 0) - getattr(getattr(mesh_file, "weld", None), "welded_vertices", 0)
              - len(getattr(mesh_file, "dissolved_vertices", ())))
    if unused > 0:
        notes.append(f"ignored {unused} vertices used by no face")
    if r.get("boundary_edges"):
        notes.append(f"open mesh: {r['boundary_edges']} boundary edges, closed for the construction by a ghost layer")
    return notes + refinement_notes(surface)


def refinement_notes(surface) -> list[str]:
    """With ``--refinements auto`` and the paper's two Doo-Sabin steps taken: why one step is not enough
    (``SurfaceTopology.two_steps_why``, set by "auto" only). ``surface``: a Surface or its SurfaceTopology."""
    topology = getattr(surface, "topology", surface)
    why = getattr(topology, "two_steps_why", None)
    if not why:
        return []
    return [f"--refinements auto: two Doo-Sabin steps (16 patches a quad), one is not enough here: {why} "
            "(docs/sharp-features.md, \"One Doo-Sabin step\")"]


def crease_notes(surface) -> list[str]:
    """With ``--exact-creases``: how many infinitely sharp crease edges became C0 seams, and which did not, why."""
    options = getattr(surface, "options", None)
    return seam_notes(getattr(options, "exact_creases", False), getattr(surface, "features", None),
                      getattr(surface, "topology", None))


def seam_notes(exact_creases: bool, features, topology) -> list[str]:
    """``crease_notes`` of a surface's parts: the option, its SharpFeatures and its SurfaceTopology."""
    if not exact_creases or features is None or topology is None:
        return []
    # by the vertices' identities (copies of one vertex in non-manifold sheets are one); an edge tagged twice counts once
    name = (lambda v: v) if features.vertex_identity is None else (lambda v: features.vertex_identity[v])
    sharp = int(np.unique(np.sort(name(features.crease_edges[features.crease_sharpness >= INFINITELY_SHARP]), axis=1),
                          axis=0).shape[0])
    corners = np.unique(name(features.corner_vertices[features.corner_sharpness >= INFINITELY_SHARP]))
    if sharp == 0 and corners.size == 0:
        return []
    sheets = topology.crease_sheets
    cut = 0 if sheets is None else len(sheets.cut_edges)
    kept = sharp - cut
    notes = [f"C0 creases: {cut} of {sharp} infinitely sharp crease edges are C0 seams"] if cut else []
    lone = np.setdiff1d(corners, np.zeros(0, dtype=np.int64) if sheets is None else sheets.cut_edges.ravel())
    if lone.size:
        notes.append(f"{lone.size} infinitely sharp corners are not on a C0 seam and stay the sharpest G1 corner "
                     f"(vertices {', '.join(map(str, lone[:8].tolist()))}{' ...' if lone.size > 8 else ''}, 0-based)")
    ends = 0 if sheets is None or sheets.dart_vertex is None else sheets.dart_vertex.size
    if ends:
        notes.append(f"{ends} C0 crease lines end inside the surface (darts): C0 up to the dart, where the crease "
                     "fades out into a G1 point (docs/sharp-features.md, \"Darts\")")
    darts = 0 if sheets is None or sheets.dart_edges is None else len(sheets.dart_edges)
    if darts:
        notes.append(f"{darts} infinitely sharp crease edges are crease lines of one edge that end inside the surface "
                     "at both ends: they stay the sharpest G1 crease, which fades out at both ends as in OpenSubdiv")
        kept -= darts
    if kept:
        named = [] if sheets is None else sheets.inexact_vertices.tolist()
        at = f" (at vertices {', '.join(map(str, named[:8]))}{' ...' if len(named) > 8 else ''}, 0-based)" if named else ""
        notes.append(f"{kept} infinitely sharp crease edges stay the sharpest G1 crease: their crease lines have a "
                     f"vertex where a C0 seam is not exact yet{at}: a crease end inside the surface, the mesh boundary, "
                     "three or more faces on one side, or a corner with a sector of several faces (docs/sharp-features.md)")
    return notes


def dissolve_notes(mesh_file) -> list[str]:
    """The notes on repeated faces dropped, crease sectors merged (``mesh.creases.sectors``) and interior valence-2
    vertices dissolved (``mesh.valence_two``)."""
    notes = []
    if getattr(mesh_file, "repeated_faces", 0):
        notes.append(f"dropped {mesh_file.repeated_faces} faces that repeat an earlier face (the same cycle again, or "
                     "its reversal where the two make a closed two-sided card)")
    sheets = getattr(mesh_file, "non_manifold_edges", None)
    if sheets is not None:
        shown = ", ".join(f"{a}-{b}" for a, b in sheets[:6].tolist()) + (", ..." if len(sheets) > 6 else "")
        seams = getattr(mesh_file, "non_manifold_seams", len(sheets))
        touching = f"; {len(sheets) - seams} only touch there (every sheet holds them in two faces)" if seams < len(sheets) else ""
        notes.append(f"C0 creases: cut {len(sheets)} edges in more than two faces (vertices {shown}, 0-based) into "
                     f"manifold sheets: {seams} are a C0 crease the sheets meet along{touching} (docs/sharp-features.md)")
    merge = getattr(mesh_file, "sector_merge", None)
    if merge is not None:
        faces, polygons, at, lost = merge
        shown = ", ".join(str(int(v)) for v in at[:8]) + (", ..." if len(at) > 8 else "")
        notes.append(f"C0 creases: merged {faces} faces into {polygons} polygons around {len(at)} crease vertices "
                     f"(vertices {shown}, 0-based), so that every crease sector has at most two faces (one at a "
                     "corner), which the exact C0 crease needs (docs/sharp-features.md)")
        if len(lost):
            edges = ", ".join(f"{a}-{b}" for a, b in lost[:6].tolist()) + (", ..." if len(lost) > 6 else "")
            notes.append(f"C0 creases: {len(lost)} crease edges alone on their line, with both ends inside the surface, "
                         f"were merged away inside a corner's sector (edges {edges}, 0-based): not used")
    dissolved = getattr(mesh_file, "dissolved_vertices", ())
    if not len(dissolved):
        return notes
    base = 1 if str(mesh_file.path).lower().endswith(".obj") else 0
    shown = ", ".join(str(int(v) + base) for v in dissolved[:8]) + (", ..." if len(dissolved) > 8 else "")
    which = "as in the OBJ file, from 1" if base else "from 0"
    return notes + [f"dissolved {len(dissolved)} interior vertices of valence 2 into the edges they split (vertices "
                    f"{shown}, {which}): a 2-sided cell has no A3 filling; their faces lost that corner"]


def weld_notes(weld) -> list[str]:
    """The notes of a ``prepare.mesh_edits.WeldReport`` (or None: the mesh was not welded)."""
    if weld is None:
        return []
    where = "at the same position" if weld.tolerance == 0 else f"within {weld.tolerance:g} of the bounding-box diagonal"
    notes = []
    if weld.welded_vertices:
        notes.append(f"welded {weld.welded_vertices} vertices {where} into the vertex they coincide with "
                     "(--no-weld keeps them)")
    if weld.unwelded_vertices:
        notes.append(f"kept {weld.unwelded_vertices} positions as several vertices: welding them would put an edge "
                     "in more than two faces")
    if weld.dropped_faces:
        notes.append(f"dropped {weld.dropped_faces} faces that welding left with fewer than 3 corners")
    return notes


def input_notes(mesh_file, data=None) -> list[str]:
    """The notes of a prepared input without a built surface: the sharp features', the reader's, the welding's and
    the other edits' (``c1surf check``'s order)."""
    return list(getattr(data, "feature_notes", [])) + file_notes(mesh_file) + weld_notes(getattr(mesh_file, "weld", None)) \
        + dissolve_notes(mesh_file)
