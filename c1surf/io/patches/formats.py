"""Patch files by suffix (``io.registry.PATCH_READERS`` / ``PATCH_WRITERS``): read any, write a PatchSet, a
Surface, or a PatchStream (by blocks, the formats of ``PATCH_WRITERS.streamed()``)."""
from __future__ import annotations

import dataclasses

from ...evaluation.patch_set import PatchSet, surface_patch_set
from .. import registry
from .checks import check_patch_range

__all__ = ["load_patch_set", "write_patch_set", "write_patch_stream", "write_surface_patches"]


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
    registry.PATCH_WRITERS[suffix].function(path, patch_set, **options)


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
