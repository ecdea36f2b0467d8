"""What every c1surf command shares: one-line errors, progress (click's bars) on a terminal."""
from __future__ import annotations

import functools
import sys
import time
import traceback

import click
import numpy as np

from ..construction.features import INFINITELY_SHARP
from ..mesh.errors import TopologyError
from ..io.errors import C1SurfFileError
from ..io.registry import UnsupportedFormat, suffix_of


class Failure(click.ClickException):
    """A user-facing failure: printed as ``c1surf: error: ...``, exit status 1."""

    exit_code = 1

    def show(self, file=None):
        click.echo(f"c1surf: error: {self.message}", err=True)


def topology_failure(error: TopologyError, mesh_file) -> Failure:
    """Turn a core TopologyError into ``FILE:LINE: message`` using the file's face lines."""
    obj = str(mesh_file.path).lower().endswith(".obj")
    message = error.describe(vertex_base=1 if obj else 0)
    if obj and error.vertices:
        message += " (vertex numbers as in the OBJ file, from 1)"
    lines = []
    if mesh_file.face_lines is not None and error.faces.size:
        lines = sorted({int(mesh_file.face_lines[f]) for f in error.faces if 0 <= f < mesh_file.n_faces})
    where = f"{mesh_file.path}:{lines[0]}" if lines else f"{mesh_file.path}"
    if len(lines) > 1:
        shown = ", ".join(str(x) for x in lines[:8]) + (", ..." if len(lines) > 8 else "")
        message += f"; faces on lines {shown}"
    elif error.faces.size and not lines:
        message += f"; faces {', '.join(str(int(f)) for f in error.faces[:8])} (0-based)"
    return Failure(f"{where}: {message}")


def file_notes(mesh_file) -> list[str]:
    """Notes on what reading ``mesh_file`` ignored (``MeshFile.reader_notes``: OBJ ``l``/``p`` records, ...)."""
    return list(getattr(mesh_file, "reader_notes", None) or [])


def repair_notes(surface, mesh_file, data=None) -> list[str]:
    """One-line notes on what c1surf changed or ignored to make the input usable (the sharp features first).

    ``data``: the ``io.meshes.surface_data.SurfaceData`` the surface was built from (its
    ``feature_notes`` say which tags were honoured and which not), or None.
    """
    r = getattr(surface, "repairs", {}) or {}
    notes = list(getattr(data, "feature_notes", [])) + crease_notes(surface) + file_notes(mesh_file)
    if getattr(mesh_file, "collapsed_corners", 0):
        notes.append(f"dropped {mesh_file.collapsed_corners} repeated corners (zero-length edges such as 'f a b c c')")
    notes += weld_notes(getattr(mesh_file, "weld", None)) + dissolve_notes(mesh_file)
    if r.get("flipped_faces"):
        notes.append(f"flipped {r['flipped_faces']} faces to orient each connected component consistently")
    if r.get("non_orientable"):
        notes.append("the surface is not orientable: built on its orientation double cover; normals flip across a seam "
                     "(use `c1surf check --unoriented`)")
    if r.get("split_vertices"):
        notes.append(f"split {r['split_vertices']} pinched vertices into one vertex per fan of faces")
    # welding leaves the merged vertices unused: only the file's own unused vertices are news
    unused = (r.get("unused_vertices", 0) - getattr(getattr(mesh_file, "weld", None), "welded_vertices", 0)
              - len(getattr(mesh_file, "dissolved_vertices", ())))
    if unused > 0:
        notes.append(f"ignored {unused} vertices used by no face")
    if r.get("boundary_edges"):
        notes.append(f"open mesh: {r['boundary_edges']} boundary edges, closed for the construction by a ghost layer")
    return notes


def crease_notes(surface) -> list[str]:
    """With ``--exact-creases``: how many infinitely sharp crease edges became C0 seams, and which did not, why."""
    options = getattr(surface, "options", None)
    return seam_notes(getattr(options, "exact_creases", False), getattr(surface, "features", None),
                      getattr(surface, "topology", None))


