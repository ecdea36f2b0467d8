"""From what a mesh file says about sharp features to the construction's ``SharpFeatures``, and the notes.

Three sources, merged (an edge or corner named twice keeps its largest sharpness):

- the file's own tags (``MeshFile.tags``: OBJ ``t`` lines, PLY edge creases and vertex corners);
- a JSON sidecar (``--creases FILE``, read by ``io.meshes.sidecars.read_creases_file``) for files written
  without tags::

      {"creases": [[0, 1, 10], [4, 5, 6, 2.5]],   # a chain of vertices, then its sharpness
       "corners": [[7, 10]],                      # vertex, sharpness
       "holes": [3, 12]}                          # faces (all indices from 0)

- ``--crease-angle DEG``: every edge whose faces meet at a dihedral angle above
  DEG is infinitely sharp (``mesh.feature_edges``).

Every tag is either honoured or named in a note with what c1surf does instead.
"""
from __future__ import annotations

import numpy as np

from ..construction.features import INFINITELY_SHARP, SharpFeatures
from ..mesh.creases.tags import SharpTags
from ..mesh.feature_edges import feature_edges

__all__ = ["sharp_features", "features_from_tags", "feature_notes"]

OTHER_TAGS = {
    "creasemethod": "c1surf's own crease rule is used (stencils.creases)",
    "facevaryinginterpolateboundary": "c1surf carries no face-varying data",
    "facevaryingpropagatecorners": "c1surf carries no face-varying data",
    "smoothtriangles": "triangles follow A3 (or --triangles parametric)",
    "vertexedit": "hierarchical edits are not supported",
    "edgeedit": "hierarchical edits are not supported",
}


def sharp_features(mesh, sidecar: SharpFeatures | None = None, crease_angle: float | None = None,
                   ignore_tags: bool = False, exact_creases: bool = False):
    """The creases, corners and holes of ``mesh`` for the construction, and the notes about them.

    Parameters
    ----------
    mesh : a MeshFile (``io.meshes.mesh_file``): path, points, faces and ``tags`` (``mesh.creases.tags.SharpTags``)
    sidecar : SharpFeatures of a ``--creases`` JSON sidecar (``io.meshes.sidecars.read_creases_file``), or None
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
    features = SharpFeatures() if ignore_tags else features_from_tags(tags)
    if sidecar is not None:
        features = features.merged(sidecar)
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


def features_from_tags(tags: SharpTags) -> SharpFeatures:
    """The construction's SharpFeatures of the creases, corners and holes of ``tags``."""
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
