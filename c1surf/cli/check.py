"""``c1surf check``: measure tangent-plane continuity across every shared patch edge."""
from __future__ import annotations

from pathlib import Path

import click

from ..evaluation.smoothness import measure_smoothness
from ..io.patches.formats import load_patch_set
from ..io.registry import PATCH_READERS
from ..io.meshes.read import read_mesh
from .common import file_notes, friendly_errors
from .convert import build_or_fail, extension_setup
from .options import extension_options, surface_options


@click.command()
@click.argument("path", metavar="PATCHES|INPUT", type=click.Path(dir_okay=False))
@click.option("--tolerance", type=float, default=1e-9, show_default=True,
              help="Largest normal jump (radians) and relative position gap accepted as G1.")
@click.option("--samples", type=click.IntRange(2, None), default=11, show_default=True,
              help="Points sampled along each shared patch edge, end points included.")
@click.option("--unoriented", is_flag=True,
              help="Compare normals up to sign (tangent-plane continuity of non-orientable surfaces such as a Moebius strip).")
@surface_options
@extension_options
@friendly_errors
def check(path, tolerance, samples, unoriented, blend, alpha, beta, tangent_rule, blend_file, interpolate_vertices, interpolate_normals,
          weights, triangles, attributes, refinements):
    """Check that a surface is G1 (tangent-plane continuous).

    PATCHES is a patch file written by `convert --patches`; an OBJ/PLY INPUT is
    converted first (with the surface options below). Shared edges are found
    from the patch geometry alone (matching end and mid points), not from the
    construction's bookkeeping. Prints the largest position gap and normal
    jump and exits 1 when the surface is not G1 to within --tolerance.
    """
    suffix = Path(path).suffix.lower()
    if suffix in PATCH_READERS:
        patch_set = load_patch_set(path)
        groups, patch_weights = patch_set.groups, patch_set.weights  # weights: rational patches (A2a)
    else:
        mesh = read_mesh(path)
        for note in file_notes(mesh):  # check has no --quiet: the notes go to stderr, the report to stdout
            click.echo(f"c1surf: note: {note}", err=True)
        options, data = extension_setup(mesh, None, blend, alpha, beta, tangent_rule, blend_file, interpolate_vertices,
                                        interpolate_normals, weights, triangles, attributes, refinements)
        surface = build_or_fail(mesh, options, data)
        groups, patch_weights = [surface.biquadratic, surface.bicubic], surface.patch_weights
    report = measure_smoothness(groups, samples=samples, tolerance=min(tolerance, 1e-9), weights=patch_weights,
                                unoriented=unoriented)
    n_patches = sum(len(g) for g in groups)
    click.echo(f"patches:          {n_patches}")
    click.echo(f"shared edges:     {report.shared_edges}")
    click.echo(f"boundary edges:   {report.boundary_edges}")
    if report.overshared_edges:
        click.echo(f"edges in > 2 patches: {report.overshared_edges}")
    click.echo(f"max position gap: {report.max_gap:.3e} ({report.relative_gap:.3e} of the bounding box)")
    click.echo(f"max normal jump:  {report.max_normal_jump:.3e} rad")
    ok = report.is_g1(tolerance, tolerance)
    click.echo(f"G1: {'yes' if ok else 'NO'} (tolerance {tolerance:g})")
    if not ok:
        raise click.exceptions.Exit(1)