def seam_notes(exact_creases: bool, features, topology) -> list[str]:
    """``crease_notes`` of a surface's parts: the option, its SharpFeatures and its SurfaceTopology."""
    if not exact_creases or features is None or topology is None:
        return []
    # by the vertices' identities (copies of one vertex in non-manifold sheets are one); an edge tagged twice counts once
    name = (lambda v: v) if features.vertex_identity is None else (lambda v: features.vertex_identity[v])
    sharp = int(np.unique(np.sort(name(features.crease_edges[features.crease_sharpness >= INFINITELY_SHARP]), axis=1),
                          axis=0).shape[0])
    corners = np.unique(name(features.corner_vertices[features.corner_sharpness >= INFINITELY_SHARP]))
    if sharp == 0 and corners.size == 0:
        return []
    sheets = topology.crease_sheets
    cut = 0 if sheets is None else len(sheets.cut_edges)
    kept = sharp - cut
    notes = [f"C0 creases: {cut} of {sharp} infinitely sharp crease edges are C0 seams"] if cut else []
    lone = np.setdiff1d(corners, np.zeros(0, dtype=np.int64) if sheets is None else sheets.cut_edges.ravel())
    if lone.size:
        notes.append(f"{lone.size} infinitely sharp corners are not on a C0 seam and stay the sharpest G1 corner "
                     f"(vertices {', '.join(map(str, lone[:8].tolist()))}{' ...' if lone.size > 8 else ''}, 0-based)")
    darts = 0 if sheets is None or sheets.dart_edges is None else len(sheets.dart_edges)
    if darts:
        notes.append(f"{darts} infinitely sharp crease edges lie on crease lines that end inside the surface (darts): "
                     "they stay the sharpest G1 crease, which fades out at the dart as in OpenSubdiv; the rest of "
                     "their crease is a C0 seam")
        kept -= darts
    if kept:
        named = [] if sheets is None else sheets.inexact_vertices.tolist()
        at = f" (at vertices {', '.join(map(str, named[:8]))}{' ...' if len(named) > 8 else ''}, 0-based)" if named else ""
        notes.append(f"{kept} infinitely sharp crease edges stay the sharpest G1 crease: their crease lines have a "
                     f"vertex where a C0 seam is not exact yet{at}: a crease end inside the surface, the mesh boundary, "
                     "three or more faces on one side, or a corner with a sector of several faces (docs/sharp-features.md)")
    return notes


def dissolve_notes(mesh_file) -> list[str]:
    """The notes on repeated faces dropped, crease sectors merged (``mesh.creases.sectors``) and interior valence-2
    vertices dissolved (``mesh.valence_two``)."""
    notes = []
    if getattr(mesh_file, "repeated_faces", 0):
        notes.append(f"dropped {mesh_file.repeated_faces} faces that repeat an earlier face (the same cycle again, or "
                     "its reversal where the two make a closed two-sided card)")
    sheets = getattr(mesh_file, "non_manifold_edges", None)
    if sheets is not None:
        shown = ", ".join(f"{a}-{b}" for a, b in sheets[:6].tolist()) + (", ..." if len(sheets) > 6 else "")
        seams = getattr(mesh_file, "non_manifold_seams", len(sheets))
        touching = f"; {len(sheets) - seams} only touch there (every sheet holds them in two faces)" if seams < len(sheets) else ""
        notes.append(f"C0 creases: cut {len(sheets)} edges in more than two faces (vertices {shown}, 0-based) into "
                     f"manifold sheets: {seams} are a C0 crease the sheets meet along{touching} (docs/sharp-features.md)")
    merge = getattr(mesh_file, "sector_merge", None)
    if merge is not None:
        faces, polygons, at, lost = merge
        shown = ", ".join(str(int(v)) for v in at[:8]) + (", ..." if len(at) > 8 else "")
        notes.append(f"C0 creases: merged {faces} faces into {polygons} polygons around {len(at)} crease vertices "
                     f"(vertices {shown}, 0-based), so that every crease sector has at most two faces (one at a "
                     "corner), which the exact C0 crease needs (docs/sharp-features.md)")
        if len(lost):
            edges = ", ".join(f"{a}-{b}" for a, b in lost[:6].tolist()) + (", ..." if len(lost) > 6 else "")
            notes.append(f"C0 creases: {len(lost)} crease edges that start a crease line ending inside the surface were "
                         f"merged away inside a corner's sector (edges {edges}, 0-based): not used (the rest of "
                         "each line stays the sharpest G1 crease)")
    dissolved = getattr(mesh_file, "dissolved_vertices", ())
    if not len(dissolved):
        return notes
    base = 1 if str(mesh_file.path).lower().endswith(".obj") else 0
    shown = ", ".join(str(int(v) + base) for v in dissolved[:8]) + (", ..." if len(dissolved) > 8 else "")
    which = "as in the OBJ file, from 1" if base else "from 0"
    return notes + [f"dissolved {len(dissolved)} interior vertices of valence 2 into the edges they split (vertices "
                    f"{shown}, {which}): a 2-sided cell has no A3 filling; their faces lost that corner"]


def weld_notes(weld) -> list[str]:
    """The notes of a ``io.meshes.mesh_file.WeldReport`` (or None: the mesh was not welded)."""
    if weld is None:
        return []
    where = "at the same position" if weld.tolerance == 0 else f"within {weld.tolerance:g} of the bounding-box diagonal"
    notes = []
    if weld.welded_vertices:
        notes.append(f"welded {weld.welded_vertices} vertices {where} into the vertex they coincide with "
                     "(--no-weld keeps them)")
    if weld.unwelded_vertices:
        notes.append(f"kept {weld.unwelded_vertices} positions as several vertices: welding them would put an edge "
                     "in more than two faces")
    if weld.dropped_faces:
        notes.append(f"dropped {weld.dropped_faces} faces that welding left with fewer than 3 corners")
    return notes


