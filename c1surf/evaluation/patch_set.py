"""A patch file in memory, whatever its format (JSON, NPZ, IGES).

``PatchSet`` holds the patches in file order (as runs of one degree), where
each comes from in the input mesh, the patch adjacency (shared corners and
sides, ``evaluation.adjacency``) and the header (format, versions, options, input).
``surface_patch_set`` makes one from a ``Surface``; the JSON and NPZ writers
write it, their readers give it back, and ``c1surf tessellate`` turns it into
the same mesh ``convert`` writes. See docs/patch-format.md.

``PatchStream`` is the same content for a writer by blocks (the streamed
conversion): the integers (adjacency, sources, header) whole, the
coefficients by blocks from the surface's ``patch_source``, never all held.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .. import __version__
from .adjacency import PatchAdjacency, adjacency_from_geometry, neighbour_rows, patch_adjacency

FORMAT_NAME = "c1surf-patches"
FORMAT_VERSION = 1
KIND_BY_DEGREE = {2: "biquadratic", 3: "bicubic"}
SOURCE_KINDS = ("face", "edge", "vertex")  # indexed by construction.refine.doo_sabin FACE_FROM_FACE/EDGE/VERTEX


@dataclass
class PatchSet:
    """Bezier patches with their bookkeeping.

    groups : list of (p_k, du+1, dv+1, 3) float, runs of consecutive patches of one
        degree, in file order (c1surf writes biquadratic first, then bicubic)
    adjacency : PatchAdjacency or None (IGES files carry none)
    source_kind : (P,) str array ("face", "edge", "vertex") or None
    source : (P, 2) int64 or None: (face, -1), (vertex, -1) or the edge's (a, b)
    header : dict, everything of the file but the patches (format, version,
        c1surf_version, options, input, counts), as far as the file says
    weights : None (polynomial patches) or a list parallel to ``groups`` of
        (p_k, du+1, dv+1) float: rational patches sum(w P B) / sum(w B) (A2a)
    merged : list of ``evaluation.merge.MergedPiece``, B-spline surfaces that each
        stand for a rectangle of the biquadratic patches (``convert --merge``); the
        patches themselves stay in ``groups``. Empty when there are none.
    """

    groups: list
    adjacency: PatchAdjacency | None = None
    source_kind: np.ndarray | None = None
    source: np.ndarray | None = None
    header: dict = field(default_factory=dict)
    weights: list | None = None
    merged: list = field(default_factory=list)

    @property
    def n_patches(self) -> int:
        return int(sum(len(g) for g in self.groups))

    @property
    def crease_sides(self) -> np.ndarray | None:
        """(k, 2) int: curve ids ``4 * patch + side`` of the two sides of every C0 crease piece (the header's
        "crease_sides"), or None when the file names none."""
        rows = self.header.get("crease_sides")
        if rows is None:
            return None
        rows = np.asarray(rows, dtype=np.int64).reshape(-1, 4)
        return np.stack([4 * rows[:, 0] + rows[:, 1], 4 * rows[:, 2] + rows[:, 3]], axis=1)

    def degrees(self) -> list:
        """(du, dv) of every patch, in file order."""
        out = []
        for g in self.groups:
            out.extend([(g.shape[1] - 1, g.shape[2] - 1)] * len(g))
        return out

    def by_degree(self) -> list:
        """Patches grouped by degree (first appearance order): the old ``read_patches_json`` result."""
        merged: dict = {}
        for g in self.groups:
            merged.setdefault(g.shape[1:3], []).append(g)
        return [np.concatenate(v) for v in merged.values()]

    def welding(self, tolerance: float = 1e-9) -> PatchAdjacency:
        """The stored adjacency, or one found from the geometry (``adjacency_from_geometry``)."""
        if self.adjacency is not None:
            return self.adjacency
        return adjacency_from_geometry(self.groups, tolerance, self.weights)

    def source_dicts(self) -> list:
        """JSON form of the sources: {"face": f} | {"vertex": v} | {"edge": [a, b]}."""
        if self.source_kind is None:
            return [None] * self.n_patches
        return source_dicts(self.source_kind, self.source)


def source_dicts(source_kind: np.ndarray, source: np.ndarray) -> list:
    """{"face": f} | {"vertex": v} | {"edge": [a, b]} of (P,) str kinds and (P, 2) int sources."""
    return [{"edge": [a, b]} if kind == "edge" else {kind: a} for kind, (a, b) in zip(source_kind.tolist(), source.tolist())]


def degree_runs(patches: list) -> list:
    """Stack a list of (du+1, dv+1, 3) arrays into runs of consecutive equal shape."""
    groups, run = [], []
    for p in patches:
        if run and p.shape != run[-1].shape:
            groups.append(np.stack(run))
            run = []
        run.append(p)
    if run:
        groups.append(np.stack(run))
    return groups


def surface_sources(surface):
    """(source_kind (P,) str array, source (P, 2) int64) of a Surface's patches."""
    kind, source = surface_source_ids(surface)
    return source_names(kind), source


