"""``c1surf convert``: mesh in, tessellated surface (and patch file) out."""
from __future__ import annotations

import contextlib
import os
import shutil

import click

from ..mesh.errors import TopologyError
from ..construction.surface import Surface, SurfaceOptions
from ..evaluation.stream import StreamedSurface, StreamedTessellation, UndefinedNormals
from ..evaluation.tessellate import patch_adjacency, tessellate_patches
from ..io.atomic import atomic_output
from ..io.meshes.write import write_attribute_mesh, write_streamed_mesh, write_triangle_mesh
from ..io.registry import MESH_WRITERS, PATCH_WRITERS, suffix_list, suffix_of
from ..io.patches.formats import check_patch_files_memory, write_patch_stream, write_surface_patches
from ..io.patches.iges_writer import DEFAULT_UNITS, UNITS
from ..io.meshes.read import read_mesh
from ..io.meshes.surface_data import prepare_surface_input, surface_data
from .common import Failure, Progress, friendly_errors, output_suffix, echo_repair_notes, topology_failure
from .options import (extension_options, resolve_exact_creases, surface_options, tolerance_option, tolerance_value,
                      weld_options, weld_tolerance)

# Imported where used, not here, since a streamed conversion (the usual one) needs none of them: merging
# (evaluation.merge), --curvature (curvature_ply, which imports the renderer's colour maps) and --tolerance
# (evaluation.tolerance).

# Peak memory of a tessellation, traced with tracemalloc on spot_quadrangulated (46,848 patches):
# 465 bytes per patch at N = 2, 4,436 at N = 8, 40,950 at N = 24, i.e. about
# BYTES_PER_PATCH + BYTES_PER_SAMPLE * N^2, times WRITER_HEADROOM for the mesh writers.
BYTES_PER_PATCH = 220
BYTES_PER_SAMPLE = 72
WRITER_HEADROOM = 1.1
# A streamed conversion holds, besides the surface, the sample matrices of both patch degrees
# ((S d) x (N^2 d) and 2 (S x N^2) float64 for S = 9 and 16 control points, d = 3: 2,200 bytes per
# sample) and one block of at least one patch: counted from the array shapes, as 2,400 bytes per sample.
STREAMED_BYTES_PER_SAMPLE = 2400
# The streamed writers that hold the positions of the vertices on patch sides and corners (float64 x, y, z:
# at -r 2 every vertex): STL's records need each triangle's corners (``triangle_point_blocks``).
HELD_POINTS, POINT_BYTES = (".stl",), 24
# Bytes per vertex a streamed writer keeps on the disk beside its output while writing: the vertex blocks
# of OBJ and GLB, evaluated once and read back (``evaluation.stream.SpooledTessellation``: 6 float64).
STREAM_SCRATCH_BYTES = {".obj": 48, ".glb": 48}


