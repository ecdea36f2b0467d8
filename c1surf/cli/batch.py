"""``c1surf batch``: convert many meshes, several at a time, each in its own process.

Every file is converted by ``c1surf convert`` in a child process (so a crash or
an out-of-memory kill of one never touches the others, and each conversion
gives its memory back), at most ``-j`` at once: a ``concurrent.futures`` thread
pool of ``-j`` workers, each waiting on one child at a time. Outputs go through
``atomic_output`` as in ``convert``, so an interrupted batch leaves finished
files and no partial ones; running it again skips the outputs that are newer
than their input.
"""
from __future__ import annotations

import glob
import os
import shlex
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from pathlib import Path

import click
from click.core import ParameterSource

from ..io.registry import MESH_READERS, MESH_WRITERS, PATCH_WRITERS, suffix_list
from .common import friendly_errors, shows_progress, terminal_bar, with_formats
from .options import input_options, surface_options


def expand_inputs(patterns) -> list[Path]:
    """Mesh files named by ``patterns`` (globs, ``**`` recursive, or plain paths), sorted, without duplicates."""
    found = set()
    for pattern in patterns:
        matches = glob.glob(pattern, recursive=True) if glob.has_magic(pattern) else [pattern]
        for m in matches:
            p = Path(m)
            if p.is_file() and p.suffix.lower() in MESH_READERS:
                found.add(p)
    return sorted(found)


def outputs_for(path: Path, out_dir: Path, mesh_suffix: str, patch_suffixes) -> list[Path]:
    """The files ``c1surf convert`` writes for ``path``: OUTDIR/<stem><suffix>."""
    return [out_dir / (path.stem + s) for s in (mesh_suffix, *patch_suffixes)]


def up_to_date(path: Path, outputs) -> bool:
    """True when every output exists and is at least as new as the input."""
    try:
        source = path.stat().st_mtime
        return all(o.exists() and o.stat().st_mtime >= source for o in outputs)
    except OSError:
        return False


def convert_command(path: Path, outputs, resolution, extra) -> list[str]:
    """Argument list of the child ``c1surf convert`` for one file (``extra``: the options it passes on)."""
    command = [sys.executable, "-m", "c1surf.cli.main", "convert", str(path), "-o", str(outputs[0]), "-r", str(resolution), "-q"]
    for patch_path in outputs[1:]:
        command += ["--patches", str(patch_path)]
    return command + list(extra)


def given_arguments(context: click.Context, exclude=()) -> list[str]:
    """The options given on this command line (not left at their defaults) as ``convert`` takes them again: the
    surface and input options a batch passes on to every conversion (``exclude``: parameter names not passed)."""
    arguments = []
    for param in context.command.params:
        if not isinstance(param, click.Option) or param.name in exclude:
            continue
        if context.get_parameter_source(param.name) in (None, ParameterSource.DEFAULT):
            continue
        value, flag = context.params[param.name], max(param.opts, key=len)
        if param.is_flag and param.secondary_opts:  # --weights/--no-weights
            arguments.append(flag if value else max(param.secondary_opts, key=len))
        elif param.is_flag:
            arguments += [flag] if value else []
        elif param.nargs > 1:
            arguments += [flag, *map(repr, value)]
        else:
            arguments += [flag, repr(value) if isinstance(value, float) else str(value)]
    return arguments


def failure_line(stderr: str, returncode: int) -> str:
    """The child's one-line error (``c1surf: error: ...`` without the prefix), or what ended it."""
    lines = [line for line in stderr.strip().splitlines() if line.strip()]
    for line in reversed(lines):
        if line.startswith("c1surf: error: "):
            return line[len("c1surf: error: "):]
    if returncode < 0:
        name = signal.Signals(-returncode).name if -returncode in signal.Signals._value2member_map_ else str(-returncode)
        return f"the conversion was killed by {name}" + (" (out of memory?)" if name == "SIGKILL" else "")
    return lines[-1] if lines else f"exit status {returncode}"


