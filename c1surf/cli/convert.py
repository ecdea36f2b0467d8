"""``c1surf convert``: mesh in, tessellated surface (and patch file) out."""
from __future__ import annotations

import contextlib
import os

import click

from ..api import InputOptions, Surface, SurfaceOptions, load_surface
from ..evaluation.stream import StreamedSurface, StreamedTessellation, UndefinedNormals
from ..evaluation.tessellate import patch_adjacency, tessellate_patches
from ..io.atomic import atomic_output
from ..io.meshes.usd.stage import USD_SUFFIXES, require_usd
from ..io.meshes.write import TriangleMesh, write_attribute_mesh, write_streamed_mesh, write_triangle_mesh
from ..io.meshes.write import write_mesh as write_mesh_file
from ..io.registry import MESH_WRITERS, PATCH_WRITERS, suffix_list, suffix_of
from ..io.patches.formats import check_patch_files_memory, write_patch_stream, write_surface_patches
from ..resources import (BYTES_PER_PATCH, STREAMED_BYTES_PER_SAMPLE, WRITER_HEADROOM, check_disk_space, check_memory,
                         tessellation_bytes)
from .common import Failure, Progress, echo_notes, friendly_errors, output_suffix, with_formats
from .options import (PatchFileOptions, input_options, patch_file_options, surface_options, tolerance_option,
                      tolerance_value)

# Imported where used, not here, since a streamed conversion (the usual one) needs none of them: merging
# (evaluation.merge), --curvature (curvature_ply, which imports the renderer's colour maps) and --tolerance
# (evaluation.tolerance).

CURVATURE_BYTES = 19  # --curvature: kmax, K, H, quality as float, and a colour, per vertex
POINT_BYTES = 24  # a held position (float64 x, y, z): ``Format.held_points``


def output_bytes(mesh_suffix: str, tess, float32: bool, curvature: bool, patch_suffixes, surface) -> list:
    """[(suffix, estimated bytes)] of every file ``convert`` is about to write (``io.registry.Format.file_bytes``);
    ``surface``: a Surface or the ``StreamedSurface`` a streamed conversion keeps of it."""
    mesh_format = MESH_WRITERS[mesh_suffix]
    per_vertex, per_triangle = mesh_format.file_bytes
    if float32 and mesh_format.float32:
        per_vertex //= 2
    per_vertex += CURVATURE_BYTES if curvature else 0
    counts = surface.counts if isinstance(surface, StreamedSurface) else (surface.quad_frames.shape[0],
                                                                         surface.cubic_frames.shape[0])
    rows = 9 * counts[0] + 16 * counts[1]
    if isinstance(tess, StreamedTessellation):
        n_vertices, n_triangles = tess.n_vertices, tess.n_triangles
    else:
        n_vertices, n_triangles = len(tess.points), len(tess.triangles)
    sizes = [(mesh_suffix, 1024 + per_vertex * n_vertices + per_triangle * n_triangles)]
    return sizes + [(suffix, 4096 + PATCH_WRITERS[suffix].file_bytes[0] * rows) for suffix in patch_suffixes]


def check_tessellation_size(n_patches: int, resolution: int, force: bool) -> None:
    """Refuse a tessellation of ``n_patches`` that would not fit in memory, with the estimate."""
    check_memory(tessellation_bytes(n_patches, resolution), "the tessellation", "lower --resolution", force,
                 f" ({n_patches} patches at --resolution {resolution})")


@click.command()
@click.argument("input_path", metavar="INPUT", type=click.Path(dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False),
              help=f"Tessellated mesh to write; the suffix picks the format ({suffix_list(MESH_WRITERS)}).")
@click.option("--patches", "patches_paths", type=click.Path(dir_okay=False), multiple=True,
              help=f"Also write the Bezier patches; the suffix picks the format ({suffix_list(PATCH_WRITERS)}); "
                   "repeat for several formats.")
@click.option("-r", "--resolution", type=click.IntRange(2, None), default=8, show_default=True,
              help="Samples per patch side: each patch becomes an N x N grid of welded vertices.")
@tolerance_option
@patch_file_options
@click.option("--curvature", is_flag=True,
              help="PLY output: add per-vertex kmax (max |k|), K (Gaussian), H (mean), quality (= kmax) and red/green/blue "
                   "(kmax colour-mapped), evaluated exactly on the patches.")
@click.option("--float32", is_flag=True,
              help="Write points and normals of an .obj/.ply output as float32 (smaller files; float64 by default).")
