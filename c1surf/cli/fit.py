"""``c1surf fit``: a dense mesh (scan, sculpt, STL) in, a G1 surface over a coarse control mesh fitted to it out."""
from __future__ import annotations

import contextlib
import dataclasses
import json
import os
from dataclasses import dataclass

import click
import numpy as np

from ..api import FitReport, Surface, SurfaceOptions, cage_options, check_surface, fit_surface, write_fit_cage
from ..evaluation.merge import merge_biquadratic
from ..evaluation.patch_set import surface_patch_set
from ..evaluation.tessellate import patch_adjacency, tessellate_patches
from ..fitting.control.control_mesh import REMESHERS
from ..fitting.options import FitOptions
from ..fitting.scan_fit import ScanFitOptions
from ..io.atomic import atomic_output
from ..io.images.png import write_png
from ..io.meshes.write import write_triangle_mesh
from ..io.patches.merged import cad_patch_set
from ..io.meshes.usd.stage import POINTS_PRIMVAR, USD_SUFFIXES, require_usd
from ..io.registry import CAGE_WRITERS, MESH_WRITERS, PATCH_WRITERS, suffix_list
from ..render.deviation import deviation_picture
from ..render.pictures import colormap, rgb8
from .common import Progress, UsageFailure, echo_notes, friendly_errors, output_suffix, with_formats
from .convert import check_tessellation_size, write_mesh, write_patch_files
from .options import FiniteFloat, grouped, input_options, patch_file_options, surface_options

DEVIATION_SUFFIXES = (".png", ".ply")


@dataclass(frozen=True)
class FitOutputs:
    """The files ``fit`` writes: the tessellated surface, patch files, the JSON report, deviation maps (PNG picture
    or PLY of the scan with per-vertex ``quality`` and colours), the fitted control mesh (an OBJ cage with its
    tags); None or () where not asked."""

    mesh: str | None = None
    patches: tuple = ()
    report: str | None = None
    deviation: tuple = ()
    cage: str | None = None

    def paths(self) -> list:
        return [p for p in (self.mesh, *self.patches, self.report, *self.deviation, self.cage) if p]


def output_options(command):
    """-o, --patches, --report, --deviation, --cage: one ``outputs`` argument (``FitOutputs``)."""
    return grouped(command, "outputs", [
        click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
                     help=f"Tessellated fitted surface; the suffix picks the format ({suffix_list(MESH_WRITERS)})."),
        click.option("--patches", "patches_paths", type=click.Path(dir_okay=False), multiple=True,
                     help=f"The fitted surface's Bezier patches ({suffix_list(PATCH_WRITERS)}; STEP and IGES packed "
                          "into few faces); repeat for several formats."),
        click.option("--report", "report_path", type=click.Path(dir_okay=False), default=None,
                     help="JSON report: deviations both ways (max, RMS, 99th percentile, absolute and relative to the "
                          "diagonal), control mesh, patches, CAD faces, G1 result, rounds and timings."),
        click.option("--deviation", "deviation_paths", type=click.Path(dir_okay=False), multiple=True,
                     help="The scan coloured by its distance to the surface: a .png picture with a colour bar, or a "
                          ".ply of the scan with per-vertex 'quality' (the distance) and colours; repeat for both."),
        click.option("--cage", "cage_path", type=click.Path(dir_okay=False), default=None,
                     help="The fitted control mesh as a SubD cage (moved control points, faces, creases) to edit: "
                          ".usda/.usd/.usdc (USD creaseIndices, which Blender, Houdini and Maya import) or .obj "
                          "(OpenSubdiv 't crease' lines); 'c1surf convert CAGE' with the options its first comment "
                          "(USD: the layer's doc) names gives the fitted surface bit for bit (checked: a note says "
                          "when not)."),
    ], lambda output, patches_paths, report_path, deviation_paths, cage_path: FitOutputs(
        output, tuple(patches_paths), report_path, tuple(deviation_paths), cage_path))


