"""``c1surf convert``: mesh in, tessellated surface (and patch file) out."""
from __future__ import annotations

import os

import click

from ..core.errors import TopologyError
from ..core.surface import Surface, SurfaceOptions
from ..core.tessellate import patch_adjacency, tessellate_patches
from ..io.atomic import atomic_output
from ..io.mesh_out import MESH_FORMATS, write_triangle_mesh
from ..io.patch_formats import PATCH_WRITERS
from ..io.patch_iges import DEFAULT_UNITS, UNITS
from ..io.read import read_mesh
from .common import Failure, Progress, friendly_errors, output_suffix, repair_notes, topology_failure
from .options import surface_options

BYTES_PER_SAMPLE = 200  # points, normals, two triangles and temporaries per grid sample, measured


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


def build_or_fail(mesh, options: SurfaceOptions) -> Surface:
    """Build the surface of a MeshFile; topology problems become one-line failures."""
    try:
        return Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, options)
    except TopologyError as e:
        raise topology_failure(e, mesh) from None


def check_tessellation_size(surface: Surface, resolution: int, force: bool) -> None:
    """Refuse a tessellation that would not fit in memory, with the estimate."""
    needed = surface.n_patches * resolution * resolution * BYTES_PER_SAMPLE
    available = available_memory()
    if needed > 0.8 * available and not force:
        raise Failure(
            f"the tessellation would need about {needed / 2**30:.1f} GiB ({surface.n_patches} patches at "
            f"--resolution {resolution}) but about {available / 2**30:.1f} GiB is available: lower --resolution, "
            "or pass --force to try anyway"
        )


@click.command()
@click.argument("input_path", metavar="INPUT", type=click.Path(dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False),
              help=f"Tessellated mesh to write; the suffix picks the format ({', '.join(sorted(MESH_FORMATS))}).")
@click.option("--patches", "patches_path", type=click.Path(dir_okay=False), default=None,
              help=f"Also write the Bezier patches; the suffix picks the format ({', '.join(sorted(PATCH_WRITERS))}).")
@click.option("-r", "--resolution", type=click.IntRange(2, None), default=8, show_default=True,
              help="Samples per patch side: each patch becomes an N x N grid of welded vertices.")
@click.option("--units", type=click.Choice(sorted(UNITS)), default=DEFAULT_UNITS, show_default=True,
              help="Length unit recorded in an IGES patch file (coordinates are written as they are).")
@click.option("--no-group", is_flag=True,
              help="IGES patch file: independent surfaces, without the group entity that makes CAD show one object.")
@surface_options
@click.option("--force", is_flag=True, help="Write even when the output is estimated not to fit in memory.")
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
def convert(input_path, output, patches_path, resolution, units, no_group, blend, alpha, beta, tangent_rule, force, quiet):
    """Convert the polygon mesh INPUT (OBJ or PLY, any n-gons) to a smooth surface.

    Writes OUTPUT, a triangle mesh sampled from the surface's Bezier patches
    (shared patch edges share vertices, so a closed input gives a watertight
    output, with exact normals), and optionally the patches themselves.
    """
    mesh_suffix = output_suffix(output, MESH_FORMATS, "--output")
    patch_suffix = output_suffix(patches_path, PATCH_WRITERS, "--patches") if patches_path else None
    progress = Progress(quiet)
    progress.phase(f"reading {input_path}")
    mesh = read_mesh(input_path)
    progress.phase(f"building the surface of {mesh.n_faces} faces")
    surface = build_or_fail(mesh, SurfaceOptions(blend=blend, alpha=alpha, beta=beta, tangent_rule=tangent_rule))
    if not quiet:
        for note in repair_notes(surface, mesh):
            click.echo(f"c1surf: note: {note}", err=True)
    check_tessellation_size(surface, resolution, force)
    progress.phase(f"tessellating {surface.n_patches} patches at {resolution} x {resolution}")
    # the same welding `c1surf tessellate` reads from the patch file: identical meshes
    adjacency = patch_adjacency(surface.refined, surface.frames)
    tess = tessellate_patches([surface.biquadratic, surface.bicubic], adjacency, resolution)
    progress.phase(f"writing {output}")
    with atomic_output(output, inputs=[input_path]) as mesh_tmp:
        write_triangle_mesh(mesh_tmp, tess.points, tess.triangles, tess.normals, suffix=mesh_suffix)
        if patches_path:
            if os.path.abspath(patches_path) == os.path.abspath(output):
                raise click.BadParameter("--patches and --output name the same file")
            with atomic_output(patches_path, inputs=[input_path]) as patch_tmp:
                PATCH_WRITERS[patch_suffix](patch_tmp, surface, input_path=str(input_path), adjacency=adjacency,
                                            file_name=os.path.basename(patches_path), units=units, group=not no_group)
    progress.done()
