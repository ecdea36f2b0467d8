"""The ``c1surf`` command: a click group; each subcommand lives in its own module."""
from __future__ import annotations

import contextlib
import importlib
import signal

import click

from .. import __version__
from ..memory import tune_allocator
from .common import OneLineUsageError, usage_line

# command name: (module, function), imported when that command runs (or --help lists the commands), so
# `c1surf convert` does not import what `render`, `batch` or `inspect` need
COMMANDS = {
    "convert": (".convert", "convert"), "batch": (".batch", "batch"), "check": (".check", "check"),
    "tessellate": (".tessellate", "tessellate"), "render": (".render", "render_command"),
    "measure": (".reports.measure", "measure"), "diff": (".reports.diff", "diff"),
    "inspect": (".reports.inspect", "inspect"), "fit": (".fit", "fit"),
}


class LazyGroup(click.Group):
    """A click group whose subcommands (``COMMANDS``) are imported on first use."""

    def list_commands(self, ctx):
        return sorted(set(COMMANDS) | set(self.commands))

    def get_command(self, ctx, name):
        if name not in self.commands and name in COMMANDS:
            module, function = COMMANDS[name]
            self.add_command(getattr(importlib.import_module(module, __package__), function), name)
        return self.commands.get(name)

    def make_context(self, info_name, args, parent=None, **extra):
        with _one_line_usage():
            return super().make_context(info_name, args, parent=parent, **extra)

    def invoke(self, ctx):
        with _one_line_usage():
            return super().invoke(ctx)


@contextlib.contextmanager
def _one_line_usage():
    """Click's usage errors (bad option values, unknown options, missing arguments) as one line, exit status 2."""
    try:
        yield
    except (OneLineUsageError, click.exceptions.NoArgsIsHelpError):
        raise
    except click.UsageError as error:
        raise OneLineUsageError(usage_line(error), ctx=error.ctx) from None


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="c1surf")
@click.option("--debug", is_flag=True, help="Show a Python traceback for errors (for bug reports).")
@click.pass_context
def main(ctx, debug):
    """Smooth G1 surfaces of low-degree Bezier patches from polygon meshes.

    c1surf follows J. Peters, "Constructing C^1 surfaces of arbitrary topology
    using biquadratic and bicubic splines": two Doo-Sabin refinements, one
    biquadratic patch per regular refined vertex and n bicubic patches over
    each n-sided cell. Errors print one line and exit 1 (2 for bad usage).
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    # SIGTERM (a killed make job, a batch scheduler) unwinds like Ctrl-C, so
    # temporary output files are removed and nothing partial is left behind.
    signal.signal(signal.SIGTERM, _interrupt)
    tune_allocator()  # reuse freed memory instead of faulting in fresh pages (c1surf.memory)


def _interrupt(signum, frame):
    raise KeyboardInterrupt


if __name__ == "__main__":  # pragma: no cover
    main()