def plan_options(command):
    """--faces, --tolerance, --face-cap, --fairness, --iterations: one ``plan`` argument (``ScanFitOptions``;
    --crease-angle comes with the input options)."""
    return grouped(command, "plan", [
        click.option("--faces", type=click.IntRange(8, None), default=None, metavar="N",
                     help="Control faces of the quad remesh of the scan [default: 3000, at most one per two scan triangles]."),
        click.option("--tolerance", type=FiniteFloat(0.0, 1.0, min_open=True, max_open=True), default=None, metavar="T",
                     help="Grow the control mesh until every scan vertex is within T times the bounding-box "
                          "diagonal of the surface (e.g. 0.001), or --face-cap is reached (a note says so)."),
        click.option("--face-cap", type=click.IntRange(8, 60000), default=6000, show_default=True,
                     help="The most control faces --tolerance may ask for."),
        click.option("--fairness", type=FiniteFloat(0.0), default=FitOptions.fairness, show_default=True,
                     help="Starting weight of the umbrella fairness term; it then grows while the scan stays "
                          "within 10 % of the closest fit's distances or within RMS 2.8e-4, p99 9.8e-4, max 2.94e-3 "
                          "of the diagonal (and --tolerance): the smoothest surface within that, not the closest; 0: "
                          "no fairness, the closest fit (docs/fit.md)."),
        click.option("--iterations", type=click.IntRange(1, 100), default=FitOptions.max_iterations, show_default=True,
                     help="Most rounds of footpoints and least squares (they stop earlier when the deviation stops "
                          "improving)."),
        click.option("--remesher", type=click.Choice(REMESHERS), default="auto", show_default=True,
                     help="The control mesh: 'quadriflow' QuadriFlow's coarse quads split in four (fewest irregular "
                          "vertices, so fewest CAD faces; thin parts can go), 'instant' Instant Meshes' field-aligned "
                          "quads (few CAD faces; thin parts and handles can go), 'decimate' the scan decimated with its "
                          "topology kept, paired and split into quads (finer where it bends, more CAD faces), 'auto' "
                          "the first of QuadriFlow (with --crease-angle: only where every line asked for is sharper "
                          "than its fixed 60 degrees), Instant Meshes and 'decimate' that keeps the scan's components, "
                          "Euler characteristic and rims and covers the scan (every scan vertex within about a control "
                          "edge, every rim matched); 'simplify' (opt-in) the scan turned into quads and simplified by "
                          "local operations (docs/layout.md)."),
    ], lambda faces, tolerance, face_cap, fairness, iterations, remesher: ScanFitOptions(
        faces, tolerance, face_cap, None, FitOptions(fairness=fairness, max_iterations=iterations),
        remesher).check())


@click.command()
@click.argument("scan_path", metavar="SCAN", type=click.Path(dir_okay=False))
@output_options
@click.option("-r", "--resolution", type=click.IntRange(2, None), default=8, show_default=True,
              help="Samples per patch side of the -o tessellation.")
@plan_options
@click.option("--control-mesh", "control_path", type=click.Path(dir_okay=False), default=None,
              help="Fit this control mesh (any polygons; its creases, corners and holes honoured) instead of "
                   "remeshing the scan.")
@patch_file_options
@surface_options(refinements="auto")
@input_options
@click.option("-q", "--quiet", is_flag=True, help="No progress messages (they only appear on a terminal anyway).")
@friendly_errors
@with_formats
def fit(scan_path, outputs, resolution, plan, control_path, patch_files, surface, inputs, quiet):
    """Fit a G1 surface over a coarse control mesh to the dense mesh SCAN ({mesh_inputs}).

    A quad remesh of the scan (Instant Meshes), or --control-mesh, is the
    control mesh; the paper's construction over it is fitted to the scan by
    sparse least squares (footpoints on the exact patches, point-to-plane with a
    point-to-point share and a fairness term), so the result is G1 by
    construction (C0 along --crease-angle's feature lines). Prints the
    deviation both ways and writes the outputs asked for.

    The defaults aim for a scan-to-surface distance of RMS 3e-4, 99th
    percentile 1e-3 and max 3e-3 of the bounding-box diagonal; when a scan
    does not reach it at the default face count, a note says what was reached.
    """
    if not outputs.paths():
        raise UsageFailure("nothing to write: give -o MESH, --patches FILE, --report FIT.json, --deviation "
                           "DEV.png and/or --cage CAGE.obj")
    suffixes = check_outputs(outputs)
    progress = Progress(quiet)
    plan = dataclasses.replace(plan, crease_angle=inputs.crease_angle)
    progress.phase(f"reading {scan_path}")
    fitted, report = fit_surface(scan_path, plan, surface, control_path=control_path, input_options=inputs,
                                 progress=progress.advance)
    echo_notes(report.notes, quiet)
    progress.phase("checking the fitted surface")
    document = fit_document(fitted, report, patch_files)
    for line in summary_lines(document):
        click.echo(line)
    notes = write_outputs(scan_path, outputs, suffixes, (fitted, report, document), resolution, patch_files, progress,
                          control_path)
    progress.done()
    echo_notes(notes, quiet)


