"""Which faces of a B-rep make one shell, whether it is closed, and which way it faces: for STEP and IGES alike.

A closed component becomes a solid; its shell must face outwards, which the
sign of the volume its patches enclose tells (1/3 of the integral of
(x - o) . (x_u x x_v), negative when the normals point in: an inside-out input).
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ....evaluation.measure import gauss_rule, patch_frames
from ....evaluation.patch_set import PatchSet
from .topology import FACE_PIECE, BRepTopology

__all__ = ["face_components", "closed_components", "patch_faces", "signed_volumes"]


def face_components(topology: BRepTopology) -> np.ndarray:
    """(F,) int64: the connected component of each face (faces joined through the edges they share), numbered
    in order of their first face, so the shells follow the faces."""
    face_of = np.repeat(np.arange(topology.n_faces), np.diff(topology.loop_start))
    incidence = coo_matrix((np.ones(face_of.size), (face_of, topology.loop_edge)),
                           shape=(topology.n_faces, topology.n_edges)).tocsr()
    _, labels = connected_components(incidence @ incidence.T, directed=False)
    _, first, renumbered = np.unique(labels, return_index=True, return_inverse=True)
    rank = np.empty(first.size, np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(first.size)
    return rank[renumbered.ravel()]


def closed_components(topology: BRepTopology, component: np.ndarray) -> np.ndarray:
    """(C,) bool: the components whose every edge is used twice (they bound a solid)."""
    closed = np.ones(int(component.max(initial=-1)) + 1, dtype=bool)
    face_of = np.repeat(np.arange(topology.n_faces), np.diff(topology.loop_start))
    closed[component[face_of[topology.edge_uses[topology.loop_edge] != 2]]] = False
    return closed


def patch_faces(patch_set: PatchSet, topology: BRepTopology) -> np.ndarray:
    """(P,) int64: the face each patch lies in (a merged piece's patches lie in the piece's face)."""
    first = np.cumsum([0] + [len(g) for g in patch_set.groups])
    biquadratic = [np.arange(a, a + len(g)) for a, g in zip(first, patch_set.groups) if g.shape[1:3] == (3, 3)]
    number = np.concatenate(biquadratic) if biquadratic else np.zeros(0, np.int64)
    face = np.full(patch_set.n_patches, -1, dtype=np.int64)
    for f in np.flatnonzero(topology.face_kind == FACE_PIECE).tolist():
        face[number[np.asarray(patch_set.merged[topology.face_index[f]].patches).ravel()]] = f
    single = np.flatnonzero(topology.face_kind != FACE_PIECE)
    face[topology.face_index[single]] = single
    return face


def signed_volumes(patch_set: PatchSet, topology: BRepTopology, component: np.ndarray) -> np.ndarray:
    """(C,) float: the volume each component's patches enclose, negative where their normals point in.

    Gauss-Legendre rules of ceil(3 d / 2) points per direction are exact for
    polynomial patches (the density has degree 3 d - 1); rational ones are
    integrated to the rule's accuracy, which decides the sign all the same.
    A merged piece's patches are integrated in its place (they are the same surface).
    """
    component_of_patch = component[patch_faces(patch_set, topology)]
    n_components = int(component.max(initial=-1)) + 1
    nets = [np.asarray(g, np.float64)[..., :3] for g in patch_set.groups]
    flat = np.concatenate([n.reshape(-1, 3) for n in nets] + [np.zeros((0, 3))])
    origin = 0.5 * (flat.min(axis=0) + flat.max(axis=0)) if len(flat) else np.zeros(3)
    volume = np.zeros(n_components)
    first = 0
    for k, g in enumerate(nets):
        u, w = gauss_rule((3 * (g.shape[1] - 1) + 1) // 2)
        for a in range(0, len(g), 1 << 14):  # chunks of patches: bounded memory
            weights = None if patch_set.weights is None else np.asarray(patch_set.weights[k][a: a + (1 << 14)])
            x, xu, xv = patch_frames(g[a: a + (1 << 14)], weights, u, u)
            flux = np.einsum("pabi,pabi->pab", x - origin, np.cross(xu, xv))
            per_patch = np.einsum("pab,a,b->p", flux, w, w) / 3.0
            volume += np.bincount(component_of_patch[first + a: first + a + len(per_patch)], per_patch,
                                  minlength=n_components)
        first += len(g)
    return volume