@surface_options
@input_options
@click.option("--force", is_flag=True,
              help="Write even when the output is estimated not to fit in memory or on the disk.")
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
@with_formats
def convert(input_path, output, patches_paths, resolution, tolerance, patch_files, curvature, float32, force, quiet,
            surface, inputs):
    """Convert the polygon mesh INPUT ({mesh_inputs}: any n-gons, STL triangles) to a smooth surface.

    Writes OUTPUT, a triangle mesh sampled from the surface's Bezier patches
    (shared patch edges share vertices, so a closed input gives a watertight
    output, with exact normals), and optionally the patches themselves.
    """
    mesh_suffix, patch_suffixes = output_formats(output, patches_paths, curvature, inputs.attributes)
    tolerance = tolerance_value(tolerance)
    progress = Progress(quiet)
    # a uniform resolution is tessellated and written by blocks (--tolerance plans per-patch resolutions
    # over the whole surface first, so it keeps the in-memory path)
    stream = tolerance is None and streams(mesh_suffix, patches_paths, curvature, inputs.attributes, patch_files.merge)
    surface, report = read_and_build(input_path, surface, inputs, progress, quiet, lazy_patches=stream)
    if stream and surface.lazy_patches:  # polynomial: tessellated and written by blocks
        kept = StreamedSurface(surface, sources=bool(patches_paths), sides=resolution > 2)  # -r 2: corners only
        del surface, report  # only what `kept` holds is read from here on: the rest of the build is freed now
        write_streamed(input_path, (output, mesh_suffix), kept, resolution, float32, force, progress,
                       list(zip(patches_paths, patch_suffixes)))
        progress.done()
        return
    check_patch_files_memory(patches_paths, surface.n_patches, force)  # the CAD writers' memory, before any output
    # the same welding `c1surf tessellate` reads from the patch file: identical meshes
    adjacency = patch_adjacency(surface.refined, surface.frames)
    if tolerance is not None:
        tess = tessellate_within([surface.biquadratic, surface.bicubic], adjacency, tolerance, surface.patch_weights,
                                 force, progress, quiet)
    else:
        check_tessellation_size(surface.n_patches, resolution, force)
        progress.phase(f"tessellating {surface.n_patches} patches at {resolution} x {resolution}")
        tess = tessellate_patches([surface.biquadratic, surface.bicubic], adjacency, resolution, surface.patch_weights)
    extra = curvature_columns(surface, tess, progress.advance) if curvature else {}
    check_disk_space([output, *patches_paths], output_bytes(mesh_suffix, tess, float32, curvature, patch_suffixes,
                                                           surface), force)
    progress.phase(f"writing {output}")
    patch_options = {"adjacency": adjacency, "units": patch_files.units, "group": patch_files.group,
                     "force": force, "strips": patch_files.strips}
    merged = merged_pieces(surface, patch_suffixes, patch_files.merge)
    with atomic_output(output, inputs=[input_path]) as mesh_tmp:
        write_mesh(mesh_tmp, mesh_suffix, tess, extra, report.data if inputs.attributes else None, float32)
        del tess, extra  # written: leave its memory to the patch writers
        write_patch_files(zip(patches_paths, patch_suffixes), surface, input_path, patch_options, progress, merged)
    progress.done()


def streams(mesh_suffix: str, patches_paths, curvature: bool, attributes: bool, merge: bool | None = None) -> bool:
    """Whether ``convert`` writes its mesh and patch files by blocks: formats written so (``MESH_WRITERS.streamed()``,
    ``PATCH_WRITERS.streamed()``), and no option that needs the whole surface (``--curvature``, ``--attributes``,
    ``--merge`` with patch files; rational surfaces are told apart after reading). ``C1SURF_STREAM=0`` turns it off."""
    if os.environ.get("C1SURF_STREAM", "1").strip() == "0":
        return False
    patch_suffixes = [suffix_of(path, PATCH_WRITERS) for path in patches_paths]
    if any(suffix not in PATCH_WRITERS.streamed() for suffix in patch_suffixes) or (patch_suffixes and merge):
        return False
    return mesh_suffix in MESH_WRITERS.streamed() and not (curvature or attributes)


def check_streamed_memory(needed: int, what: str, resolution: int, force: bool) -> None:
    """Refuse a streamed conversion whose ``needed`` bytes (``what`` they hold) would not fit in memory."""
    check_memory(needed, f"tessellating at --resolution {resolution}", "lower --resolution", force, f" {what}")


