"""``c1surf measure``: area, and for a closed surface volume, centroid and inertia tensor, from the patches."""
from __future__ import annotations

import json

import click

from ...evaluation.measure import AREA_RTOL, MassProperties, mass_properties
from ..check import read_or_build
from ..common import Progress, friendly_errors, with_formats
from ..options import input_options, surface_options


@click.command()
@click.argument("path", metavar="PATCHES|INPUT", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True,
              help='Print one JSON object: "area", "volume", "centroid" (3 numbers), "inertia" (3 x 3), "closed", '
                   '"area_error", "reason" (why volume, centroid and inertia are null) and "note".')
@surface_options
@input_options
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
@with_formats
def measure(path, as_json, surface, inputs, quiet):
    """Surface area and, for a closed surface, enclosed volume, centroid and inertia tensor.

    PATCHES is a patch file ({patch_inputs}); a mesh INPUT ({mesh_inputs}) is
    converted first, as by `check` (with the options below). Computed
    from the exact patches by Gauss-Legendre quadrature: the volume (divergence
    theorem), centroid and inertia of polynomial patches exactly up to rounding,
    the area (and the moments of rational patches) adaptively to about 1e-13
    relative. The inertia tensor is that of the solid of unit density about its
    centroid. A surface is closed when every patch side is shared by two
    consistently oriented patches; an open one has no volume.
    """
    progress = Progress(quiet)
    patch_set = read_or_build(path, surface, inputs, progress)
    adjacency = patch_set.welding()
    result = mass_properties(patch_set.groups, adjacency.edges, adjacency.reversed, patch_set.weights,
                             progress=progress.advance)
    progress.done()
    if as_json:
        click.echo(json.dumps(result_document(result)))
    else:
        for line in result_lines(result, patch_set.n_patches):
            click.echo(line)


def result_document(result: MassProperties) -> dict:
    """The JSON object of ``measure --json`` (null volume, centroid and inertia for an open surface)."""
    return {
        "area": result.area,
        "volume": result.volume,
        "centroid": None if result.centroid is None else result.centroid.tolist(),
        "inertia": None if result.inertia is None else result.inertia.tolist(),
        "closed": result.closed,
        "area_error": result.area_error,
        "reason": result.reason,
        "note": result.note,
    }


def result_lines(result: MassProperties, n_patches: int) -> list[str]:
    """The text report of ``measure``."""
    lines = [f"patches:   {n_patches} ({'closed' if result.closed else 'not closed'})",
             f"area:      {result.area:.15g} (estimated error {max(result.area_error, AREA_RTOL * result.area):.1e})"]
    if not result.closed:
        return lines + [f"volume, centroid, inertia: not defined: {result.reason}"]
    c = result.centroid
    lines += [f"volume:    {result.volume:.15g}", f"centroid:  {c[0]:.15g} {c[1]:.15g} {c[2]:.15g}",
              "inertia:   (unit density, about the centroid)"]
    lines += ["  " + " ".join(f"{x:22.15g}" for x in row) for row in result.inertia]
    if result.note:
        lines.append(f"note: {result.note}")
    return lines
