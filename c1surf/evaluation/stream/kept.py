"""What a streamed conversion keeps of a built Surface: the patches by blocks and a few integers, not the build.

A ``construction.surface.Surface`` holds its topology (the half-edge meshes of
both refinement steps, the frames), its stages (the Doo-Sabin steps' sparse
matrices and tables) and the refined points. Measured on a 600 x 300 quad
torus (2.88M patches): 633 MB. Writing its tessellation and patch files by
blocks needs only the patches stage's layouts and the refined points
(``PatchSource``, 165 MB), the patch adjacency (100 MB, made from the refined
mesh's faces and twins and the frames) and, for patch files, where every patch
comes from (``surface_source_ids``).

``StreamedSurface`` takes those references from the Surface. Once its
caller drops the Surface, the stages go; when the adjacency is first asked for,
the sources (if kept) and the adjacency are made from the topology, which then
goes too: at that point only what the rest of the conversion reads is held.
"""
from __future__ import annotations

import numpy as np

from ...construction.topology import RELEASED_TWIN_HALFEDGES
from ...memory import return_freed_memory
from ..adjacency import (PatchAdjacency, adjacency_from_corner_labels, adjacency_from_labels, corner_labels,
                         side_labels)
from ..patch_set import PatchStream, surface_header, surface_source_ids

__all__ = ["StreamedSurface"]


class StreamedSurface:
    """The parts of a polynomial Surface a streamed conversion reads; the rest of the build is let go.

    Parameters
    ----------
    surface : ``construction.surface.Surface``, polynomial (built with ``lazy_patches``: its patch arrays
        are never made); the caller should drop its own reference after this, so the build's memory goes
    sources : bool, keep where every patch comes from (patch files write it)
    sides : bool, the adjacency numbers the patch sides too; False: its corners only (``adjacency.edges`` None),
        enough for a tessellation at resolution 2 without patch files, and the sides' labels are never made

    Attributes
    ----------
    source : ``construction.patch_blocks.PatchSource``, the coefficients of any patches by blocks
    counts : (Nq, Nc) int; n_patches : int
    options : SurfaceOptions; n_input_vertices, n_input_faces : int (the patch file header)
    crease_sides : (k, 2) int, the two sides of each C0 crease piece (``Surface.crease_sides``; the header's)
    adjacency : PatchAdjacency of the patches (biquadratic first), made on first use
    """

    def __init__(self, surface, sources: bool = False, sides: bool = True):
        if surface.rational:
            raise ValueError("a rational surface is converted in memory")
        self.source = surface.patch_source()
        self.counts = tuple(int(count) for count in self.source.counts)
        self.options = surface.options
        self.n_input_vertices, self.n_input_faces = surface.n_input_vertices, surface.n_input_faces
        self.crease_sides = surface.crease_sides  # (k, 2): the C0 crease pieces' sides (patch files' header)
        self._topology = surface.topology  # until the adjacency (and the sources) are made from it
        self._keep_sources = bool(sources)
        self._sides = bool(sides) or bool(sources)
        self._sources = None
        self._adjacency = None

    @property
    def n_patches(self) -> int:
        return int(sum(self.counts))

    @property
    def adjacency(self) -> PatchAdjacency:
        """The patch adjacency (``adjacency.patch_adjacency``), made on first use: then the topology is let go.

        The sources, if kept, are made first (they read the topology); then the adjacency from the refined
        faces and twins and the frames alone (``adjacency.patch_adjacency`` in its three steps), with the rest
        of the topology already released, and each of those arrays let go once read.
        """
        if self._adjacency is None:
            topology, self._topology = self._topology, None
            # memory given back between the steps of a large build only, as the build does: on the 180,000-quad
            # torus (11.5 M refined half-edges) these calls cost 0.15-0.2 s and left the peak as it was (482 vs 485 MB)
            large = topology.refined.n_halfedges >= RELEASED_TWIN_HALFEDGES
            trim = return_freed_memory if large else (lambda: None)
            trim()  # the stages, if the caller dropped the Surface
            if self._keep_sources:
                self._sources = surface_source_ids(topology, compact=True)
            # twin only for the sides (the build may have let it go: ``topology.build_topology``; made again here)
            face, twin = topology.refined.face, topology.refined.twin if self._sides else None
            frames = (topology.quad_frames, topology.cubic_frames)  # as parts: no (P, 4) concatenation
            del topology  # the refined meshes of both steps, the coarse mesh, ...: everything but these arrays
            self.source.keep_slot_arrays()  # of the refined mesh, only its origin and next from here on
            trim()
            corners = corner_labels(face, frames)
            del face
            trim()
            if not self._sides:
                del frames
                self._adjacency = adjacency_from_corner_labels(corners)
                trim()  # the renumbering's tables
                return self._adjacency
            edges, forward = side_labels(twin, frames)
            del twin, frames
            trim()
            self._adjacency = adjacency_from_labels(corners, edges, forward)
            trim()  # the renumbering's tables
        return self._adjacency

    def whole_patches(self) -> list:
        """[biquadratic (Nq, 3, 3, d), bicubic (Nc, 4, 4, d)] float, made now: ``Surface.biquadratic`` /
        ``bicubic`` bit for bit (``PatchSource.arrays``), for a fallback that needs the whole surface."""
        return list(self.source.arrays())

    def patch_stream(self, input_path: str | None = None) -> PatchStream:
        """The ``PatchStream`` ``evaluation.patch_set.surface_patch_stream`` gives for the Surface (made with
        ``sources=True``): the same header, sources, adjacency and coefficients."""
        adjacency = self.adjacency
        if self._sources is None:
            raise ValueError("internal: this StreamedSurface was made without the patches' sources")
        kind, source = self._sources
        header = surface_header(self, input_path, adjacency, self.counts)
        return PatchStream(self.source, adjacency, kind, source, header)
