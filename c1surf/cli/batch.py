"""``c1surf batch``: convert many meshes, several at a time, each in its own process.

Every file is converted by ``c1surf convert`` in a child process (so a crash or
an out-of-memory kill of one never touches the others, and each conversion
gives its memory back), at most ``-j`` at once. Outputs go through
``atomic_output`` as in ``convert``, so an interrupted batch leaves finished
files and no partial ones; running it again skips the outputs that are newer
than their input.
"""
from __future__ import annotations

import glob
import os
import shlex
import subprocess
import sys
import time
from pathlib import Path

import click

from ..io.registry import MESH_READERS, MESH_WRITERS, PATCH_WRITERS
from .common import friendly_errors
from .options import surface_options


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


def convert_command(path: Path, outputs, resolution, options, extra) -> list[str]:
    """Argument list of the child ``c1surf convert`` for one file."""
    command = [sys.executable, "-m", "c1surf.cli.main", "convert", str(path), "-o", str(outputs[0]), "-r", str(resolution), "-q"]
    for patch_path in outputs[1:]:
        command += ["--patches", str(patch_path)]
    for name, value in options.items():
        command += [f"--{name.replace('_', '-')}", str(value)]
    return command + list(extra)


def failure_line(stderr: str, returncode: int) -> str:
    """The child's one-line error (``c1surf: error: ...`` without the prefix), or what ended it."""
    lines = [line for line in stderr.strip().splitlines() if line.strip()]
    for line in reversed(lines):
        if line.startswith("c1surf: error: "):
            return line[len("c1surf: error: "):]
    if returncode < 0:
        import signal

        name = signal.Signals(-returncode).name if -returncode in signal.Signals._value2member_map_ else str(-returncode)
        return f"the conversion was killed by {name}" + (" (out of memory?)" if name == "SIGKILL" else "")
    return lines[-1] if lines else f"exit status {returncode}"


class Bar:
    """One progress line on stderr, redrawn in place; only on a terminal."""

    def __init__(self, total: int, quiet: bool):
        self.total, self.enabled = total, not quiet and sys.stderr.isatty()
        self.start = time.perf_counter()

    def show(self, done: int, failed: int, running: int) -> None:
        if not self.enabled:
            return
        width = 30
        filled = int(width * done / self.total) if self.total else width
        elapsed = time.perf_counter() - self.start
        click.echo(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{self.total}  {failed} failed  {running} running  "
                   f"{elapsed:5.0f}s", err=True, nl=False)

    def close(self) -> None:
        if self.enabled:
            click.echo("", err=True)


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
@click.option("--rebuild", is_flag=True, help="Convert every input, also those whose outputs are newer.")
@click.option("--shard", default=None, metavar="I/N",
              help="Convert only inputs I, I+N, I+2N, ... of the sorted list (0-based I): one share of a cluster job array.")
@click.option("--convert-options", "extra", default="",
              help="More `c1surf convert` options, quoted as one string, e.g. \"--interpolate-vertices\".")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar (it only appears on a terminal anyway).")
@friendly_errors
def batch(patterns, out_dir, jobs, mesh_suffix, patch_suffixes, resolution, float32, blend, alpha, beta, tangent_rule,
          rebuild, shard, extra, quiet):
    """Convert every mesh matching 'GLOB' (quote it; ** recurses) into OUTDIR, -j at a time.

    Each input becomes OUTDIR/<stem><format> (and OUTDIR/<stem><patch format>
    with --patches). Outputs newer than their input are skipped, so a batch can
    be rerun after an interruption or after adding files. A failing file never
    stops the others; the summary lists one line per failure, and the exit
    status is 1 if any file failed.
    """
    inputs = expand_inputs(patterns)
    if not inputs:
        raise click.BadParameter(f"no .obj or .ply file matches {' '.join(patterns)}", param_hint="'GLOB'")
    if shard:
        try:
            index, count = (int(x) for x in shard.split("/"))
            if not 0 <= index < count:
                raise ValueError
        except ValueError:
            raise click.BadParameter(f"expected I/N with 0 <= I < N, got {shard!r}", param_hint="--shard") from None
        inputs = inputs[index::count]
    stems = {}
    for path in inputs:
        stems.setdefault(path.stem, []).append(path)
    clashes = [paths for paths in stems.values() if len(paths) > 1]
    if clashes:
        shown = "; ".join(" and ".join(str(p) for p in paths[:2]) for paths in clashes[:3])
        raise click.BadParameter(f"inputs with the same name would write the same output: {shown}", param_hint="'GLOB'")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    options = {"blend": blend, "alpha": alpha, "beta": beta, "tangent_rule": tangent_rule}
    extra_args = shlex.split(extra) + (["--float32"] if float32 else [])

    todo, skipped = [], 0
    for path in inputs:
        outputs = outputs_for(path, out, mesh_suffix, patch_suffixes)
        if not rebuild and up_to_date(path, outputs):
            skipped += 1
        else:
            todo.append((path, outputs))
    jobs = jobs or os.cpu_count() or 1
    bar = Bar(len(todo), quiet)
    failures, running, captured, done = [], {}, {}, 0
    queue = list(reversed(todo))
    try:
        while queue or running:
            while queue and len(running) < jobs:
                path, outputs = queue.pop()
                child = subprocess.Popen(convert_command(path, outputs, resolution, options, extra_args),
                                         stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
                running[child] = path
            bar.show(done, len(failures), len(running))
            for child in _wait_any(running, captured):
                path = running.pop(child)
                stderr = (captured.pop(child, b"") + child.stderr.read()).decode(errors="replace")
                child.stderr.close()
                done += 1
                if child.returncode != 0:
                    failures.append((path, failure_line(stderr, child.returncode)))
            bar.show(done, len(failures), len(running))
    except KeyboardInterrupt:
        for child in running:
            child.terminate()  # each child removes its temporary files on SIGTERM
        for child in running:
            child.wait()
        bar.close()
        raise
    bar.close()
    converted = done - len(failures)
    click.echo(f"c1surf batch: {converted} converted, {skipped} up to date, {len(failures)} failed "
               f"(of {len(inputs)} inputs) in {time.perf_counter() - bar.start:.1f}s", err=True)
    for path, message in failures:
        click.echo(f"  {path}: {message}", err=True)
    if failures:
        raise click.exceptions.Exit(1)


def _wait_any(running: dict, captured: dict) -> list:
    """Block until at least one child has ended, collecting stderr meanwhile (no child blocks on a full pipe)."""
    import selectors

    selector = selectors.DefaultSelector()
    for child in running:
        selector.register(child.stderr, selectors.EVENT_READ, child)
    try:
        while True:
            ended = [c for c in running if c.poll() is not None]
            if ended:
                return ended
            for key, _ in selector.select(timeout=0.2):
                chunk = os.read(key.fileobj.fileno(), 65536)
                if chunk:
                    captured[key.data] = captured.get(key.data, b"") + chunk
                else:
                    selector.unregister(key.fileobj)
    finally:
        selector.close()