def surface_source_ids(surface, compact: bool = False):
    """(kind (P,) int, an index into SOURCE_KINDS; source (P, 2) int64) of a Surface's patches.

    ``surface``: a Surface or its ``SurfaceTopology`` (``patch_sources()``). ``compact``: source as int32 when
    every input face and vertex id fits (a streamed conversion keeps it while writing; written as int64).
    The ids are written into the one (P, 2) array, with no (P, 2) or (P,) int64 temporaries.
    """
    kind, index, edge = surface.patch_sources()
    kind = np.asarray(kind)
    fits = compact and max(surface.n_input_vertices, surface.n_input_faces) < 2**31
    source = np.empty((len(index), 2), dtype=np.int32 if fits else np.int64)
    source[:, 0] = index
    source[:, 1] = -1
    is_edge = np.flatnonzero(kind == SOURCE_KINDS.index("edge"))
    source[is_edge] = np.asarray(edge)[is_edge]
    return kind, source


def source_names(kind: np.ndarray) -> np.ndarray:
    """(P,) str ("face", "edge", "vertex", dtype <U6) of (P,) int indices into SOURCE_KINDS."""
    return np.array(SOURCE_KINDS)[np.asarray(kind, dtype=np.int64)]


def surface_header(surface, input_path: str | None, adjacency: PatchAdjacency,
                   counts: tuple | None = None) -> dict:
    """Header of a Surface's patch file (everything but the patches); "crease_sides" only with C0 creases.

    ``surface`` needs ``options``, ``n_input_vertices`` and ``n_input_faces`` (a ``Surface``, or
    ``evaluation.stream.StreamedSurface``); ``counts``: (Nq, Nc), or None for the Surface's frames' counts.
    """
    if counts is None:  # the frames' counts: the patch arrays are not made for them (a streamed conversion)
        counts = (surface.quad_frames.shape[0], surface.cubic_frames.shape[0])
    header = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "c1surf_version": __version__,
        "options": dataclasses.asdict(surface.options),  # every SurfaceOptions field, by name
        "input": {"path": input_path, "vertices": int(surface.n_input_vertices), "faces": int(surface.n_input_faces)},
        "counts": {
            "biquadratic": int(counts[0]),
            "bicubic": int(counts[1]),
            "corners": adjacency.n_corners,
            "edges": adjacency.n_edges,
        },
    }
    crease = getattr(surface, "crease_sides", np.zeros((0, 2), dtype=np.int64))
    if len(crease):  # the two sides of each C0 crease piece: [patch, side, patch, side]
        header["crease_sides"] = np.stack(np.divmod(crease, 4), axis=-1).reshape(-1, 4).tolist()
    return header


def surface_patch_set(surface, input_path: str | None = None, adjacency: PatchAdjacency | None = None) -> PatchSet:
    """The PatchSet of a ``construction.surface.Surface`` (patches biquadratic first, then bicubic)."""
    if adjacency is None:
        adjacency = patch_adjacency(surface.refined, surface.frames)
    groups = [np.ascontiguousarray(g[..., :3]) for g in (surface.biquadratic, surface.bicubic) if len(g)]
    kind, source = surface_sources(surface)
    weights = getattr(surface, "patch_weights", None)  # rational surfaces (A2a)
    if weights is not None:
        weights = [np.ascontiguousarray(w) for g, w in zip((surface.biquadratic, surface.bicubic), weights) if len(g)]
    return PatchSet(groups, adjacency, kind, source, surface_header(surface, input_path, adjacency), weights)


