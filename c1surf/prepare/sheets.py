"""Exact C0 creases need manifold sheets and small crease sectors: the non-manifold edges cut into sheets
(``mesh.creases.non_manifold``) and the faces of too large crease sectors merged (``mesh.creases.sectors``), with
the sharp features and per-vertex data following the vertex copies and merged faces."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..construction.features import INFINITELY_SHARP, SharpFeatures
from ..mesh.creases.non_manifold import split_non_manifold_edges
from ..mesh.halfedges import build_halfedges, mesh_edge_keys
from .extension_data import SurfaceData
from .mesh_edits import merge_sector_faces
from .renumber import faces_kept

__all__ = ["split_surface_sheets", "merge_surface_sectors"]


def split_surface_sheets(mesh, data: SurfaceData | None):
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


def _sheet_junctions(mesh, sharp: np.ndarray, split) -> np.ndarray:
    """(k,) int: vertices of the non-manifold lines that some sheet holds on three or more seam edges (its
    infinitely sharp and boundary edges, e.g. a fin folded at the line): a corner there, so a corner in
    every sheet (all sheets build one curve)."""
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


def merge_surface_sectors(mesh, data: SurfaceData | None):
    """Merge the faces of crease sectors too large for an exact C0 crease (``mesh.creases.sectors``).

    Faces with different blend ratios, hole tags or other per-face data are not merged, nor semi-sharp
    crease edges; a lone crease edge between two darts inside a corner's sector may go (its tag is dropped from
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
    lost = merged.sector_merge[3]  # lone crease edges between two darts, merged away (their own note)
    if len(lost):
        n = mesh.n_vertices
        gone = np.isin(np.minimum(*f.crease_edges.T) * n + np.maximum(*f.crease_edges.T), lost[:, 0] * n + lost[:, 1])
        f = replace(f, crease_edges=f.crease_edges[~gone], crease_sharpness=f.crease_sharpness[~gone])
        data = replace(data, features=f)
    return merged, faces_kept(data, kept)
