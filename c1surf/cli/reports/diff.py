"""``c1surf diff``: two patch files, or two meshes, compared structurally and coefficient by coefficient."""
from __future__ import annotations

from pathlib import Path

import click

from ...evaluation.compare import compare_meshes, compare_patch_sets
from ...io.meshes.read import read_mesh_in_range
from ...io.patches.formats import load_patch_set
from ...io.registry import MESH_READERS, PATCH_READERS, suffix_list
from ..common import Failure, Progress, friendly_errors, with_formats
from ..options import FiniteFloat


@click.command()
@click.argument("first", metavar="A", type=click.Path(dir_okay=False))
@click.argument("second", metavar="B", type=click.Path(dir_okay=False))
@click.option("--tolerance", type=FiniteFloat(0.0), default=1e-12, show_default=True,
              help="Largest coefficient (or vertex) move accepted as equal, relative to the bounding-box diagonal of A.")
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
@with_formats
def diff(first, second, tolerance, quiet):
    """Compare two patch files ({patch_inputs}) or two meshes ({mesh_inputs}).

    Structure first: patch counts and degrees, weights, merged pieces (meshes:
    vertex and face counts, face sizes and vertices); then every control point
    of B against A's. Prints the first differences (patch, source, coefficient,
    how far it moved) and exits 0 when A and B are equal within --tolerance,
    1 when they differ.
    """
    kinds = [input_kind(path) for path in (first, second)]
    if kinds[0] != kinds[1]:
        raise Failure(f"{first} is a {kinds[0]} file and {second} a {kinds[1]} file: give two of one kind")
    progress = Progress(quiet)
    read = load_patch_set if kinds[0] == "patch" else read_mesh_in_range
    progress.phase(f"reading {first}")
    a = read(first)
    progress.phase(f"reading {second}")
    b = read(second)
    progress.phase("comparing")
    if kinds[0] == "patch":
        comparison = compare_patch_sets(a, b, tolerance)
    else:
        comparison = compare_meshes(a.points, a.face_sizes, a.face_vertices, b.points, b.face_sizes, b.face_vertices,
                                    tolerance)
    progress.done()
    for line in comparison.lines():
        click.echo(line)
    if not comparison.equal:
        raise click.exceptions.Exit(1)


def input_kind(path) -> str:
    """"patch" or "mesh" by the suffix of ``path``; a one-line failure for any other."""
    suffix = Path(path).suffix.lower()
    if suffix in PATCH_READERS:
        return "patch"
    if suffix in MESH_READERS:
        return "mesh"
    raise Failure(f"{path}: unsupported input (suffix {suffix!r}): c1surf diff compares patch files "
                  f"({suffix_list(PATCH_READERS)}) or meshes ({suffix_list(MESH_READERS)})")