@dataclass
class PatchStream:
    """A polynomial surface's patch file content by blocks of patches (``surface_patch_stream``).

    patches : ``construction.patch_blocks.PatchSource``, the coefficients of any patches, bit for bit the arrays
    adjacency : PatchAdjacency, as ``PatchSet.adjacency``
    source_kind : (P,) int, indices into SOURCE_KINDS; source_ids : (P, 2) int (int64, or int32 where the
        ids fit: ``integers`` gives int64 rows), as ``PatchSet.source``
    header : dict, as ``PatchSet.header``
    """

    patches: object
    adjacency: PatchAdjacency
    source_kind: np.ndarray
    source_ids: np.ndarray
    header: dict
    _partners: np.ndarray | None = None

    # the integer arrays of a patch file: (name, shape of a row, dtype), as PatchSet writers store them
    INTEGERS = (("source_kind", (), "<U6"), ("source", (2,), "<i8"), ("corners", (4,), "<i8"), ("edges", (4,), "<i8"),
                ("reversed", (4,), "|b1"), ("neighbours", (4, 2), "<i8"))

    @property
    def counts(self) -> tuple:
        """(Nq, Nc): biquadratic patches, then bicubic, in file order."""
        return tuple(self.patches.counts)

    @property
    def n_patches(self) -> int:
        return int(sum(self.counts))

    def blocks(self, kind: int, size: int):
        """Yield (first, coefficients (c, k, k, 3) float): patches first..first+c-1 of ``kind`` (0 biquadratic,
        1 bicubic; ids within the kind), in order, up to ``size`` at a time; x, y, z only."""
        for a in range(0, self.counts[kind], size):
            ids = np.arange(a, min(a + size, self.counts[kind]))
            yield a, np.ascontiguousarray(self.patches.coefficients(kind, ids)[0][..., :3])

    def integers(self, name: str, a: int, z: int) -> np.ndarray:
        """Rows a..z-1 (global patch ids) of the integer array ``name`` of ``INTEGERS``, of its shape and dtype:
        the rows of ``PatchSet.source_kind``, ``source``, the adjacency's corners, edges, reversed, neighbours()."""
        if name == "source_kind":
            return source_names(self.source_kind[a:z])
        if name == "source":
            return self.source_ids[a:z].astype(np.int64)
        if name == "neighbours":
            if self._partners is None:
                self._partners = self.adjacency.partners()  # (4 P,) int32: a quarter of neighbours()
            return neighbour_rows(self._partners[4 * a : 4 * z])
        return getattr(self.adjacency, name)[a:z].astype(bool if name == "reversed" else np.int64)

    def source_dicts(self, a: int, z: int) -> list:
        """JSON form of the sources of patches a..z-1 (global ids), as ``PatchSet.source_dicts``."""
        return source_dicts(self.integers("source_kind", a, z), self.source_ids[a:z])


def surface_patch_stream(surface, input_path: str | None = None, adjacency: PatchAdjacency | None = None) -> PatchStream:
    """The PatchStream of a polynomial ``construction.surface.Surface`` (its patch arrays are not made).

    Writers by blocks write from it the bytes they write from ``surface_patch_set`` (the same header,
    sources, adjacency and coefficients). Raises ValueError for a rational surface (weights are written whole).
    """
    if surface.rational:
        raise ValueError("a rational surface's patches are written whole")
    if adjacency is None:
        adjacency = patch_adjacency(surface.refined, surface.frames)
    kind, source = surface_source_ids(surface)
    return PatchStream(surface.patch_source(), adjacency, kind, source, surface_header(surface, input_path, adjacency))


__all__ = ["PatchSet", "PatchStream", "surface_patch_set", "surface_patch_stream", "degree_runs", "FORMAT_NAME",
           "FORMAT_VERSION", "KIND_BY_DEGREE", "SOURCE_KINDS"]
