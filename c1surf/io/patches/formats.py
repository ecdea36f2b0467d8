"""Suffix -> writer / reader tables for patch files (``--patches``, ``tessellate``, ``check``)."""
from __future__ import annotations

from pathlib import Path

from .json_patches import read_patch_set_json, read_patches_json, write_patches_json
from .iges import read_patch_set_iges, write_patches_iges
from .npz import read_patch_set_npz, write_patches_npz
from .step import write_patches_step

# Each writer: writer(path, surface, input_path=None, **options); options a writer
# does not use are ignored: adjacency (a PatchAdjacency already computed),
# file_name (the final name when ``path`` is a temporary file), units and group (IGES).
# Each reader: reader(path) -> list of patch arrays (by degree).
# Each loader: loader(path) -> PatchSet (file order, sources, adjacency, header).
PATCH_WRITERS = {
    ".json": write_patches_json,
    ".npz": write_patches_npz,
    ".igs": write_patches_iges,
    ".iges": write_patches_iges,
    ".step": write_patches_step,
    ".stp": write_patches_step,
}
PATCH_LOADERS = {
    ".json": read_patch_set_json,
    ".npz": read_patch_set_npz,
    ".igs": read_patch_set_iges,
    ".iges": read_patch_set_iges,
}
PATCH_READERS = {".json": read_patches_json, **{k: (lambda path, load=v: load(path).by_degree()) for k, v in PATCH_LOADERS.items() if k != ".json"}}


def load_patch_set(path):
    """Read any patch file (the suffix picks the reader) as a PatchSet."""
    suffix = Path(path).suffix.lower()
    if suffix not in PATCH_LOADERS:
        raise ValueError(f"unknown patch format {suffix!r}; use one of {', '.join(sorted(PATCH_LOADERS))}")
    return PATCH_LOADERS[suffix](path)


def patch_suffix(path) -> str:
    """Lower-case suffix of ``path`` if it names a supported patch format, else ValueError."""
    suffix = Path(path).suffix.lower()
    if suffix not in PATCH_WRITERS:
        raise ValueError(f"unknown patch format {suffix!r}; use one of {', '.join(sorted(PATCH_WRITERS))}")
    return suffix