def write_streamed(input_path, target: tuple, surface, resolution: int, float32: bool, force: bool, progress: Progress,
                   patch_targets=()) -> None:
    """Tessellate and write ``target`` (output path, its mesh suffix) by blocks (``evaluation.stream``), never holding the patches or the mesh;
    then each (path, suffix) of ``patch_targets`` by blocks of patches (``evaluation.patch_set.PatchStream``).

    ``surface``: the ``evaluation.stream.StreamedSurface`` of a polynomial Surface (or the Surface, which is
    then held throughout): its adjacency is made first, and the Surface's topology let go with it.

    Memory is not the limit then, only the disk (``check_disk_space``), but for the sample matrices of one
    patch and, for STL, the positions on patch sides and corners. A sample without a normal
    (``UndefinedNormals``: a degenerate patch point takes its neighbours' normal) needs the whole
    tessellation: that file is written again in memory, with the same bytes the in-memory path writes.
    """
    output, mesh_suffix = target
    check_streamed_memory(STREAMED_BYTES_PER_SAMPLE * resolution * resolution, "for one patch", resolution, force)
    if not isinstance(surface, StreamedSurface):
        surface = StreamedSurface(surface, sources=bool(patch_targets))
    adjacency = surface.adjacency
    if MESH_WRITERS[mesh_suffix].held_points:
        held = adjacency.n_corners + (adjacency.n_edges * (resolution - 2) if resolution > 2 else 0)  # ids below the interiors
        check_streamed_memory(POINT_BYTES * held, "for the positions on patch sides", resolution, force)
    tess = StreamedTessellation(surface.source, adjacency, resolution)
    patch_paths, patch_suffixes = [path for path, _ in patch_targets], [suffix for _, suffix in patch_targets]
    sizes = output_bytes(mesh_suffix, tess, float32, False, patch_suffixes, surface)
    scratch = MESH_WRITERS[mesh_suffix].scratch_bytes * tess.n_vertices
    check_disk_space([output, *patch_paths], [(mesh_suffix, sizes[0][1] + scratch), *sizes[1:]], force)
    progress.phase(f"tessellating {surface.n_patches} patches at {resolution} x {resolution} into {output}")
    with atomic_output(output, inputs=[input_path]) as mesh_tmp:
        try:
            write_streamed_mesh(mesh_tmp, tess, mesh_suffix, float32)
        except UndefinedNormals:
            check_tessellation_size(surface.n_patches, resolution, force)
            whole = tessellate_patches(surface.whole_patches(), adjacency, resolution)
            write_mesh(mesh_tmp, mesh_suffix, whole, {}, None, float32)
            del whole
        del tess
        if patch_targets:
            stream = surface.patch_stream(str(input_path))
            with contextlib.ExitStack() as patch_files:  # all files appear together, or none
                for path, suffix in patch_targets:
                    progress.phase(f"writing {path}")
                    patch_tmp = patch_files.enter_context(atomic_output(path, inputs=[input_path]))
                    write_patch_stream(patch_tmp, stream, suffix, file_name=os.path.basename(path))


def merged_pieces(surface: Surface, patch_suffixes, merge: bool | None) -> dict:
    """{patch suffix: list of merged pieces or None} for ``--merge/--no-merge`` (None: ``Format.merged``, IGES and STEP).

    The pieces (``evaluation.merge.merge_biquadratic``) are computed once, when some file takes them.
    """
    from ..evaluation.merge import merge_biquadratic

    wanted = {suffix: (merge if merge is not None else PATCH_WRITERS[suffix].merged) for suffix in patch_suffixes}
    pieces = merge_biquadratic(surface) if any(wanted.values()) else None
    return {suffix: pieces if take else None for suffix, take in wanted.items()}


def read_and_build(input_path, surface_options: SurfaceOptions, input_options: InputOptions, progress: Progress,
                   quiet: bool, lazy_patches: bool = False):
    """``api.load_surface`` with the command's progress lines, then its notes (unless ``quiet``): (Surface, LoadReport)."""
    surface, report = load_surface(input_path, surface_options, input_options, lazy_patches=lazy_patches,
                                   progress=progress.phase)
    echo_notes(report.notes, quiet)
    return surface, report


def output_formats(output, patches_paths, curvature: bool, attributes: bool) -> tuple[str, list[str]]:
    """The suffixes of ``--output`` and of each ``--patches``; usage errors for what cannot be written."""
    mesh_suffix = output_suffix(output, MESH_WRITERS, "--output")
    require_usd([output] if mesh_suffix in USD_SUFFIXES else [])  # before the surface is built
    patch_suffixes = [output_suffix(p, PATCH_WRITERS, "--patches") for p in patches_paths]
    targets = [os.path.abspath(p) for p in (output, *patches_paths)]
    if len(set(targets)) != len(targets):
        raise click.BadParameter("--output and --patches must name different files")
    if curvature and mesh_suffix not in MESH_WRITERS.holding("properties"):
        raise click.BadParameter("--curvature needs a .ply --output (per-vertex properties)")
    if curvature and attributes:
        raise click.BadParameter("--curvature and --attributes both write vertex colours: choose one")
    if attributes and mesh_suffix not in MESH_WRITERS.holding("attributes"):
        raise click.BadParameter(f"--attributes needs an --output in {', '.join(MESH_WRITERS.holding('attributes'))}")
    return mesh_suffix, patch_suffixes