def check_outputs(outputs: FitOutputs) -> dict:
    """{path: suffix} of every output; usage errors for suffixes no writer takes and names given twice."""
    suffixes = {}
    if outputs.mesh:
        suffixes[outputs.mesh] = output_suffix(outputs.mesh, MESH_WRITERS, "--output")
    for path in outputs.patches:
        suffixes[path] = output_suffix(path, PATCH_WRITERS, "--patches")
    if outputs.report:
        suffixes[outputs.report] = output_suffix(outputs.report, {".json": None}, "--report")
    for path in outputs.deviation:
        suffixes[path] = output_suffix(path, dict.fromkeys(DEVIATION_SUFFIXES), "--deviation")
    if outputs.cage:
        suffixes[outputs.cage] = output_suffix(outputs.cage, CAGE_WRITERS, "--cage")
    require_usd([p for p, suffix in suffixes.items() if suffix in USD_SUFFIXES])  # before the fit, not after
    paths = [os.path.abspath(p) for p in outputs.paths()]
    if len(set(paths)) != len(paths):
        raise UsageFailure("-o, --patches, --report, --deviation and --cage must name different files")
    return suffixes


def cad_face_count(surface: Surface, patch_files) -> int:
    """The faces of the STEP/IGES file: merged biquadratic rectangles (cut into strips one span wide unless
    --cad-pieces, ``io.patches.merged.cad_patch_set``), then every other patch."""
    if patch_files.merge is False:
        return surface.n_patches
    packed = dataclasses.replace(surface_patch_set(surface, ""), merged=merge_biquadratic(surface))
    packed = cad_patch_set(packed) if patch_files.strips else packed
    covered = sum(int(np.size(piece.patches)) for piece in packed.merged)
    return len(packed.merged) + surface.n_patches - covered


def fit_document(surface: Surface, report: FitReport, patch_files) -> dict:
    """The JSON report of ``fit`` (``--report``; docs/fit.md lists its keys)."""
    result = report.fit
    g1 = check_surface(surface)
    deviation = result.deviation
    return {
        "scan": {"file": report.path, "vertices": int(report.scan_points.shape[0]),
                 "triangles": int(report.scan_triangles.shape[0]), "diagonal": float(deviation.diagonal)},
        "control_mesh": {"faces": result.control.n_faces, "vertices": int(result.control.points.shape[0]),
                         "crease_edges": int(result.control.crease_edges.shape[0]), **result.control.report},
        "patches": {"biquadratic": int(surface.quad_frames.shape[0]), "bicubic": int(surface.cubic_frames.shape[0]),
                    "total": surface.n_patches, "refinements": int(surface.refinements)},
        "cad_faces": cad_face_count(surface, patch_files),
        "scan_to_surface": deviation.scan_stats, "surface_to_scan": deviation.surface_stats,
        "surface_over_holes": deviation.over_holes_fraction,
        "g1": {"max_normal_jump": float(g1.max_normal_jump), "max_gap": float(g1.relative_gap),
               "is_g1": bool(g1.is_g1(1e-9, 1e-9))},
        "fit": {"iterations": result.fit.iterations, "stopped": result.fit.stopped, "solver": result.fit.solver,
                "fairness": result.fit.fairness, "history": result.fit.history},
        "topology": result.topology,
        "rounds": result.rounds, "timings": {**result.timings, **result.fit.timings}, "notes": report.notes,
    }


def summary_lines(document: dict) -> list[str]:
    """What ``fit`` prints: sizes, the deviation both ways (relative to the diagonal), the G1 result."""
    a, b = document["scan_to_surface"], document["surface_to_scan"]
    lines = [f"control mesh:     {document['control_mesh']['faces']} faces",
             f"patches:          {document['patches']['total']} ({document['patches']['refinements']} Doo-Sabin "
             f"steps), {document['cad_faces']} CAD faces packed",
             f"scan to surface:  RMS {a['relative_rms']:.3g}, 99% {a['relative_p99']:.3g}, max {a['relative_max']:.3g} "
             "of the diagonal",
             f"surface to scan:  RMS {b['relative_rms']:.3g}, 99% {b['relative_p99']:.3g}, max {b['relative_max']:.3g} "
             "of the diagonal" + (f" (where the scan has data: {document['surface_over_holes']:.1%} of the surface "
                                  "lies past its rims or over its holes)" if document["surface_over_holes"] else ""),
             f"G1: {'yes' if document['g1']['is_g1'] else 'NO'} (max normal jump {document['g1']['max_normal_jump']:.3e} "
             "rad)"]
    topology = document.get("topology")
    if topology:
        scan, surface = (topology[k] for k in ("scan", "surface"))
        lines.append(f"topology:         {_counts_text(surface)}" + (" (the scan's)" if not topology["differences"] else
                                                                      f"; the scan: {_counts_text(scan)}"))
        read = topology.get("scan_as_read")
        if read and any(read[k] != scan[k] for k in ("components", "euler_characteristic", "rims")):
            lines.append(f"scan as read:     {_counts_text(read)} ({read['pinched_vertices']} pinched vertices, "
                         f"{read['non_manifold_edges']} non-manifold edges; above: as a manifold)")
    return lines


