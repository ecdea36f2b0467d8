"""``c1surf inspect``: what c1surf sees in a mesh file and what ``convert`` will do with it, without converting.

The report is one dict (``inspection``), printed as text or, with ``--json``, as
one JSON object whose keys docs/cli.md documents ("Inspecting a mesh"). It runs
the same steps ``convert`` runs up to the topology (the reader, the repairs of
``mesh.repair``, ``construction.topology.build_topology``: integers only) and
stops before any geometry.
"""
from __future__ import annotations

import dataclasses
import json
import math

import click
import numpy as np

from ...api import prepared_input, repair_notes, seam_notes, topology_error
from ...construction.cell_memory import cell_work_bytes
from ...construction.topology import build_topology
from ...errors import ResourceRefusal
from ...evaluation.adjacency import patch_adjacency
from ...io.errors import MeshInputError
from ...io.patches.formats import patch_writer_memory
from ...io.meshes.mesh_file import collapse_repeated_corners
from ...io.meshes.read import read_mesh
from ...io.registry import MESH_WRITERS
from ...mesh.errors import TopologyError
from ...mesh.repair import prepare_topology
from ...mesh.statistics import degenerate_faces, histogram, mesh_statistics
from ...resources import tessellation_bytes
from ..common import friendly_errors, with_formats
from ..convert import check_tessellation_size
from ..options import input_options, surface_options

PLY_HEADER_BYTES = 250  # about: the header of convert's binary PLY (xyz and normals as double)
PLY_VERTEX_BYTES = 6 * 8  # x y z nx ny nz, double
PLY_TRIANGLE_BYTES = 1 + 3 * 4  # list uchar int vertex_indices
REPAIR_KEYS = ("flipped_faces", "split_vertices", "unused_vertices", "components", "boundary_edges", "non_orientable")


@click.command()
@click.argument("input_path", metavar="INPUT", type=click.Path(dir_okay=False))
@click.option("-r", "--resolution", type=click.IntRange(2, None), default=8, show_default=True,
              help="The --resolution of the conversion the output sizes are estimated for.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (keys: docs/cli.md, \"Inspecting a mesh\").")
@surface_options
@input_options
@friendly_errors
@with_formats
def inspect(input_path, resolution, as_json, surface, inputs):
    """Report what c1surf sees in the mesh INPUT ({mesh_inputs}) and what `convert` would do with it.

    Counts (faces by size, valences, boundary loops, components with their
    Euler characteristic and genus, non-manifold edges, pinched, valence-2 and
    unused vertices, degenerate faces, sharp-feature tags), the repairs the
    conversion makes, whether it refuses the mesh and why, the patch counts and
    the output sizes at --resolution. The surface and input options are
    those of the conversion planned (the patch counts depend on --refinements,
    the C0 seams on --exact-creases/--g1-creases). Exits 0 for a refused mesh
    too; 1 only when the file cannot be read.
    """
    report = inspection(input_path, resolution, surface, inputs)
    if as_json:
        click.echo(json.dumps(report, indent=2))
    else:
        for line in text_lines(report):
            click.echo(line)


def inspection(path, resolution: int, surface=None, inputs=None) -> dict:
    """The report of ``c1surf inspect`` as a JSON-ready dict (keys: docs/cli.md, "Inspecting a mesh").

    ``surface``, ``inputs``: the SurfaceOptions and InputOptions of the conversion planned (defaults: convert's).
    Raises MeshInputError (through ``read_mesh``) only for a file that cannot be read at all.
    """
    raw = read_mesh(path, keep_degenerate=True)
    degenerate = degenerate_faces(raw.face_sizes, raw.face_vertices)
    mesh, refusal = converted_mesh(raw, degenerate.size > 0)
    stats = mesh_statistics(*usable_faces(mesh.face_sizes, mesh.face_vertices), mesh.n_vertices)
    topology, repairs, built, data, exact_creases = None, None, mesh, None, False
    if refusal is None:
        try:  # welded and with its valence-2 vertices dissolved, as convert builds it (api.prepared_input)
            prepared = prepared_input(path, surface, inputs)
            built, data, exact_creases = prepared.mesh, prepared.data, prepared.options.exact_creases
        except MeshInputError as e:
            refusal = str(e)
    if refusal is None:
        topology, repairs, refusal = plan(built, prepared.options.refinements, data.features, exact_creases)
    outputs = None
    if topology is not None:
        outputs = output_sizes(topology, resolution)
        # the formats of MESH_WRITERS.streamed() are written by blocks (not limited by memory); the others are held whole first
        outputs["in_memory_refusal"] = None
        try:
            check_tessellation_size(outputs["patches"], resolution, force=False)
        except ResourceRefusal as e:  # the memory guard of an in-memory conversion
            outputs["in_memory_refusal"] = e.message
    return {
        "file": str(path),
        **statistics_dict(stats),
        # every face, also one that collapsing left with fewer than 3 corners (the topology counts leave it out)
        "faces": mesh.n_faces, "face_sizes": _histogram_dict(histogram(mesh.face_sizes)),
        "degenerate_faces": int(degenerate.size),
        "collapsed_corners": int(mesh.collapsed_corners),
        "tags": tags_dict(mesh.tags),
        "repairs": repairs,
        "notes": planned_notes(topology, built, data, exact_creases),
        "refused": refusal,
        "patches": None if topology is None else patch_counts(topology),
        "output": outputs,
    }


