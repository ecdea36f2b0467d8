"""What every c1surf command shares: one-line errors, progress on a terminal."""
from __future__ import annotations

import functools
import sys
import time
import traceback

import click

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


def repair_notes(surface, mesh_file) -> list[str]:
    """One-line notes on what c1surf changed or ignored to make the input usable."""
    r = getattr(surface, "repairs", {}) or {}
    notes = []
    if getattr(mesh_file, "collapsed_corners", 0):
        notes.append(f"dropped {mesh_file.collapsed_corners} repeated corners (zero-length edges such as 'f a b c c')")
    if r.get("flipped_faces"):
        notes.append(f"flipped {r['flipped_faces']} faces to orient each connected component consistently")
    if r.get("non_orientable"):
        notes.append("the surface is not orientable: built on its orientation double cover; normals flip across a seam "
                     "(use `c1surf check --unoriented`)")
    if r.get("split_vertices"):
        notes.append(f"split {r['split_vertices']} pinched vertices into one vertex per fan of faces")
    if r.get("unused_vertices"):
        notes.append(f"ignored {r['unused_vertices']} vertices used by no face")
    if r.get("boundary_edges"):
        notes.append(f"open mesh: {r['boundary_edges']} boundary edges, closed for the construction by a ghost layer")
    return notes


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


class Progress:
    """Phase messages on stderr, only when it is a terminal and not ``--quiet``."""

    def __init__(self, quiet: bool = False):
        self.enabled = not quiet and sys.stderr.isatty()
        self.start = time.perf_counter()
        self.last = None
        self.bar = None  # (label, done, started) of the progress bar being drawn

    def phase(self, name: str) -> None:
        if not self.enabled:
            return
        self._end_bar()
        now = time.perf_counter()
        if self.last is not None:
            click.echo(f" {now - self.last:.2f}s", err=True)
        click.echo(f"c1surf: {name}...", err=True, nl=False)
        self.last = now

    def advance(self, label: str, amount: int, total: int) -> None:
        """Progress bar of a long step: ``amount`` more of ``total`` done (redrawn in place)."""
        if not self.enabled:
            return
        now = time.perf_counter()
        if self.bar is None or self.bar[0] != label:
            self._end_bar()
            if self.last is not None:  # close the open phase line
                click.echo(f" {now - self.last:.2f}s", err=True)
                self.last = None
            self.bar = (label, 0, now)
        label, done, started = self.bar
        done = min(done + amount, total)
        self.bar = (label, done, started)
        filled = int(30 * done / total) if total > 0 else 30
        click.echo(f"\rc1surf: {label} [{'#' * filled}{'.' * (30 - filled)}] {100 * done // max(total, 1):3d}%",
                   err=True, nl=False)
        if done >= total:
            self._end_bar()

    def _end_bar(self) -> None:
        if self.bar is not None:
            click.echo(f" {time.perf_counter() - self.bar[2]:.2f}s", err=True)
            self.bar = None

    def done(self) -> None:
        if self.enabled:
            self._end_bar()
        if self.enabled and self.last is not None:
            click.echo(f" {time.perf_counter() - self.last:.2f}s (total {time.perf_counter() - self.start:.2f}s)", err=True)


def output_suffix(path, allowed, what: str) -> str:
    """Lower-case suffix of ``path``; a usage error unless ``allowed`` (an ``io.registry`` table) has it."""
    try:
        return suffix_of(path, allowed)
    except UnsupportedFormat as e:
        raise click.BadParameter(f"{what}: {e}") from None