def curvature_columns(surface: Surface, tess, progress) -> dict:
    """Keyword arguments of ``write_triangle_mesh`` adding the exact curvature at every tessellation vertex."""
    from .curvature_ply import curvature_properties

    return curvature_properties([surface.biquadratic, surface.bicubic], tess, progress, surface.patch_weights)


def write_mesh(path, suffix: str, tess, extra: dict, attribute_data, float32: bool) -> None:
    """Write the tessellation ``tess``; with ``attribute_data`` (the input's ``prepare.extension_data.SurfaceData``)
    its extra point columns too."""
    if attribute_data is not None:  # texture coordinates / colours ride along as extra columns of the points
        write_attribute_mesh(path, tess.points[:, :3], tess.triangles, tess.normals, tess.points[:, 3:],
                             attribute_data.attribute_names, colour_scale=attribute_data.colour_scale, suffix=suffix,
                             float32=float32)
    elif suffix in MESH_WRITERS.holding("patch ids"):  # USD: the patch of each triangle rides along
        write_mesh_file(path, TriangleMesh(tess.points[:, :3], tess.triangles, tess.normals,
                                           triangle_patch=tess.triangle_patch), suffix, float32)
    else:
        write_triangle_mesh(path, tess.points, tess.triangles, tess.normals, suffix=suffix, float32=float32, **extra)


def write_patch_files(targets, surface: Surface, input_path, patch_options: dict, progress: Progress,
                      merged: dict | None = None) -> None:
    """Write the patches into every (path, suffix) of ``targets``: all files appear together, or none.

    ``patch_options``: the keyword arguments every patch writer takes besides the
    paths (adjacency, units, group); ``merged``: {suffix: merged pieces or None}
    (``merged_pieces``), None for none.
    """
    with contextlib.ExitStack() as patch_files:
        for patches_path, patch_suffix in targets:
            progress.phase(f"writing {patches_path}")
            patch_tmp = patch_files.enter_context(atomic_output(patches_path, inputs=[input_path]))
            write_surface_patches(patch_tmp, surface, patch_suffix, input_path=str(input_path),
                                  file_name=os.path.basename(patches_path), merged=(merged or {}).get(patch_suffix),
                                  **patch_options)


# --tolerance: peak bytes per output vertex besides BYTES_PER_PATCH (traced with tracemalloc on spot_quadrangulated:
# 158 at --tolerance 1e-5, 1.1 M vertices; points, normals, the evaluating patch and parameters of each vertex, about
# two triangles, and the template blocks' ids)
TOLERANCE_BYTES_PER_VERTEX = 160


def tessellate_within(groups, adjacency, tolerance: float, weights, force: bool, progress: Progress, quiet: bool):
    """``--tolerance``: the tessellation to a chordal tolerance (``evaluation.tolerance``), after the memory guard.

    The plan (segment counts, templates, numbering) comes first, so the guard refuses
    with its exact vertex count; before the plan's side counts and templates (which
    take seconds and GBs at a tolerance far too small) it refuses on a lower bound,
    the cells of each patch's fewest segments. Unless ``quiet``, a note gives the
    triangle count and the measured chordal error (``chordal.measured_chordal_error``).
    """
    from ..evaluation.tolerance import measured_chordal_error, plan_tolerance, tessellate_plan

    n_patches = sum(len(g) for g in groups)

    def guard(n_vertices: int, at_least: str = "") -> None:
        needed = (n_patches * BYTES_PER_PATCH + TOLERANCE_BYTES_PER_VERTEX * n_vertices) * WRITER_HEADROOM
        check_memory(needed, "the tessellation", "raise --tolerance", force,
                     f" ({at_least}{n_vertices} vertices at --tolerance {tolerance:g})")

    progress.phase(f"choosing resolutions for a chordal error within {tolerance:g} of the diagonal")
    try:  # the guard first on a lower bound of the vertices, before the plan's costly steps, then on its count
        plan = plan_tolerance(groups, adjacency, tolerance, weights, budget=lambda n: guard(n, "at least "))
    except ValueError as e:  # more than MAX_SEGMENTS a side
        raise Failure(f"--tolerance {tolerance:g}: {e}") from None
    guard(plan.n_vertices)
    progress.phase(f"tessellating {plan.n_patches} patches at 1 to {int(plan.segments.max(initial=1))} segments a side")
    tess = tessellate_plan(groups, plan, weights)
    if not quiet:
        progress.phase("measuring the chordal error")
        error = measured_chordal_error(groups, tess, weights)
        click.echo(f"c1surf: note: --tolerance {tolerance:g}: {len(tess.triangles)} triangles, {len(tess.points)} "
                   f"vertices; measured chordal error {error:.3g} of the bounding-box diagonal", err=True)
    return tess
