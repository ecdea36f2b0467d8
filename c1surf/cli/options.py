"""Click options shared by the commands that build a surface."""
from __future__ import annotations

import math

import click
from click.core import ParameterSource

from ..construction.surface import TANGENT_RULES, TRIANGLE_RULES
from .common import Failure
from .numbers import FiniteFloat


def surface_options(command):
    """Add --blend, --alpha, --beta, --tangent-rule to a command."""
    options = [
        click.option("--blend", type=FiniteFloat(0.0, 1.0), default=0.5, show_default=True,
                     help="Doo-Sabin blend ratio alpha_f of every cell (A1): smaller follows the mesh more closely."),
        click.option("--alpha", type=FiniteFloat(0.0, 1.0), default=1.0, show_default=True,
                     help="Shape parameter of the bicubic tangent coefficients P_32 at each cell centre (A3)."),
        click.option("--beta", type=FiniteFloat(-10.0, 10.0), default=0.0, show_default=True,
                     help="Centre point S = S_C + beta (S_P - S_C) of each bicubic cell (section 1.3.3); 0 keeps the cell centroid."),
        click.option("--tangent-rule", type=click.Choice(TANGENT_RULES), default="symmetric", show_default=True,
                     help="Tangent plane at cell centres: 'symmetric' (A3) or 'corners' (A3a, from the C_i only)."),
    ]
    return with_options(command, options)


def extension_options(command):
    """Add the options of the paper's extensions (README, "Extensions of the paper")."""
    options = [
        click.option("--blend-file", type=click.Path(dir_okay=False), default=None,
                     help='JSON of per-cell and per-vertex blend ratios: {"default": r, "faces": {index or OBJ group: r}, '
                          '"vertices": {index: r}} (0-based). PLY face/vertex properties "blend" are used without it.'),
        click.option("--interpolate-vertices", is_flag=True,
                     help="A1a: make the surface pass through every input vertex (needs --beta 0)."),
        click.option("--interpolate-normals", is_flag=True,
                     help="A1a: also give the surface the input's vertex normals there (OBJ vn, PLY nx ny nz); "
                          "implies --interpolate-vertices."),
        click.option("--weights/--no-weights", "weights", default=None,
                     help="A2a: rational patches from the vertex weights (OBJ 'v x y z w', PLY 'weight'); "
                          "default: on when some weight differs from 1."),
        click.option("--triangles", type=click.Choice(TRIANGLE_RULES), default="g1", show_default=True,
                     help="3-sided cells: 'g1' (A3) or 'parametric' (section 1.3.4: parametrically C1 to the "
                          "biquadratic patches around)."),
        click.option("--attributes", is_flag=True,
                     help="Carry texture coordinates and vertex colours through the construction into the output "
                          "(.ply or .obj output)."),
        click.option("--refinements", type=click.Choice(["0", "1", "2", "auto"]), default="2", show_default=True,
                     help="Doo-Sabin steps before A2/A3: 2 as in the paper; 0 or 1 when a closed input already "
                          "satisfies R1-R3 after that many (Prop. 1.3.1); auto: the fewest that work."),
    ]
    return with_options(feature_options(command), options)


def feature_options(command):
    """Add the sharp-feature options (README, "Sharp features")."""
    options = [
        click.option("--creases", "creases_file", type=click.Path(dir_okay=False), default=None,
                     help='JSON of creases, corners and holes besides the file\'s tags: {"creases": [[v0, v1, ..., '
                          'sharpness]], "corners": [[v, sharpness]], "holes": [face, ...]} (indices from 0).'),
        click.option("--crease-angle", type=FiniteFloat(0.0, 180.0, max_open=True), default=None, metavar="DEG",
                     help="Make every edge whose two faces meet at a dihedral angle above DEG degrees an infinitely "
                          "sharp crease (for meshes without tags)."),
        click.option("--ignore-tags", is_flag=True,
                     help="Build the smooth surface: the file's crease, corner and hole tags are read but not used."),
        click.option("--exact-creases/--g1-creases", "exact_creases", default=None,
                     help="Infinitely sharp creases as C0 seams (the default; sectors of three or more faces are merged "
                          "first, edges in more than two faces cut into sheets; a note names what stays the sharpest "
                          "G1 crease: crease ends inside the surface) or, with --g1-creases, all as the sharpest G1 "
                          "crease (a narrow fillet). Patch files list the crease sides; check measures their gap "
                          "(docs/sharp-features.md). --interpolate-vertices/--interpolate-normals imply --g1-creases."),
        click.option("--non-manifold", type=click.Choice(["sheets", "refuse"]), default="sheets", show_default=True,
                     help="Edges in more than two faces: cut into manifold sheets that meet along one C0 crease "
                          "(a note names the edges), or refuse the mesh with the one-line error."),
    ]
    return with_options(command, options)


def resolve_exact_creases(exact_creases: bool | None, interpolate: bool = False) -> bool:
    """``--exact-creases/--g1-creases`` as given, else C0 creases unless vertices are interpolated (A1a)."""
    return (not interpolate) if exact_creases is None else bool(exact_creases)


def weld_options(command):
    """Add --weld TOL and --no-weld (vertices at one position become one vertex; ``weld_tolerance``)."""
    options = [
        click.option("--weld", type=FiniteFloat(0.0, 1.0), default=None, metavar="TOL",
                     help="Weld vertices closer than TOL times the bounding-box diagonal (default: weld equal "
                          "positions only, as STL files and seam-split meshes need)."),
        click.option("--no-weld", is_flag=True,
                     help="Keep the file's vertices: faces join only where they share a vertex number."),
    ]
    return with_options(command, options)


def weld_tolerance(weld: float | None, no_weld: bool) -> float | None:
    """The welding tolerance of ``--weld``/``--no-weld``: None for no welding, 0 for equal positions."""
    if no_weld and weld is not None:
        raise click.BadParameter("--weld and --no-weld contradict each other: give one of them")
    return None if no_weld else (weld or 0.0)


def with_options(command, options: list):
    """Decorate ``command`` with click ``options``, listed in the order --help shows them."""
    for option in reversed(options):
        command = option(command)
    return command


class UsageFailure(Failure):
    """A one-line ``c1surf: error:`` for a bad option value, with the exit status of bad usage (2)."""

    exit_code = 2


def tolerance_option(command):
    """Add --tolerance T (a per-patch resolution instead of --resolution's uniform one; ``tolerance_value``)."""
    return click.option(
        "--tolerance", type=float, default=None, metavar="T",
        help="Instead of --resolution: each patch gets its own grid, fine enough that every triangle is within T "
             "times the bounding-box diagonal of the exact surface (a guaranteed bound on the chordal error); patches "
             "sharing a side sample it alike and transitions have no T-junctions, so a closed input stays watertight. "
             "E.g. 0.001.")(command)


def tolerance_value(tolerance: float | None) -> float | None:
    """The --tolerance value of a command (None: uniform --resolution); one-line errors for misuse.

    T must be a positive finite number, and an explicit --resolution contradicts it
    (its default does not).
    """
    if tolerance is None:
        return None
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise UsageFailure(f"--tolerance must be a positive number (a fraction of the bounding-box diagonal, e.g. "
                           f"0.001), got {tolerance}")
    context = click.get_current_context(silent=True)
    if context is not None and context.get_parameter_source("resolution") not in (None, ParameterSource.DEFAULT):
        raise UsageFailure("--tolerance and --resolution both set the tessellation's resolution: give one of them")
    return float(tolerance)
