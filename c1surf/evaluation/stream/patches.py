"""Patches read by blocks, wherever they are held: arrays (a patch file's, memory-mapped for NPZ) or a streamed
Surface's ``PatchSource`` (computed on demand). The smoothness check and the mass properties read them through
these, a block or a set of patches at a time, so that neither holds more than the patches' own arrays (or, for a
mesh input, none of them).
"""
from __future__ import annotations

import mmap

import numpy as np


__all__ = ["ArrayPatches", "SourcePatches", "StreamedPatchSet", "patch_blocks"]

# Patches per block of the checks (bicubic: 12 MB of coefficients, and the side points and frames of a block).
BLOCK = 1 << 15


class ArrayPatches:
    """Patches held as arrays, in runs of one degree (a ``PatchSet``'s ``groups`` and ``weights``).

    groups : list of (p_k, du+1, dv+1, >= 3) float arrays (x, y, z first; memory-mapped ones stay so)
    weights : None or a list parallel to ``groups`` of (p_k, du+1, dv+1) float (rational patches, A2a)
    """

    def __init__(self, groups, weights=None):
        keep = [k for k, g in enumerate(groups) if len(g)]
        self.groups = [groups[k] for k in keep]
        self.weights = None if weights is None else [weights[k] for k in keep]
        self.counts = [int(len(g)) for g in self.groups]
        self.degrees = [(g.shape[1] - 1, g.shape[2] - 1) for g in self.groups]
        arrays = self.groups + ([] if self.weights is None else self.weights)
        self._maps = list({id(m): m for m in (_mapping(a) for a in arrays) if m is not None}.values())

    def release(self) -> None:
        """Give back the pages of memory-mapped arrays read so far (an NPZ's members: they stay in the page
        cache, and are read again from there): a pass over the patches then holds a block of them, not all."""
        advice = getattr(mmap, "MADV_DONTNEED", None)  # POSIX; elsewhere the pages stay
        for mapped in self._maps if advice is not None else ():
            mapped.madvise(advice)

    @property
    def rational(self) -> bool:
        return self.weights is not None

    def take(self, k: int, ids: np.ndarray):
        """(points (c, du+1, dv+1, 3) float64, weights (c, du+1, dv+1) float64 or None): patches ``ids`` (c,) int
        of group ``k`` (indices within the group, sorted or not)."""
        points = np.asarray(self.groups[k][ids], dtype=np.float64)[..., :3]
        return points, None if self.weights is None else np.asarray(self.weights[k][ids], dtype=np.float64)

    def block(self, k: int, a: int, z: int):
        """``take`` of the patches a..z-1 of group ``k``, by a slice (a memory map reads them in order)."""
        points = np.asarray(self.groups[k][a:z], dtype=np.float64)[..., :3]
        return points, None if self.weights is None else np.asarray(self.weights[k][a:z], dtype=np.float64)


class SourcePatches:
    """The patches of a polynomial streamed Surface (``construction.patch_blocks.PatchSource``): biquadratic,
    then bicubic, the kinds without patches left out (as ``patch_set.surface_patch_set``), bit for bit."""

    def __init__(self, source):
        if source.rational:
            raise ValueError("internal: a rational surface's patches are read whole")
        self.source = source
        self.kinds = [kind for kind, count in enumerate(source.counts) if count]
        self.counts = [int(source.counts[kind]) for kind in self.kinds]
        self.degrees = [(2, 2) if kind == 0 else (3, 3) for kind in self.kinds]
        self.weights = None

    rational = False

    def release(self) -> None:
        """Nothing to give back (``PatchSource`` keeps its own cache)."""

    def take(self, k: int, ids: np.ndarray):
        """As ``ArrayPatches.take``."""
        return np.ascontiguousarray(self.source.coefficients(self.kinds[k], ids)[0][..., :3]), None

    def block(self, k: int, a: int, z: int):
        return self.take(k, np.arange(a, z))


def _mapping(array):
    """The ``mmap.mmap`` an array's memory comes from (``np.frombuffer`` of a mapped file), or None."""
    while array is not None:
        if isinstance(array, mmap.mmap):
            return array
        array = array.obj if isinstance(array, memoryview) else getattr(array, "base", None)
    return None


def patch_blocks(patches, size: int):
    """Yield (first global id, group k, a, z): the patches a..z-1 of each group in order, ``size`` at most,
    global ids counting through the groups in order."""
    start = 0
    for k, count in enumerate(patches.counts):
        for a in range(0, count, size):
            yield start + a, k, a, min(a + size, count)
            patches.release()
        start += count


class StreamedPatchSet:
    """What ``check`` and ``measure`` read of a ``PatchSet``, for a streamed polynomial Surface: ``groups`` a
    ``SourcePatches`` reader (``measure_smoothness`` and ``mass_properties`` take it in place of the arrays),
    ``weights`` None, the crease sides, and the adjacency made on first use (``StreamedSurface.adjacency``).

    kept : ``stream.StreamedSurface`` (its caller drops the Surface, so the build's memory goes)
    """

    weights = None

    def __init__(self, kept):
        self.kept = kept
        self.groups = SourcePatches(kept.source)
        crease = np.asarray(kept.crease_sides).reshape(-1, 2)
        self.crease_sides = crease if len(crease) else None  # as ``PatchSet.crease_sides``: None when none listed

    @property
    def n_patches(self) -> int:
        return self.kept.n_patches

    @property
    def adjacency(self):
        return self.kept.adjacency

    def welding(self, tolerance: float = 1e-9):
        """The construction's adjacency (as ``PatchSet.welding`` of the surface's patch set)."""
        return self.kept.adjacency