def echo_repair_notes(surface, mesh_file, quiet: bool, data=None) -> None:
    """Print ``repair_notes`` as ``c1surf: note:`` lines on stderr, unless ``quiet``."""
    if not quiet:
        for note in repair_notes(surface, mesh_file, data):
            click.echo(f"c1surf: note: {note}", err=True)


def friendly_errors(command):
    """Decorator: known failures become one line and exit 1; --debug shows the traceback."""

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        ctx = click.get_current_context()
        debug = bool((ctx.obj or {}).get("debug"))
        try:
            return command(*args, **kwargs)
        except (click.ClickException, click.exceptions.Exit, click.exceptions.Abort):
            raise
        except C1SurfFileError as e:
            if debug:
                traceback.print_exc()
            raise Failure(str(e)) from None
        except OSError as e:  # disk full, permissions, a vanished directory while writing
            if debug:
                traceback.print_exc()
            where = f"{e.filename}: " if e.filename else ""
            raise Failure(f"{where}{e.strerror or e}; no output was written") from None
        except MemoryError:
            if debug:
                traceback.print_exc()
            raise Failure("out of memory: lower --resolution or convert a smaller mesh") from None
        except KeyboardInterrupt:
            raise Failure("interrupted; no partial output was left behind") from None

    return wrapper


def shows_progress(quiet: bool) -> bool:
    """True when progress belongs on stderr: it is a terminal and ``--quiet`` was not given."""
    return not quiet and sys.stderr.isatty()


def terminal_bar(length: int, template: str, info_sep: str = " ", **shown):
    """A click progress bar on stderr: ``#`` and ``.`` over 30 columns, then ``shown`` (show_pos, ...).

    The current item is shown as given (a string: counts, or the elapsed time at the end).
    """
    return click.progressbar(length=length, file=sys.stderr, bar_template=template, fill_char="#", empty_char=".",
                             width=30, info_sep=info_sep, item_show_func=lambda item: item, **shown)


class Progress:
    """Phase messages and progress bars on stderr, only when it is a terminal and not ``--quiet``.

    ``phase(name)`` opens a timed line (``c1surf: reading cube.obj... 0.01s``);
    ``advance(label, amount, total)`` draws the bar of a long step, and is the
    ``progress`` callable the evaluation and render functions take; ``done()``
    closes the last line with the total time.
    """

    def __init__(self, quiet: bool = False):
        self.enabled = shows_progress(quiet)
        self.start = time.perf_counter()
        self.phase_start = None  # of the open phase line
        self.bar = None  # click progress bar of the step being drawn
        self.bar_label, self.bar_start = None, None
        context = click.get_current_context(silent=True)
        if self.enabled and context is not None:
            context.call_on_close(self._end_bar)  # a failure mid-bar still ends its line and shows the cursor

    def phase(self, name: str) -> None:
        """Start the line of phase ``name`` (ending the one before with its time)."""
        if not self.enabled:
            return
        self._end_bar()
        self._end_phase()
        click.echo(f"c1surf: {name}...", err=True, nl=False)
        self.phase_start = time.perf_counter()

    def advance(self, label: str, amount: int, total: int) -> None:
        """Progress bar of a long step: ``amount`` more of ``total`` done (redrawn in place)."""
        if not self.enabled:
            return
        if self.bar is None or self.bar_label != label:
            self._start_bar(label, total)
        self.bar.update(amount)
        if self.bar.pos >= total:
            self._end_bar()

    def end_line(self) -> None:
        """End the open phase or bar line (with its time), so that a note printed next has a line of its own."""
        if self.enabled:
            self._end_bar()
            self._end_phase()

    def done(self) -> None:
        """End the last line: its time and the total time."""
        if not self.enabled:
            return
        self._end_bar()
        self._end_phase(f" (total {time.perf_counter() - self.start:.2f}s)")

    def _end_phase(self, note: str = "") -> None:
        if self.phase_start is not None:
            click.echo(f" {time.perf_counter() - self.phase_start:.2f}s{note}", err=True)
            self.phase_start = None

    def _start_bar(self, label: str, total: int) -> None:
        self._end_bar()
        self._end_phase()
        self.bar = terminal_bar(total, "%(label)s [%(bar)s] %(info)s", label=f"c1surf: {label}", show_percent=True)
        self.bar_label, self.bar_start = label, time.perf_counter()
        self.bar.render_progress()  # drawn at 0% already: the first chunk of a step may take seconds

    def _end_bar(self) -> None:
        """Finish the bar's line with the step's time instead of its ETA."""
        if self.bar is None:
            return
        self.bar.show_eta = False
        self.bar.update(0, current_item=f"{time.perf_counter() - self.bar_start:.2f}s")
        self.bar.render_progress()
        self.bar.render_finish()
        self.bar = None


def output_suffix(path, allowed, what: str) -> str:
    """Lower-case suffix of ``path``; a usage error unless ``allowed`` (an ``io.registry`` table) has it."""
    try:
        return suffix_of(path, allowed)
    except UnsupportedFormat as e:
        raise click.BadParameter(f"{what}: {e}") from None
