"""Patch files by suffix (``io.registry.PATCH_READERS`` / ``PATCH_WRITERS``): read any, write a PatchSet, a
Surface, or a PatchStream (by blocks, the formats of ``PATCH_WRITERS.streamed()``)."""
from __future__ import annotations

import dataclasses
import os

from ...evaluation.patch_set import PatchSet, surface_patch_set
from .. import registry
from .checks import check_patch_range
from ..errors import OutputError
from ...resources import MEMORY_LIMIT_VARIABLE, MEMORY_SHARE, available_memory

__all__ = ["load_patch_set", "write_patch_set", "write_patch_stream", "write_surface_patches", "patch_writer_memory",
           "check_patch_writer_memory", "check_patch_files_memory", "available_memory", "MEMORY_LIMIT_VARIABLE"]



def load_patch_set(path) -> PatchSet:
    """Read any patch file (the suffix picks the reader) as a PatchSet, its coordinates in c1surf's range."""
    patch_set = registry.PATCH_READERS[registry.suffix_of(path, registry.PATCH_READERS)].function(path)
    check_patch_range(path, patch_set)
    return patch_set


def write_patch_set(path, patch_set: PatchSet, suffix: str | None = None, **options) -> None:
    """Write ``patch_set`` in the format of ``suffix`` (default: the path's).

    ``options``: file_name (the final name when ``path`` is a temporary file),
    units and group (IGES); a format ignores the options it has no use for.
    """
    suffix = suffix or registry.suffix_of(path, registry.PATCH_WRITERS)
    if not options.pop("force", False):
        check_patch_writer_memory(options.get("file_name") or path, patch_set.n_patches, suffix)
    registry.PATCH_WRITERS[suffix].function(path, patch_set, **options)


def patch_writer_memory(suffix: str, n_patches: int) -> int:
    """Peak bytes the writer of ``suffix`` takes for ``n_patches`` patches beyond the patch set (0: not modelled,
    small beside it). Measured for the CAD writers (``registry.STEP_MEMORY``, ``IGES_MEMORY``)."""
    return registry.PATCH_WRITERS[suffix].writer_memory(n_patches)


def check_patch_writer_memory(path, n_patches: int, suffix: str | None = None, available: int | None = None) -> None:
    """Refuse, before anything is written, a patch file whose writer would not fit in memory.

    Raises OutputError (one line: the estimate, what is available, what to do) when the writer's peak
    (``patch_writer_memory``) exceeds 80 % of ``available`` (default ``available_memory()``).
    """
    suffix = suffix or registry.suffix_of(path, registry.PATCH_WRITERS)
    needed = patch_writer_memory(suffix, n_patches)
    available = available_memory() if available is None else available
    if needed and needed > MEMORY_SHARE * available:
        kind = suffix.lstrip(".").upper()
        iges = patch_writer_memory(".igs", n_patches)
        other = (f"write .igs (about {iges / 2**30:.1f} GiB), .npz or .json patches instead"
                 if suffix != ".igs" and iges <= MEMORY_SHARE * available else "write .npz or .json patches instead")
        raise OutputError(path, f"writing {n_patches} patches as {kind} would need about {needed / 2**30:.1f} GiB of "
                          f"memory but about {available / 2**30:.1f} GiB is available: make a surface of fewer faces "
                          f"(`c1surf fit` a coarser control mesh first), {other}, or pass --force to try anyway")


def write_patch_stream(path, stream, suffix: str | None = None, **options) -> None:
    """Write an ``evaluation.patch_set.PatchStream`` by blocks: the bytes ``write_patch_set`` writes for its surface.

    Raises ValueError for a format written whole only (``PATCH_WRITERS.streamed()`` lists the others).
    """
    suffix = suffix or registry.suffix_of(path, registry.PATCH_WRITERS)
    function = registry.PATCH_WRITERS[suffix].streamed_function
    if function is None:
        raise ValueError(f"{suffix} files are written whole, not by blocks "
                         f"({', '.join(registry.PATCH_WRITERS.streamed())} are)")
    function(path, stream, **options)


def write_surface_patches(path, surface, suffix: str | None = None, input_path: str | None = None, adjacency=None,
                          merged=None, **options) -> None:
    """Write the patches of a ``construction.surface.Surface`` (see ``write_patch_set``).

    ``adjacency``: its PatchAdjacency when already computed; ``merged``: the
    ``evaluation.merge.MergedPiece`` list of ``convert --merge``, or None.
    """
    patch_set = dataclasses.replace(surface_patch_set(surface, input_path, adjacency), merged=list(merged or []))
    write_patch_set(path, patch_set, suffix, **options)


def check_patch_files_memory(paths, n_patches: int, force: bool = False) -> None:
    """``check_patch_writer_memory`` of every patch file a conversion will write (none with ``force``): called
    before the first output is written, so that a refusal leaves nothing behind."""
    if not force:
        for path in paths:
            check_patch_writer_memory(path, n_patches)
