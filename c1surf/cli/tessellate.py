"""``c1surf tessellate``: a patch file back to a triangle mesh, identical to what ``convert`` writes."""
from __future__ import annotations

import click

from ..evaluation.tessellate import tessellate_patches
from ..io.atomic import atomic_output
from ..io.meshes.usd.stage import USD_SUFFIXES, require_usd
from ..io.patches.formats import load_patch_set
from ..io.registry import MESH_WRITERS, PATCH_READERS, suffix_list
from .common import Failure, Progress, friendly_errors, output_suffix, with_formats
from .convert import check_tessellation_size, tessellate_within, write_mesh
from .options import tolerance_option, tolerance_value


@click.command()
@click.argument("patches_path", metavar="PATCHES", type=click.Path(dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False),
              help=f"Triangle mesh to write; the suffix picks the format ({suffix_list(MESH_WRITERS)}).")
@click.option("-r", "--resolution", type=click.IntRange(2, None), default=8, show_default=True,
              help="Samples per patch side: each patch becomes an N x N grid of welded vertices.")
@tolerance_option
@click.option("--force", is_flag=True, help="Write even when the output is estimated not to fit in memory.")
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
@with_formats
def tessellate(patches_path, output, resolution, tolerance, force, quiet):
    """Tessellate the patch file PATCHES ({patch_inputs}) into a triangle mesh ({mesh_outputs}).

    With the same --resolution (or --tolerance), the mesh is byte for byte the
    one `convert` writes for the same surface: JSON and NPZ files store how patches share
    corners and sides, and the welding uses exactly those ids. IGES files
    (and STEP files) store no adjacency; shared corners and sides are then found from the
    patch geometry (points within 1e-9 of the bounding box), which for a
    c1surf surface gives the same welding.
    """
    mesh_suffix = output_suffix(output, MESH_WRITERS, "--output")
    require_usd([output] if mesh_suffix in USD_SUFFIXES else [])
    patch_suffix = output_suffix(patches_path, PATCH_READERS, "PATCHES")
    tolerance = tolerance_value(tolerance)
    progress = Progress(quiet)
    progress.phase(f"reading {patches_path}")
    patch_set = load_tessellable(patches_path, patch_suffix)
    if tolerance is None:
        check_tessellation_size(patch_set.n_patches, resolution, force)
    if patch_set.adjacency is None:
        progress.phase("finding shared corners and sides from the geometry")
    adjacency = patch_set.welding()
    if tolerance is not None:  # the same tessellation `convert --tolerance` makes of these patches
        tess = tessellate_within(patch_set.groups, adjacency, tolerance, patch_set.weights, force, progress, quiet)
    else:
        progress.phase(f"tessellating {patch_set.n_patches} patches at {resolution} x {resolution}")
        tess = tessellate_patches(patch_set.groups, adjacency, resolution, patch_set.weights)  # weights: rational (A2a)
    progress.phase(f"writing {output}")
    with atomic_output(output, inputs=[patches_path]) as mesh_tmp:
        write_mesh(mesh_tmp, mesh_suffix, tess, {}, None, False)  # convert's: the patch of each triangle in USD
    progress.done()


def load_tessellable(patches_path, patch_suffix: str):
    """The PatchSet of a patch file; a failure when it holds no patch or one of degree above 3."""
    patch_set = load_patch_set(patches_path)  # with the range check every patch reader's result gets
    if patch_set.n_patches == 0:
        raise Failure(f"{patches_path}: the patch file holds no patches")
    dims = {g.shape[1:3] for g in patch_set.groups}
    if any(max(d) > 4 for d in dims):
        raise Failure(f"{patches_path}: patches of degree above 3 are not supported")
    return patch_set
