"""What every c1surf command shares: one-line errors, progress (click's bars) on a terminal."""
from __future__ import annotations

import functools
import sys
import time
import traceback

import click
import numpy as np

from ..errors import C1SurfFileError, OptionError, ResourceRefusal
from ..io.registry import MESH_READERS, MESH_WRITERS, PATCH_READERS, PATCH_WRITERS, UnsupportedFormat, suffix_of


class Failure(click.ClickException):
    """A user-facing failure: printed as ``c1surf: error: ...``, exit status 1."""

    exit_code = 1

    def show(self, file=None):
        click.echo(f"c1surf: error: {self.message}", err=True)


def usage_line(error: click.UsageError) -> str:
    """One line for a click usage error: ``--blend: 2 is not in [0, 1]``, ``no such option: --blned``.

    Names the command's --help for what the line cannot say.
    """
    if isinstance(error, click.BadParameter):
        hint = error.param_hint
        if hint is None and error.param is not None:
            hint = _param_name(error.param)
        if isinstance(error, click.MissingParameter):
            what = error.param_type or (error.param.param_type_name if error.param is not None else "parameter")
            text = f"missing {what} {hint}" if hint else f"missing {what}"
            if error.message:
                text += f": {error.message}"
        else:
            text = f"{_join(hint)}: {error.message}" if hint else error.message
    else:
        text = error.format_message()
    text = " ".join(str(text).split()).replace(". (", " (").rstrip(".")
    text = text[:1].lower() + text[1:] if text[:2] != text[:2].upper() else text
    command = error.ctx.command_path if error.ctx is not None else "c1surf"
    return f"{text} (see `{command} --help`)"


def _param_name(param) -> str:
    """The option's longest name (``--blend``) or the argument's metavar (``INPUT``)."""
    if isinstance(param, click.Option):
        return max(param.opts, key=len)
    return param.metavar or (param.name or "").upper()


def _join(hint) -> str:
    if isinstance(hint, (list, tuple)):
        return " / ".join(str(h) for h in hint)
    return str(hint).strip("'\"")


class OneLineUsageError(click.UsageError):
    """A usage error printed as one ``c1surf: error:`` line, exit status 2."""

    def show(self, file=None):
        click.echo(f"c1surf: error: {self.message}", err=True)


class UsageFailure(Failure):
    """A one-line ``c1surf: error:`` for a bad option value, with the exit status of bad usage (2)."""

    exit_code = 2


def echo_notes(notes, quiet: bool = False) -> None:
    """Print ``notes`` as ``c1surf: note:`` lines on stderr, unless ``quiet``."""
    if not quiet:
        for note in notes:
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
        except ResourceRefusal as e:  # the resource guard (c1surf.resources): what to do instead
            raise Failure(e.message) from None
        except OptionError as e:  # SurfaceOptions / InputOptions that contradict each other
            raise UsageFailure(str(e)) from None
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


def with_formats(command):
    """Fill a command's docstring (its --help) with the formats of ``io.registry``: {mesh_inputs}, {patch_inputs},
    {mesh_outputs}, {patch_outputs} become "OBJ, PLY, STL, OFF" and the like. Apply it first (next to the def)."""
    names = {"{mesh_inputs}": MESH_READERS.names(), "{patch_inputs}": PATCH_READERS.names(),
             "{mesh_outputs}": MESH_WRITERS.names(), "{patch_outputs}": PATCH_WRITERS.names()}
    for key, value in names.items():
        command.__doc__ = command.__doc__.replace(key, value)
    return command


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
