#!/usr/bin/env python
"""What reading STEP in a child process costs (issue 42): ``c1surf measure`` on a valid 2,016-face STEP file,
Open CASCADE in the process (``io.patches.step.CONTAINED = False``, the reader before) against in its child
(the default), processes in turn, medians of wall and CPU time (the child's included)::

    python bench/step_isolation.py [--repeats 5] [--folder /tmp/c1surf-step-isolation]

The file: a 14 x 9 quad torus converted with ``--patches torus2k.step --no-merge`` (one face per patch).
"""
from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

RUN = ("import sys, c1surf.io.patches.step as s; s.CONTAINED = {contained}; from c1surf.cli.main import main; "
       "sys.argv = ['c1surf', 'measure', {path!r}]; main()")


def torus_step(folder: Path) -> Path:
    """The 2,016-face STEP file (made once)."""
    step = folder / "torus2k.step"
    if step.exists():
        return step
    folder.mkdir(parents=True, exist_ok=True)
    n, m = 14, 9
    a, b = np.meshgrid(2 * np.pi * np.arange(n) / n, 2 * np.pi * np.arange(m) / m, indexing="ij")
    points = np.stack([(3 + np.cos(b)) * np.cos(a), (3 + np.cos(b)) * np.sin(a), np.sin(b)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    quads = np.stack([i * m + j, (i + 1) % n * m + j, (i + 1) % n * m + (j + 1) % m, i * m + (j + 1) % m], -1)
    obj = folder / "torus2k.obj"
    obj.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
                   + "".join("f " + " ".join(str(k + 1) for k in q) + "\n" for q in quads.reshape(-1, 4)))
    subprocess.run([sys.executable, "-m", "c1surf.cli.main", "convert", str(obj), "-o", str(folder / "torus2k.ply"),
                    "--patches", str(step), "--no-merge", "-q"], check=True)
    return step


def timed(path: Path, contained: bool) -> tuple[float, float]:
    """(wall, CPU of the process and its children) of one ``c1surf measure`` process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", RUN.format(contained=contained, path=str(path))], check=True,
                   stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--folder", default="/tmp/c1surf-step-isolation")
    args = parser.parse_args()
    path = torus_step(Path(args.folder))
    runs: dict = {False: [], True: []}
    for _ in range(args.repeats):
        for contained in (False, True):  # in turn
            runs[contained].append(timed(path, contained))
    for contained in (False, True):
        wall, cpu = (statistics.median(x) for x in zip(*runs[contained]))
        print(f"{'child process' if contained else 'in process':14s} wall {wall:6.2f} s  CPU {cpu:6.2f} s")
    ratios = [statistics.median(x[k] for x in runs[True]) / statistics.median(x[k] for x in runs[False]) for k in (0, 1)]
    print(f"child / in process: wall {ratios[0]:.3f}, CPU {ratios[1]:.3f} ({path.stat().st_size / 1e6:.1f} MB, "
          f"{args.repeats} processes each)")


if __name__ == "__main__":
    main()
