"""The ``c1surf`` command: a click group; each subcommand lives in its own module."""
from __future__ import annotations

import signal

import click

from .. import __version__
from .runtime import tune_allocator
from .batch import batch
from .check import check
from .convert import convert
from .render import render_command
from .reports.diff import diff
from .reports.measure import measure
from .reports.inspect import inspect
from .tessellate import tessellate


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
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
    tune_allocator()  # reuse freed memory instead of faulting in fresh pages (c1surf.cli.runtime)


def _interrupt(signum, frame):
    raise KeyboardInterrupt


main.add_command(convert)
main.add_command(batch)
main.add_command(check)
main.add_command(tessellate)
main.add_command(render_command)
main.add_command(measure)
main.add_command(diff)
main.add_command(inspect)

if __name__ == "__main__":  # pragma: no cover
    main()