def _counts_text(counts: dict) -> str:
    return (f"{counts['components']} component{'s' * (counts['components'] != 1)}, Euler characteristic "
            f"{counts['euler_characteristic']}, {counts['rims']} rim{'s' * (counts['rims'] != 1)}")


def write_outputs(scan_path, outputs: FitOutputs, suffixes: dict, fitted: tuple, resolution: int, patch_files,
                  progress: Progress, control_path=None) -> list:
    """Every output asked for; ``fitted``: (Surface, FitReport, the report's document). All appear together, or none.
    Returns the notes of the writing (a cage that does not rebuild the fit bit for bit). No output may overwrite
    the scan or ``control_path`` (``--control-mesh``: a cage fitted again is written under another name)."""
    surface, report, document = fitted
    notes = []
    with contextlib.ExitStack() as files:
        def target(path):
            progress.phase(f"writing {path}")
            return files.enter_context(atomic_output(path, inputs=[p for p in (scan_path, control_path) if p]))

        if outputs.cage:
            notes = write_fit_cage(target(outputs.cage), surface, report, cage_comments(surface, outputs.cage),
                                   outputs.cage)
            document["notes"] = document["notes"] + notes
        adjacency = patch_adjacency(surface.refined, surface.frames)
        if outputs.mesh:
            check_tessellation_size(surface.n_patches, resolution, False)
            tess = tessellate_patches([surface.biquadratic, surface.bicubic], adjacency, resolution,
                                      surface.patch_weights)
            write_mesh(target(outputs.mesh), suffixes[outputs.mesh], tess, {}, None, False)
        if outputs.patches:
            merged = {suffix: None for suffix in suffixes.values()}
            wanted = [s for p, s in suffixes.items() if p in outputs.patches]
            if any(patch_files.merge if patch_files.merge is not None else PATCH_WRITERS[s].merged for s in wanted):
                from .convert import merged_pieces

                merged = merged_pieces(surface, wanted, patch_files.merge)
            write_patch_files([(p, suffixes[p]) for p in outputs.patches], surface, scan_path,
                              {"adjacency": adjacency, "units": patch_files.units, "group": patch_files.group,
                               "strips": patch_files.strips},
                              progress, merged)
        if outputs.report:
            with open(target(outputs.report), "w") as f:
                json.dump(document, f, indent=1, default=_json_number)
        for path in outputs.deviation:
            write_deviation(target(path), suffixes[path], report)
    return notes


def convert_flags(surface: Surface) -> str:
    """The ``convert`` options that build ``surface`` again from its cage (``api.cage_options``), as text."""
    options, inputs = cage_options(surface)
    default = SurfaceOptions()
    flags = [f"--refinements {options.refinements}"]
    flags += [f"--{name.replace('_', '-')} {getattr(options, name)!r}".replace("'", "")
              for name in ("blend", "alpha", "beta", "tangent_rule", "triangles")
              if getattr(options, name) != getattr(default, name)]
    flags += ["--interpolate-vertices"] if options.interpolate_vertices else []
    flags += ["--g1-creases"] if not inputs.exact_creases and not options.interpolate_vertices else []
    return " ".join(flags)


def cage_comments(surface: Surface, path: str) -> list[str]:
    """The comment lines that open a ``--cage`` file: what it is and the command that rebuilds the fit."""
    tags = ("tags as OpenSubdiv writes them (t crease 2/1/0 a b sharpness, indices from 0)" if path.lower().endswith(
        ".obj") else "creases as USD creaseIndices, creaseLengths 2 and creaseSharpnesses, one crease an edge; float64 "
                     f"points in primvars:{POINTS_PRIMVAR}")
    return [f"c1surf fit cage: the fitted control mesh; c1surf convert {os.path.basename(path)} "
            f"{convert_flags(surface)} gives the fitted surface bit for bit",
            f"{tags}; sharpness 10: infinitely sharp"]


def write_deviation(path, suffix: str, report: FitReport) -> None:
    """The scan coloured by its distance to the surface: a picture (.png) or the scan as PLY with ``quality``."""
    distance = report.fit.deviation.scan_to_surface
    diagonal = report.fit.deviation.diagonal
    if suffix == ".png":
        write_png(path, deviation_picture(report.scan_points, report.scan_triangles, distance, diagonal))
        return
    hi = float(np.percentile(distance, 99)) or 1.0
    colours = rgb8(colormap(distance, 0.0, hi, "viridis"))
    write_triangle_mesh(path, report.scan_points, report.scan_triangles, suffix=".ply",
                        vertex_properties={"quality": distance, "relative": distance / diagonal}, vertex_colors=colours)


def _json_number(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON")