class ConvertProcesses:
    """The ``c1surf convert`` children of a batch: one per file, each run by a worker thread.

    A child is started only while the batch is not stopping, under the same
    lock that ``stop`` takes, so no child starts after ``stop`` has ended the
    running ones.
    """

    def __init__(self):
        self.lock = threading.Lock()
        self.running = set()
        self.stopping = False

    def run(self, command: list[str]) -> tuple[int, str]:
        """Run ``command`` to its end: (exit status, stderr text); stderr is drained as it comes (no full pipe)."""
        with self.lock:
            if self.stopping:  # never started: the batch is being interrupted
                return -signal.SIGTERM, ""
            child = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            self.running.add(child)
        try:
            _, stderr = child.communicate()
        finally:
            with self.lock:
                self.running.discard(child)
        return child.returncode, stderr.decode(errors="replace")

    def stop(self) -> None:
        """End every running child and wait for it (on SIGTERM each child removes its temporary files)."""
        with self.lock:
            self.stopping = True
            children = list(self.running)
        for child in children:
            child.terminate()
        for child in children:
            child.wait()


def run_conversions(commands: dict[Path, list[str]], jobs: int, quiet: bool) -> list[tuple[Path, str]]:
    """Run the ``convert`` commands ``jobs`` at a time; (input, one-line reason) of each failure, as they end.

    On Ctrl-C or SIGTERM no further child starts, the running ones are ended
    and waited for, and the interrupt goes on to the caller.
    """
    if not commands:
        return []
    processes, failures = ConvertProcesses(), []
    with ThreadPoolExecutor(max_workers=jobs) as pool, batch_bar(len(commands), quiet) as bar:
        futures = {pool.submit(processes.run, command): path for path, command in commands.items()}
        pending = set(futures)
        try:
            while pending:
                ended, pending = wait(pending, timeout=1.0, return_when=FIRST_COMPLETED)
                for future in ended:
                    returncode, stderr = future.result()
                    if returncode != 0:
                        failures.append((futures[future], failure_line(stderr, returncode)))
                running = sum(future.running() for future in pending)
                bar.update(len(ended), current_item=f"{len(failures)} failed  {running} running")
        except KeyboardInterrupt:
            pool.shutdown(wait=False, cancel_futures=True)
            processes.stop()
            raise
    return failures


def batch_bar(total: int, quiet: bool):
    """The batch's progress line (files done of ``total``, ETA, failed and running), or none off a terminal."""
    if not shows_progress(quiet):
        return NoBar()
    return terminal_bar(total, "[%(bar)s] %(info)s", info_sep="  ", show_pos=True, show_eta=True)