def available_memory() -> int:
    """Bytes of memory available to this process (MemAvailable), or 8 GiB if unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 8 << 30


def build_or_fail(mesh, options: SurfaceOptions, data=None, lazy_patches: bool = False) -> Surface:
    """Build the surface of a MeshFile; topology problems become one-line failures.

    ``data``: an ``io.meshes.surface_data.SurfaceData`` (blend ratios, weights, normals,
    attribute columns) for the paper's extensions, or None. ``lazy_patches``: the patch
    arrays are made when first used (``Surface``), for a polynomial surface only (a
    rational one checks its patch weights here).
    """
    try:
        if data is None:
            return Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, options, lazy_patches=lazy_patches)
        kwargs = data.surface_kwargs()
        lazy_patches = lazy_patches and kwargs["weights"] is None
        return Surface(mesh.face_sizes, mesh.face_vertices, data.points, options, lazy_patches=lazy_patches, **kwargs)
    except TopologyError as e:
        raise topology_failure(e, mesh) from None
    except ValueError as e:  # extension data the construction cannot use (e.g. weights making a patch weight <= 0)
        raise Failure(f"{mesh.path}: {e}") from None


def extension_setup(mesh, mesh_suffix: str | None, blend, alpha, beta, tangent_rule, blend_file, interpolate_vertices,
                    interpolate_normals, weights, triangles, attributes, refinements="2", creases_file=None,
                    crease_angle=None, ignore_tags=False, exact_creases=None, non_manifold="sheets"):
    """SurfaceOptions and SurfaceData for the surface options and the extension options of a command.

    ``mesh_suffix``: of the tessellated output (``--attributes`` needs one that
    carries them), or None for a command that writes no mesh.
    """
    interpolate = interpolate_vertices or interpolate_normals
    if interpolate and beta != 0:
        raise click.BadParameter("--interpolate-vertices/--interpolate-normals need --beta 0 (beta moves cell centres off the vertices)")
    if interpolate_normals and alpha == 0:
        raise click.BadParameter("--interpolate-normals needs --alpha > 0")
    if attributes and mesh_suffix is not None and mesh_suffix not in MESH_WRITERS.holding("attributes"):
        raise click.BadParameter(f"--attributes needs an --output in {', '.join(MESH_WRITERS.holding('attributes'))}")
    if interpolate and exact_creases:
        raise click.BadParameter("--exact-creases does not work with --interpolate-vertices/--interpolate-normals yet")
    exact_creases = resolve_exact_creases(exact_creases, interpolate)
    if interpolate and refinements == "0":
        raise click.BadParameter("--interpolate-vertices needs at least one refinement step (--refinements 1, 2 or auto)")
    options = SurfaceOptions(blend=blend, alpha=alpha, beta=beta, tangent_rule=tangent_rule,
                             interpolate_vertices=interpolate, triangles=triangles,
                             refinements=refinements if refinements == "auto" else int(refinements),
                             exact_creases=exact_creases)
    data = surface_data(mesh, blend_file=blend_file, use_weights=weights, normals=interpolate_normals, attributes=attributes,
                        creases_file=creases_file, crease_angle=crease_angle, ignore_tags=ignore_tags,
                        exact_creases=exact_creases, non_manifold=non_manifold)
    return options, data


def tessellation_bytes(n_patches: int, resolution: int) -> float:
    """Estimated peak memory (bytes) of tessellating and writing ``n_patches`` at ``resolution`` (see the constants)."""
    return n_patches * (BYTES_PER_PATCH + BYTES_PER_SAMPLE * resolution * resolution) * WRITER_HEADROOM


# Bytes each output format takes, measured on twisted.obj (15,682 vertices, 31,360 triangles at
# -r 8; 3,636 coefficient rows, 9 per biquadratic and 16 per bicubic patch), a little above:
# per vertex and per triangle for meshes (PLY with float64 positions and normals, halved by
# --float32), per coefficient row for patch files (STEP and IGES unmerged: merging only shrinks them;
# the IGES B-rep takes 273 bytes a row on twisted, 318 on spot).
MESH_FILE_BYTES = {".ply": (48, 13), ".obj": (95, 50), ".stl": (0, 50), ".glb": (24, 12), ".off": (45, 20)}
PATCH_FILE_BYTES = {".json": 80, ".npz": 45, ".igs": 330, ".iges": 330, ".step": 460, ".stp": 460}
CURVATURE_BYTES = 19  # --curvature: kmax, K, H, quality as float, and a colour, per vertex


def output_bytes(mesh_suffix: str, tess, float32: bool, curvature: bool, patch_suffixes, surface) -> list:
    """[(suffix, estimated bytes)] of every file ``convert`` is about to write (``*_FILE_BYTES``); ``surface``: a
    Surface or the ``StreamedSurface`` a streamed conversion keeps of it."""
    per_vertex, per_triangle = MESH_FILE_BYTES[mesh_suffix]
    if float32 and mesh_suffix in (".ply", ".obj"):
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
    return sizes + [(suffix, 4096 + PATCH_FILE_BYTES[suffix] * rows) for suffix in patch_suffixes]


def check_disk_space(paths, sizes, force: bool) -> None:
    """Refuse, before writing, outputs whose estimated ``sizes`` exceed the free space where they go.

    Files on one file system add up; a folder that does not exist is left to ``atomic_output``.
    """
    totals: dict = {}
    free: dict = {}
    for path, (_, size) in zip(paths, sizes):
        folder = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(folder):
            continue
        device = os.stat(folder).st_dev
        totals[device] = totals.get(device, 0) + size
        free.setdefault(device, shutil.disk_usage(folder).free)
    for device, total in totals.items():
        if total > free[device] and not force:
            raise Failure(f"the output files would take about {total / 2**20:.1f} MiB but only "
                          f"{free[device] / 2**20:.1f} MiB is free there: free some space, write elsewhere, "
                          "or pass --force to try anyway")


def check_tessellation_size(n_patches: int, resolution: int, force: bool) -> None:
    """Refuse a tessellation of ``n_patches`` that would not fit in memory, with the estimate."""
    needed = tessellation_bytes(n_patches, resolution)
    available = available_memory()
    if needed > 0.8 * available and not force:
        raise Failure(
            f"the tessellation would need about {needed / 2**30:.1f} GiB ({n_patches} patches at "
            f"--resolution {resolution}) but about {available / 2**30:.1f} GiB is available: lower --resolution, "
            "or pass --force to try anyway"
        )


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
@click.option("--units", type=click.Choice(sorted(UNITS)), default=DEFAULT_UNITS, show_default=True,
              help="Length unit recorded in an IGES patch file (coordinates are written as they are).")
@click.option("--no-group", is_flag=True,
              help="IGES patch file: independent surfaces only, without the B-rep (solid or shell sharing its edges) "
                   "that makes CAD show one object: for readers without IGES B-rep support.")
@click.option("--curvature", is_flag=True,
              help="PLY output: add per-vertex kmax (max |k|), K (Gaussian), H (mean), quality (= kmax) and red/green/blue "
                   "(kmax colour-mapped), evaluated exactly on the patches.")
@click.option("--float32", is_flag=True,
              help="Write points and normals of an .obj/.ply output as float32 (smaller files; float64 by default).")
@surface_options
@extension_options
@weld_options
@click.option("--merge/--no-merge", default=None,
              help="Merge rectangles of biquadratic patches into B-spline surfaces, which IGES and STEP write "
                   "instead of their patches (CAD opens few large faces) and JSON/NPZ keep beside them "
                   "(key \"merged\", merged_* arrays). Default: IGES and STEP files merged, JSON and NPZ not; "
                   "--merge: every patch file; --no-merge: none (one face per patch).")
@click.option("--force", is_flag=True,
              help="Write even when the output is estimated not to fit in memory or on the disk.")
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
def convert(input_path, output, patches_paths, resolution, tolerance, units, no_group, curvature, float32, merge, force,
            quiet, weld, no_weld, **shape):
    """Convert the polygon mesh INPUT (OBJ, PLY or OFF, any n-gons; STL triangles) to a smooth surface.

    Writes OUTPUT, a triangle mesh sampled from the surface's Bezier patches
    (shared patch edges share vertices, so a closed input gives a watertight
    output, with exact normals), and optionally the patches themselves.
    """
    mesh_suffix, patch_suffixes = output_formats(output, patches_paths, curvature, shape["attributes"])
    tolerance = tolerance_value(tolerance)
    progress = Progress(quiet)
    # a uniform resolution is tessellated and written by blocks (--tolerance plans per-patch resolutions
    # over the whole surface first, so it keeps the in-memory path)
    stream = tolerance is None and streams(mesh_suffix, patches_paths, curvature, shape["attributes"], merge)
    surface, data = read_and_build(input_path, mesh_suffix, shape, progress, quiet, weld_tolerance(weld, no_weld),
                                   lazy_patches=stream)
    if stream and surface.lazy_patches:  # polynomial: tessellated and written by blocks
        kept = StreamedSurface(surface, sources=bool(patches_paths), sides=resolution > 2)  # -r 2: corners only
        del surface, data  # only what `kept` holds is read from here on: the rest of the build is freed now
        write_streamed(input_path, output, mesh_suffix, kept, resolution, float32, force, progress,
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
    patch_options = {"adjacency": adjacency, "units": units, "group": not no_group, "force": force}
    merged = merged_pieces(surface, patch_suffixes, merge)
    with atomic_output(output, inputs=[input_path]) as mesh_tmp:
        write_mesh(mesh_tmp, mesh_suffix, tess, extra, data if shape["attributes"] else None, float32)
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
    available = available_memory()
    if needed > 0.8 * available and not force:
        raise Failure(f"tessellating at --resolution {resolution} would need about {needed / 2**30:.1f} GiB {what} "
                      f"but about {available / 2**30:.1f} GiB is available: lower --resolution, or pass --force "
                      "to try anyway")


def write_streamed(input_path, output, mesh_suffix: str, surface, resolution: int, float32: bool,
                   force: bool, progress: Progress, patch_targets=()) -> None:
    """Tessellate and write ``output`` by blocks (``evaluation.stream``), never holding the patches or the mesh;
    then each (path, suffix) of ``patch_targets`` by blocks of patches (``evaluation.patch_set.PatchStream``).

    ``surface``: the ``evaluation.stream.StreamedSurface`` of a polynomial Surface (or the Surface, which is
    then held throughout): its adjacency is made first, and the Surface's topology let go with it.

    Memory is not the limit then, only the disk (``check_disk_space``), but for the sample matrices of one
    patch and, for STL, the positions on patch sides and corners. A sample without a normal
    (``UndefinedNormals``: a degenerate patch point takes its neighbours' normal) needs the whole
    tessellation: that file is written again in memory, with the same bytes the in-memory path writes.
    """
    check_streamed_memory(STREAMED_BYTES_PER_SAMPLE * resolution * resolution, "for one patch", resolution, force)
    if not isinstance(surface, StreamedSurface):
        surface = StreamedSurface(surface, sources=bool(patch_targets))
    adjacency = surface.adjacency
    if mesh_suffix in HELD_POINTS:
        held = adjacency.n_corners + (adjacency.n_edges * (resolution - 2) if resolution > 2 else 0)  # ids below the interiors
        check_streamed_memory(POINT_BYTES * held, "for the positions on patch sides", resolution, force)
    tess = StreamedTessellation(surface.source, adjacency, resolution)
    patch_paths, patch_suffixes = [path for path, _ in patch_targets], [suffix for _, suffix in patch_targets]
    sizes = output_bytes(mesh_suffix, tess, float32, False, patch_suffixes, surface)
    scratch = STREAM_SCRATCH_BYTES.get(mesh_suffix, 0) * tess.n_vertices
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


CAD_SUFFIXES = (".igs", ".iges", ".step", ".stp")  # the patch formats merged by default: CAD opens few large faces


def merged_pieces(surface: Surface, patch_suffixes, merge: bool | None) -> dict:
    """{patch suffix: list of merged pieces or None} for ``--merge/--no-merge`` (None: IGES and STEP only).

    The pieces (``evaluation.merge.merge_biquadratic``) are computed once, when some file takes them.
    """
    from ..evaluation.merge import merge_biquadratic

    wanted = {suffix: (merge if merge is not None else suffix in CAD_SUFFIXES) for suffix in patch_suffixes}
    pieces = merge_biquadratic(surface) if any(wanted.values()) else None
    return {suffix: pieces if take else None for suffix, take in wanted.items()}


def read_and_build(input_path, mesh_suffix: str | None, shape: dict, progress: Progress, quiet: bool,
                   weld: float | None = 0.0, lazy_patches: bool = False):
    """Read the mesh file, weld it and build its surface: (Surface, SurfaceData); notes on repairs unless ``quiet``.

    ``shape``: the values of the surface and extension options (``options.py``),
    keyed by ``extension_setup``'s parameter names; ``weld``: the tolerance of
    ``options.weld_tolerance`` (None: no welding); ``lazy_patches``: ``build_or_fail``'s.
    """
    progress.phase(f"reading {input_path}")
    mesh = read_mesh(input_path)
    options, data = extension_setup(mesh, mesh_suffix, **shape)
    mesh, data = prepare_surface_input(mesh, data, weld, options.exact_creases)
    progress.phase(f"building the surface of {mesh.n_faces} faces")
    surface = build_or_fail(mesh, options, data, lazy_patches)
    echo_repair_notes(surface, mesh, quiet, data)
    return surface, data


def output_formats(output, patches_paths, curvature: bool, attributes: bool) -> tuple[str, list[str]]:
    """The suffixes of ``--output`` and of each ``--patches``; usage errors for what cannot be written."""
    mesh_suffix = output_suffix(output, MESH_WRITERS, "--output")
    patch_suffixes = [output_suffix(p, PATCH_WRITERS, "--patches") for p in patches_paths]
    targets = [os.path.abspath(p) for p in (output, *patches_paths)]
    if len(set(targets)) != len(targets):
        raise click.BadParameter("--output and --patches must name different files")
    if curvature and mesh_suffix not in MESH_WRITERS.holding("properties"):
        raise click.BadParameter("--curvature needs a .ply --output (per-vertex properties)")
    if curvature and attributes:
        raise click.BadParameter("--curvature and --attributes both write vertex colours: choose one")
    return mesh_suffix, patch_suffixes


def curvature_columns(surface: Surface, tess, progress) -> dict:
    """Keyword arguments of ``write_triangle_mesh`` adding the exact curvature at every tessellation vertex."""
    from .curvature_ply import curvature_properties

    return curvature_properties([surface.biquadratic, surface.bicubic], tess, progress, surface.patch_weights)


def write_mesh(path, suffix: str, tess, extra: dict, attribute_data, float32: bool) -> None:
    """Write the tessellation ``tess``; with ``attribute_data`` (a SurfaceData) its extra point columns too."""
    if attribute_data is not None:  # texture coordinates / colours ride along as extra columns of the points
        write_attribute_mesh(path, tess.points[:, :3], tess.triangles, tess.normals, tess.points[:, 3:],
                             attribute_data.attribute_names, attribute_data.colour_scale, suffix=suffix, float32=float32)
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

    The plan (segment counts, templates, numbering) comes first and is cheap, so the
    guard refuses with its exact vertex count; unless ``quiet``, a note gives the
    triangle count and the measured chordal error (``chordal.measured_chordal_error``).
    """
    from ..evaluation.tolerance import measured_chordal_error, plan_tolerance, tessellate_plan

    progress.phase(f"choosing resolutions for a chordal error within {tolerance:g} of the diagonal")
    try:
        plan = plan_tolerance(groups, adjacency, tolerance, weights)
    except ValueError as e:  # more than MAX_SEGMENTS a side
        raise Failure(f"--tolerance {tolerance:g}: {e}") from None
    needed = (plan.n_patches * BYTES_PER_PATCH + TOLERANCE_BYTES_PER_VERTEX * plan.n_vertices) * WRITER_HEADROOM
    available = available_memory()
    if needed > 0.8 * available and not force:
        raise Failure(f"the tessellation would need about {needed / 2**30:.1f} GiB ({plan.n_vertices} vertices at "
                      f"--tolerance {tolerance:g}) but about {available / 2**30:.1f} GiB is available: raise --tolerance, "
                      "or pass --force to try anyway")
    progress.phase(f"tessellating {plan.n_patches} patches at 1 to {int(plan.segments.max(initial=1))} segments a side")
    tess = tessellate_plan(groups, plan, weights)
    if not quiet:
        progress.phase("measuring the chordal error")
        error = measured_chordal_error(groups, tess, weights)
        click.echo(f"c1surf: note: --tolerance {tolerance:g}: {len(tess.triangles)} triangles, {len(tess.points)} "
                   f"vertices; measured chordal error {error:.3g} of the bounding-box diagonal", err=True)
    return tess