def planned_notes(topology, built, data, exact_creases: bool) -> list[str]:
    """The notes ``convert`` would print: the sharp features', the C0 seams' (``--exact-creases``), the repairs'."""
    if topology is None:
        return [] if data is None else list(data.feature_notes)
    notes = repair_notes(topology, built, data)  # the feature notes first
    at = len(data.feature_notes)
    notes[at:at] = seam_notes(exact_creases, data.features, topology)
    return notes


def converted_mesh(raw, degenerate: bool):
    """(MeshFile as ``convert`` reads it, refusal or None): repeated corners collapsed as the readers do.

    A file with a degenerate face is read again as ``convert`` reads it, so a refusal
    is the reader's own one line; the statistics then describe the collapsed faces.
    """
    if degenerate:
        try:
            return read_mesh(raw.path), None
        except MeshInputError as e:
            sizes, vertices, keep = collapse_repeated_corners(raw.face_sizes, raw.face_vertices)
            collapsed = int(keep.size - keep.sum())
            return dataclasses.replace(raw, face_sizes=sizes, face_vertices=vertices, collapsed_corners=collapsed), str(e)
    return raw, None


def usable_faces(face_sizes: np.ndarray, face_vertices: np.ndarray):
    """(face_sizes, face_vertices) without the faces of fewer than 3 corners (left by collapsing a refused file)."""
    keep = face_sizes >= 3
    if keep.all():
        return face_sizes, face_vertices
    return face_sizes[keep], face_vertices[np.repeat(keep, face_sizes)]


def plan(mesh, refinements, features=None, exact_creases: bool = False):
    """(SurfaceTopology or None, repairs dict or None, refusal or None) of what ``convert`` would build.

    The refusal is the one line ``convert`` prints (without ``c1surf: error:``); ``features``:
    the sharp features (hole faces have no patches).
    """
    try:
        topology = build_topology(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices, refinements,
                                  features=features, exact_creases=exact_creases)
    except TopologyError as e:
        return None, repairs_before(mesh), str(topology_error(e, mesh))
    return topology, {key: topology.repairs[key] for key in REPAIR_KEYS}, None


def repairs_before(mesh):
    """The repairs of a mesh whose topology is refused after them (valence 2, refinements), or None."""
    try:
        _, _, report = prepare_topology(mesh.face_sizes, mesh.face_vertices, mesh.n_vertices)
    except TopologyError:  # refused before any repair (an edge in more than two faces)
        return None
    return {key: report[key] for key in REPAIR_KEYS}


def patch_counts(topology) -> dict:
    """Biquadratic and bicubic patches of the topology, and the refinement steps it took."""
    quad, cubic = int(topology.quad_frames.shape[0]), int(topology.cubic_frames.shape[0])
    return {"biquadratic": quad, "bicubic": cubic, "total": quad + cubic, "refinements": int(topology.refinements)}


def output_sizes(topology, resolution: int) -> dict:
    """Sizes of ``convert``'s tessellation at ``resolution``: exact counts, approximate bytes.

    Each patch is an N x N grid welded along shared sides and corners
    (``evaluation.adjacency``), so the vertices are P (N-2)^2 + sides (N-2) +
    corners; the triangles 2 P (N-1)^2.
    """
    n = int(resolution)
    adjacency = patch_adjacency(topology.refined, topology.frames)
    patches = adjacency.n_patches
    vertices = patches * (n - 2) ** 2 + adjacency.n_edges * (n - 2) + adjacency.n_corners
    triangles = 2 * patches * (n - 1) ** 2
    return {
        "resolution": n, "patches": patches, "vertices": int(vertices), "triangles": int(triangles),
        "ply_bytes": int(PLY_HEADER_BYTES + PLY_VERTEX_BYTES * vertices + PLY_TRIANGLE_BYTES * triangles),
        "memory_bytes": int(tessellation_bytes(patches, n) + cell_work_bytes(topology)),
        "cad_memory_bytes": {suffix: patch_writer_memory(suffix, patches) for suffix in (".igs", ".step")},
    }


def statistics_dict(stats) -> dict:
    """The counts of a ``mesh.statistics.MeshStatistics`` with JSON keys (histograms: {"value": count})."""
    hist = _histogram_dict
    c = stats.components
    components = [
        {"vertices": int(c.vertices[i]), "edges": int(c.edges[i]), "faces": int(c.faces[i]),
         "boundary_edges": int(c.boundary_edges[i]), "boundary_loops": int(c.boundary_loops[i]),
         "non_manifold_edges": int(c.non_manifold_edges[i]), "euler_characteristic": int(c.euler_characteristic[i]),
         "orientable": bool(c.orientable[i]), "genus": _number(c.genus[i]),
         "nonorientable_genus": _number(c.nonorientable_genus[i])}
        for i in range(c.vertices.size)
    ]
    return {
        "vertices": stats.n_vertices, "faces": stats.n_faces, "edges": stats.n_edges,
        "face_sizes": hist(stats.face_sizes),
        "valences": {"interior": hist(stats.interior_valences), "boundary": hist(stats.boundary_valences)},
        "unused_vertices": stats.unused_vertices, "boundary_edges": stats.boundary_edges,
        "boundary_loops": stats.boundary_loops, "non_manifold_edges": stats.non_manifold_edges,
        "pinched_vertices": stats.pinched_vertices, "valence2_interior_vertices": stats.valence2_interior_vertices,
        "euler_characteristic": int(c.euler_characteristic.sum()), "components": components,
    }


