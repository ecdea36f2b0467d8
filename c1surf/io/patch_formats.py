"""Suffix -> writer table for patch files (``--patches``)."""
from __future__ import annotations

from pathlib import Path

from .patch_file import read_patches_json, write_patches_json

# Each writer: writer(path, surface, input_path=None). Each reader: reader(path) -> list of patch arrays.
PATCH_WRITERS = {".json": write_patches_json}
PATCH_READERS = {".json": read_patches_json}


def patch_suffix(path) -> str:
    """Lower-case suffix of ``path`` if it names a supported patch format, else ValueError."""
    suffix = Path(path).suffix.lower()
    if suffix not in PATCH_WRITERS:
        raise ValueError(f"unknown patch format {suffix!r}; use one of {', '.join(sorted(PATCH_WRITERS))}")
    return suffix
