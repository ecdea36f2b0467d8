"""``c1surf check``: measure tangent-plane continuity across every shared patch edge."""
from __future__ import annotations

import math
from pathlib import Path

import click
from click.core import ParameterSource

from ..api import load_patches
from ..evaluation.smoothness import measure_smoothness
from ..io.registry import MESH_READERS, PATCH_READERS
from .common import Progress, echo_notes, friendly_errors, with_formats
from .options import FiniteFloat, input_options, surface_options


def read_or_build(path, surface, inputs, progress=None):
    """The patches of a patch file, or of the surface of a mesh file built with the options (``api.load_patches``).

    With a ``Progress``: a polynomial surface is kept as a streamed one (``StreamedPatchSet``: its patches
    computed by blocks when read, never all held), the phases shown on a terminal. The notes on the mesh's
    repairs and sharp features go to stderr, each on a line of its own (the commands using this print a report
    on stdout).
    """
    patch_set, notes = load_patches(path, surface, inputs, None if progress is None else progress.phase,
                                    streamed=progress is not None)
    if notes and progress is not None:
        progress.end_line()  # a note on a line of its own, never inside a phase's line
    echo_notes(notes)
    return patch_set


CREASE_HINT = math.radians(1.0)  # a normal jump no G1 surface has: a crease, most likely


def patch_file_crease_angle(inputs) -> float | None:
    """``--crease-angle`` for a patch file (the edges whose normals jump by more are creases); a note names the
    options given that only a mesh input uses (a patch file is measured as it is)."""
    context = click.get_current_context()
    given = [param.opts[-1] if param.opts[-1].startswith("--") else param.opts[0] for param in context.command.params
             if param.name in MESH_ONLY and context.get_parameter_source(param.name) not in (None, ParameterSource.DEFAULT)]
    if given:
        click.echo(f"c1surf: note: {', '.join(given)}: used only when the input is a mesh, not for a patch file", err=True)
    return inputs.crease_angle


# the options of surface_options and input_options but --crease-angle (which a patch file takes too)
MESH_ONLY = ("blend", "alpha", "beta", "tangent_rule", "interpolate_vertices", "triangles", "refinements", "weld",
             "no_weld", "blend_file", "interpolate_normals", "weights", "attributes", "creases_file", "ignore_tags",
             "exact_creases", "non_manifold")


@click.command()
@click.argument("path", metavar="PATCHES|INPUT", type=click.Path(dir_okay=False))
@click.option("--tolerance", type=FiniteFloat(0.0), default=1e-9, show_default=True,
              help="Largest normal jump (radians) and relative position gap accepted as G1.")
@click.option("--samples", type=click.IntRange(2, 10000), default=11, show_default=True,
              help="Points sampled along each shared patch edge, end points included.")
@click.option("--unoriented", is_flag=True,
              help="Compare normals up to sign (tangent-plane continuity of non-orientable surfaces such as a Moebius strip).")
@surface_options
@input_options
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
@with_formats
def check(path, tolerance, samples, unoriented, surface, inputs, quiet):
    """Check that a surface is G1 (tangent-plane continuous).

    PATCHES is a patch file ({patch_inputs}) written by `convert --patches`; a
    mesh INPUT ({mesh_inputs}) is converted first (with the options below). Shared edges are found
    from the patch geometry alone (matching end and mid points), not from the
    construction's bookkeeping. Prints the largest position gap and normal
    jump and exits 1 when the surface is not G1 to within --tolerance. The
    crease edges a patch file lists (`convert --exact-creases`) must be shared
    by their two sides to within --tolerance and are not measured for G1.
    IGES and STEP files list none: there --crease-angle DEG makes the shared
    edges whose normals jump by more than DEG creases (measured for the gap).
    """
    patch_file = Path(path).suffix.lower() in PATCH_READERS
    bend = patch_file_crease_angle(inputs) if patch_file else None
    progress = Progress(quiet)
    patch_set = read_or_build(path, surface, inputs, progress)
    groups, patch_weights = patch_set.groups, patch_set.weights  # weights: rational patches (A2a)
    if bend is not None and patch_set.crease_sides is not None:
        progress.end_line()
        click.echo(f"c1surf: note: {path} lists its crease sides: --crease-angle is not used", err=True)
        bend = None
    report = measure_smoothness(groups, samples=samples, tolerance=min(tolerance, 1e-9), weights=patch_weights,
                                unoriented=unoriented, crease_sides=patch_set.crease_sides,
                                crease_angle=None if bend is None else math.radians(bend), progress=progress.advance)
    progress.done()
    n_patches = patch_set.n_patches
    click.echo(f"patches:          {n_patches}")
    click.echo(f"shared edges:     {report.shared_edges}")
    click.echo(f"boundary edges:   {report.boundary_edges}")
    if report.overshared_edges:
        click.echo(f"edges in > 2 patches: {report.overshared_edges}")
    click.echo(f"max position gap: {report.max_gap:.3e} ({report.relative_gap:.3e} of the bounding box)")
    click.echo(f"max normal jump:  {report.max_normal_jump:.3e} rad")
    if patch_set.crease_sides is not None:  # C0 creases (--exact-creases): met exactly, not G1 across
        click.echo(f"crease edges:     {report.crease_edges} of {len(patch_set.crease_sides)} listed, max gap "
                   f"{report.max_crease_gap:.3e} ({report.relative_crease_gap:.3e} of the bounding box)")
        if report.unpaired_crease_sides:
            click.echo(f"crease edges whose two sides do not meet: {report.unpaired_crease_sides}")
    elif bend is not None:  # a file without the list (IGES, STEP): the edges bending more than DEG
        click.echo(f"crease edges:     {report.crease_edges} bending more than {bend:g} degrees, max gap "
                   f"{report.max_crease_gap:.3e} ({report.relative_crease_gap:.3e} of the bounding box)")
    ok = report.is_g1(tolerance, tolerance)
    click.echo(f"G1: {'yes' if ok else 'NO'} (tolerance {tolerance:g})")
    if patch_file and patch_set.crease_sides is None and bend is None and report.max_normal_jump > CREASE_HINT:
        click.echo(f"c1surf: note: {path} lists no crease sides (c1surf's IGES and STEP files do not), so every shared edge "
                   f"is measured for G1, and some bend by {math.degrees(report.max_normal_jump):.3g} degrees: "
                   "pass --crease-angle DEG to measure the edges bending more than DEG as creases (their gap only)",
                   err=True)
    if not ok:
        raise click.exceptions.Exit(1)
