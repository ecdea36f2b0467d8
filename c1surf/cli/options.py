"""Click options shared by the commands, grouped into the objects the library takes, and ``FiniteFloat``.

``click.FloatRange`` lets ``nan`` through every range (each comparison with NaN is false), and ``float``
takes ``nan`` and ``inf``: a NaN blend ratio then turns every output point into NaN. ``FiniteFloat`` is
the type of every float option of every command.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import click
from click.core import ParameterSource

from ..api import NON_MANIFOLD_RULES, InputOptions, SurfaceOptions
from ..construction.surface import TANGENT_RULES, TRIANGLE_RULES
from ..io.meshes.usd.stage import UsdReadOptions
from ..io.patches.iges_writer import DEFAULT_UNITS, UNITS
from .common import UsageFailure


def _number(value: float) -> str:
    """``value`` as the user would type it: 0.5, 1, 1e-06."""
    return f"{value:g}"


class FiniteFloat(click.FloatRange):
    """A finite float, optionally within [min, max] (open ends with ``min_open``/``max_open``).

    Errors name the range the way the help does: ``2 is not in [0, 1]``, ``nan is not a finite number``.
    """

    name = "float"

    def __init__(self, min: float | None = None, max: float | None = None,
                 min_open: bool = False, max_open: bool = False):
        super().__init__(min=min, max=max, min_open=min_open, max_open=max_open, clamp=False)

    def convert(self, value, param, ctx):
        number = click.types.FloatParamType.convert(self, value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value} is not a finite number", param, ctx)
        low = self.min is not None and (number <= self.min if self.min_open else number < self.min)
        high = self.max is not None and (number >= self.max if self.max_open else number > self.max)
        if low or high:
            self.fail(f"{value} is not in {self.describe()}", param, ctx)
        return number

    def describe(self) -> str:
        """The range as an interval: [0, 1], (0, 180), [0, inf)."""
        left = "(" if self.min_open or self.min is None else "["
        right = ")" if self.max_open or self.max is None else "]"
        low = "-inf" if self.min is None else _number(self.min)
        high = "inf" if self.max is None else _number(self.max)
        return f"{left}{low}, {high}{right}"

    def _describe_range(self) -> str:  # the help's "[0<=x<=1]"
        return self.describe() if (self.min is not None or self.max is not None) else "finite"

    def __repr__(self) -> str:
        return f"FiniteFloat{self.describe()}"


def surface_options(command=None, *, refinements: str = "2"):
    """Add the construction's options (``SurfaceOptions``: A1, A3, A1a, section 1.3.4, Prop. 1.3.1); the command
    receives them as one ``surface`` argument. ``@surface_options(refinements="auto")``: another default for
    --refinements (``fit``: the fewest Doo-Sabin steps the control mesh allows)."""
    if command is None:
        return lambda command: surface_options(command, refinements=refinements)
    options = [
        click.option("--blend", type=FiniteFloat(0.0, 1.0), default=0.5, show_default=True,
                     help="Doo-Sabin blend ratio alpha_f of every cell (A1): smaller follows the mesh more closely."),
        click.option("--alpha", type=FiniteFloat(0.0, 1.0), default=1.0, show_default=True,
                     help="Shape parameter of the bicubic tangent coefficients P_32 at each cell centre (A3)."),
        click.option("--beta", type=FiniteFloat(-10.0, 10.0), default=0.0, show_default=True,
                     help="Centre point S = S_C + beta (S_P - S_C) of each bicubic cell (section 1.3.3); 0 keeps the cell centroid."),
        click.option("--tangent-rule", type=click.Choice(TANGENT_RULES), default="symmetric", show_default=True,
                     help="Tangent plane at cell centres: 'symmetric' (A3) or 'corners' (A3a, from the C_i only)."),
        click.option("--interpolate-vertices", is_flag=True,
                     help="A1a: make the surface pass through every input vertex (needs --beta 0)."),
        click.option("--triangles", type=click.Choice(TRIANGLE_RULES), default="g1", show_default=True,
                     help="3-sided cells: 'g1' (A3) or 'parametric' (section 1.3.4: parametrically C1 to the "
                          "biquadratic patches around)."),
        click.option("--refinements", type=click.Choice(["0", "1", "2", "auto"]), default=refinements, show_default=True,
                     help="Doo-Sabin steps before A2/A3: 2 as in the paper; 1 when R1-R3 hold after one step on the "
                          "cells the kept patches read (open meshes, C0 creases and darts too), 0 when a closed input "
                          "already satisfies them (Prop. 1.3.1); auto: the fewest that work (a note says why two)."),
    ]

    def build(refinements, **values):
        steps = refinements if refinements == "auto" else int(refinements)
        return SurfaceOptions(refinements=steps, **values)

    return grouped(command, "surface", options, build)


def input_options(command):
    """Add the options saying what to read from a mesh file and how to repair it (``InputOptions``: welding, the
    paper's extensions' data (docs/paper-notes.md), sharp features (docs/sharp-features.md)); the command receives
    them as one ``inputs`` argument."""
    options = [
        click.option("--weld", type=FiniteFloat(0.0, 1.0), default=None, metavar="TOL",
                     help="Weld vertices closer than TOL times the bounding-box diagonal (default: weld equal "
                          "positions only, as STL files and seam-split meshes need)."),
        click.option("--no-weld", is_flag=True,
                     help="Keep the file's vertices: faces join only where they share a vertex number."),
        click.option("--blend-file", type=click.Path(dir_okay=False), default=None,
                     help='JSON of per-cell and per-vertex blend ratios: {"default": r, "faces": {index or OBJ group: r}, '
                          '"vertices": {index: r}} (0-based). PLY face/vertex properties "blend" are used without it.'),
        click.option("--interpolate-normals", is_flag=True,
                     help="A1a: also give the surface the input's vertex normals there (OBJ vn, PLY nx ny nz); "
                          "implies --interpolate-vertices."),
        click.option("--weights/--no-weights", "weights", default=None,
                     help="A2a: rational patches from the vertex weights (OBJ 'v x y z w', PLY 'weight'); "
                          "default: on when some weight differs from 1."),
        click.option("--attributes", is_flag=True,
                     help="Carry texture coordinates and vertex colours through the construction (into the output "
                          "of a command that writes a .ply or .obj mesh)."),
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
        click.option("--usd-prim", default=None, metavar="PATH",
                     help="USD input: read the UsdGeom.Mesh prims at or below this prim path (one mesh, or the "
                          "meshes of one Xform) instead of every mesh of the stage as one surface."),
        click.option("--usd-local", is_flag=True,
                     help="USD input: the points as each mesh prim stores them, without its local-to-world transform "
                          "(by default the meshes sit where the scene places them)."),
        click.option("--non-manifold", type=click.Choice(NON_MANIFOLD_RULES), default="sheets", show_default=True,
                     help="Edges in more than two faces: cut into manifold sheets that meet along one C0 crease "
                          "(a note names the edges), or refuse the mesh with the one-line error."),
    ]

    def build(weld, no_weld, interpolate_normals, usd_prim, usd_local, **values):
        usd = UsdReadOptions(usd_prim, not usd_local) if usd_prim is not None or usd_local else None
        return InputOptions(weld=weld_tolerance(weld, no_weld), normals=interpolate_normals, usd=usd, **values)

    return grouped(command, "inputs", options, build)


@dataclass(frozen=True)
class PatchFileOptions:
    """How ``--patches`` files are written: IGES units, the IGES B-rep group, merged B-spline pieces (None: the
    format's default, ``io.registry.Format.merged``), IGES and STEP faces cut into strips one span wide
    (``io.patches.merged.cad_patch_set``: Open CASCADE's default mass properties exact; False: whole pieces)."""

    units: str = DEFAULT_UNITS
    group: bool = True
    merge: bool | None = None
    strips: bool = True


def patch_file_options(command):
    """Add --units, --no-group, --merge/--no-merge and --cad-strips/--cad-pieces; the command receives them as one ``patch_files`` argument."""
    options = [
        click.option("--units", type=click.Choice(sorted(UNITS)), default=DEFAULT_UNITS, show_default=True,
                     help="Length unit recorded in an IGES patch file (coordinates are written as they are)."),
        click.option("--no-group", is_flag=True,
                     help="IGES patch file: independent surfaces only, without the B-rep (solid or shell sharing its "
                          "edges) that makes CAD show one object: for readers without IGES B-rep support."),
        click.option("--merge/--no-merge", default=None,
                     help="Merge rectangles of biquadratic patches into B-spline surfaces, which IGES and STEP write "
                          "instead of their patches (CAD opens few large faces) and JSON/NPZ keep beside them "
                          "(key \"merged\", merged_* arrays). Default: IGES and STEP files merged, JSON and NPZ not; "
                          "--merge: every patch file; --no-merge: none (one face per patch)."),
        click.option("--cad-strips/--cad-pieces", default=True, show_default=True,
                     help="IGES and STEP: cut the merged pieces into strips one span wide (the default; about 2x "
                          "the faces of whole pieces), so that Open CASCADE's default mass properties (FreeCAD's "
                          "Shape.Volume, gmsh's getMass) agree with `c1surf measure` to 1e-8; --cad-pieces: one "
                          "face per piece, whose default volume is off by up to 4e-3 (docs/cad-exchange.md)."),
    ]
    return grouped(command, "patch_files", options,
                   lambda units, no_group, merge, cad_strips: PatchFileOptions(units, not no_group, merge, cad_strips))


def weld_tolerance(weld: float | None, no_weld: bool) -> float | None:
    """The welding tolerance of ``--weld``/``--no-weld``: None for no welding, 0 for equal positions."""
    if no_weld and weld is not None:
        raise click.BadParameter("--weld and --no-weld contradict each other: give one of them")
    return None if no_weld else (weld or 0.0)


def grouped(command, name: str, options: list, build):
    """Decorate ``command`` with click ``options`` whose values reach it as one object: ``name=build(**values)``.

    ``build`` takes the options' parameter names; a ValueError it raises is a usage error (exit 2).
    """
    names = [option(lambda: None).__click_params__[0].name for option in options]

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        values = {key: kwargs.pop(key) for key in names}
        try:
            kwargs[name] = build(**values)
        except ValueError as e:
            raise UsageFailure(str(e)) from None
        return command(*args, **kwargs)

    return with_options(wrapper, options)


def with_options(command, options: list):
    """Decorate ``command`` with click ``options``, listed in the order --help shows them."""
    for option in reversed(options):
        command = option(command)
    return command


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