def _histogram_dict(rows: np.ndarray) -> dict:
    """(k, 2) rows (value, count) as {"value": count} (JSON keys are strings)."""
    return {str(int(k)): int(v) for k, v in rows}


def _number(x: float):
    """An integer-valued float as int, NaN as None (JSON null)."""
    return None if math.isnan(x) else int(x)


def tags_dict(tags) -> dict:
    """Counts of the sharp-feature tags by kind (``io.meshes.tags.record.SharpTags``)."""
    other: dict[str, int] = {}
    for name, _ in tags.other:
        other[name] = other.get(name, 0) + 1
    return {"crease_edges": len(tags.crease_edges), "corner_vertices": len(tags.corner_vertices),
            "hole_faces": len(tags.hole_faces), "interpolate_boundary": tags.interpolate_boundary,
            "other": other, "summary": tags.summary()}


def text_lines(report: dict) -> list[str]:
    """The report as aligned ``name  value`` lines."""
    rows = [("vertices", f"{report['vertices']} ({report['unused_vertices']} unused)"),
            ("faces", f"{report['faces']}, by size {_hist(report['face_sizes'])}"),
            ("edges", f"{report['edges']} ({report['boundary_edges']} boundary, "
                      f"{report['non_manifold_edges']} in more than two faces)"),
            ("valences", f"interior {_hist(report['valences']['interior'])}; "
                         f"boundary {_hist(report['valences']['boundary'])}"),
            ("boundary loops", str(report["boundary_loops"])),
            ("components", _components(report["components"])),
            ("pinched vertices", str(report["pinched_vertices"])),
            ("valence-2 interior", str(report["valence2_interior_vertices"])),
            ("degenerate faces", f"{report['degenerate_faces']} ({report['collapsed_corners']} repeated corners dropped)"),
            ("sharp tags", report["tags"]["summary"] or "none"),
            ("repairs", _repairs(report["repairs"])),
            ("conversion", f"refused: {report['refused']}" if report["refused"] else "will convert")]
    if report["patches"]:
        p = report["patches"]
        rows.append(("patches", f"{p['total']} ({p['biquadratic']} biquadratic + {p['bicubic']} bicubic, "
                                f"{p['refinements']} refinements)"))
    if report["output"]:
        o = report["output"]
        rows.append((f"output at -r {o['resolution']}", f"{o['vertices']} vertices, {o['triangles']} triangles, "
                                                         f"PLY about {_bytes(o['ply_bytes'])}, "
                                                         f"memory about {_bytes(o['memory_bytes'])}"))
        rows.append(("CAD patch files", ", ".join(f"{s} writer about {_bytes(b)}" for s, b in o["cad_memory_bytes"].items())))
        if o["in_memory_refusal"]:
            streamed = ", ".join(MESH_WRITERS.streamed())
            rows.append(("held in memory", f"refused (plain {streamed} outputs stream): {o['in_memory_refusal']}"))
    notes = [f"  note: {note}" for note in report["notes"]]
    return [report["file"]] + [f"  {name:<20}{value}" for name, value in rows] + notes


def _hist(counts: dict) -> str:
    return " ".join(f"{k}:{v}" for k, v in counts.items()) or "-"


def _components(components: list, shown: int = 6) -> str:
    """``2: (V 8, E 12, F 6, chi 2, genus 0, closed), ...``."""
    parts = []
    for c in components[:shown]:
        if c["genus"] is not None:
            kind = f"genus {c['genus']}"
        elif not c["orientable"] and c["nonorientable_genus"] is not None:
            kind = f"non-orientable, {c['nonorientable_genus']} cross-caps"
        else:
            kind = "not a surface (edges in more than two faces)"
        ends = f"{c['boundary_loops']} boundary loops" if c["boundary_loops"] else "closed"
        parts.append(f"(V {c['vertices']}, E {c['edges']}, F {c['faces']}, chi {c['euler_characteristic']}, {kind}, {ends})")
    more = ", ..." if len(components) > shown else ""
    return f"{len(components)}: " + ", ".join(parts) + more


def _repairs(repairs) -> str:
    if repairs is None:
        return "unknown (refused before the repairs)"
    done = [f"{key.replace('_', ' ')} {value}" for key, value in repairs.items()
            if key not in ("components", "non_orientable") and value]
    if repairs["non_orientable"]:
        done.append("orientation double cover")
    return ", ".join(done) or "none"


def _bytes(n: int) -> str:
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{n} B"