class NoBar:
    """Stands in for the progress bar when none is shown (stderr piped, or ``--quiet``)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    def update(self, n_steps: int, current_item=None) -> None:
        pass


@click.command()
@click.argument("patterns", nargs=-1, required=True, metavar="'GLOB'...")
@click.option("-o", "--output-dir", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for the outputs (created if missing): OUTDIR/<input stem><format>.")
@click.option("-j", "--jobs", type=click.IntRange(1, None), default=None,
              help="Conversions at once (default: the number of cores; each needs the memory of one `convert`).")
@click.option("-f", "--format", "mesh_suffix", type=click.Choice(sorted(MESH_WRITERS)), default=".ply", show_default=True,
              help="Tessellated mesh format of every output.")
@click.option("--patches", "patch_suffixes", type=click.Choice(sorted(PATCH_WRITERS)), multiple=True,
              help="Also write each surface's Bezier patches in this format (repeat for several).")
@click.option("-r", "--resolution", type=click.IntRange(2, None), default=8, show_default=True,
              help="Samples per patch side (as in `convert`).")
@click.option("--float32", is_flag=True, help="Write points and normals as float32 (as in `convert`).")
@surface_options
@input_options
@click.option("--rebuild", is_flag=True, help="Convert every input, also those whose outputs are newer.")
@click.option("--shard", default=None, metavar="I/N",
              help="Convert only inputs I, I+N, I+2N, ... of the sorted list (0-based I): one share of a cluster job array.")
@click.option("--convert-options", "extra", default="",
              help="More `c1surf convert` options, quoted as one string, e.g. \"--curvature\".")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar (it only appears on a terminal anyway).")
@friendly_errors
@with_formats
def batch(patterns, out_dir, jobs, mesh_suffix, patch_suffixes, resolution, rebuild, shard, extra, quiet, **passed_on):
    """Convert every mesh ({mesh_inputs}) matching 'GLOB' (quote it; ** recurses) into OUTDIR, -j at a time.

    Each input becomes OUTDIR/<stem><format> (and OUTDIR/<stem><patch format>
    with --patches). Outputs newer than their input are skipped, so a batch can
    be rerun after an interruption or after adding files. A failing file never
    stops the others; the summary lists one line per failure, and the exit
    status is 1 if any file failed. The surface and input options (and --float32)
    are passed on to every conversion.
    """
    started = time.perf_counter()
    inputs = select_inputs(patterns, shard)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    planned = {path: outputs_for(path, out, mesh_suffix, patch_suffixes) for path in inputs}
    refuse_outputs_over_inputs(planned)
    todo = {path: outputs for path, outputs in planned.items() if rebuild or not up_to_date(path, outputs)}
    # passed_on: --float32, and the surface and input options (built, so checked, by their decorators): each
    # conversion takes them again as they were given
    passed = given_arguments(click.get_current_context(), exclude=("out_dir", "jobs", "mesh_suffix", "patch_suffixes", "resolution",
                                                                  "rebuild", "shard", "extra", "quiet"))
    extra_args = shlex.split(extra) + passed
    commands = {path: convert_command(path, outputs, resolution, extra_args) for path, outputs in todo.items()}
    failures = run_conversions(commands, jobs or os.cpu_count() or 1, quiet)
    summarize(len(inputs), len(todo), failures, time.perf_counter() - started)


def refuse_outputs_over_inputs(planned: dict) -> None:
    """A usage error when an output would be one of the inputs (OUTDIR their folder, --format their format):
    outputs beside the inputs in another format are fine."""
    sources = {path.resolve(): path for path in planned}
    for path, outputs in planned.items():
        for output in outputs:
            if output.resolve() in sources:
                raise click.BadParameter(f"the output {output} would overwrite the input {sources[output.resolve()]}: "
                                         "choose another output folder or --format", param_hint="--output-dir")


def summarize(n_inputs: int, n_run: int, failures, seconds: float) -> None:
    """The closing lines on stderr: the counts (``n_run`` conversions tried), then one line per failure; exit status 1 if any file failed."""
    click.echo(f"c1surf batch: {n_run - len(failures)} converted, {n_inputs - n_run} up to date, "
               f"{len(failures)} failed (of {n_inputs} inputs) in {seconds:.1f}s", err=True)
    for path, message in failures:  # the child's line names its file already, most often
        click.echo(f"  {message}" if message.startswith(f"{path}:") else f"  {path}: {message}", err=True)
    if failures:
        raise click.exceptions.Exit(1)


def select_inputs(patterns, shard: str | None) -> list[Path]:
    """The inputs of this batch: the files matching ``patterns``, this shard's share, no two of one stem."""
    inputs = expand_inputs(patterns)
    if not inputs:
        raise click.BadParameter(f"no mesh file ({suffix_list(MESH_READERS)}) matches {' '.join(patterns)}",
                                 param_hint="'GLOB'")
    if shard:
        index, count = parse_shard(shard)
        inputs = inputs[index::count]
    stems = {}
    for path in inputs:
        stems.setdefault(path.stem, []).append(path)
    clashes = [paths for paths in stems.values() if len(paths) > 1]
    if clashes:
        shown = "; ".join(" and ".join(str(p) for p in paths[:2]) for paths in clashes[:3])
        raise click.BadParameter(f"inputs with the same name would write the same output: {shown}", param_hint="'GLOB'")
    return inputs


def parse_shard(shard: str) -> tuple[int, int]:
    """``"I/N"`` as (I, N) with 0 <= I < N; a usage error otherwise."""
    try:
        index, count = (int(x) for x in shard.split("/"))
        if not 0 <= index < count:
            raise ValueError
    except ValueError:
        raise click.BadParameter(f"expected I/N with 0 <= I < N, got {shard!r}", param_hint="--shard") from None
    return index, count
