"""c1surf against libigl in pairs of processes taken in turn: the steadier reading of issue 15's speed ratios.

One ``make bench`` run measures each tool in its own block of processes; on a
machine whose first touches of memory cost what the host makes them, two
blocks minutes apart can differ by a third. Here each pair runs back to back on
the issue's pair of inputs (the 180,000-quad torus, and libigl on its
360,000-triangle split; 2,880,000 output vertices each), with the harness's own
workers and command lines, and the ratios of the pairs are printed:

- in memory: c1surf's worker (build + N = 2 tessellation), then libigl's (``igl.loop`` x2);
- whole process: ``c1surf convert in.obj -o out.ply -r 2``, then libigl's read, Loop x2, binary PLY.

    .venv/bin/python bench/pairs.py [--pairs 5] [--inputs /tmp/c1surf-bench-inputs]
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
from pathlib import Path

from harness.meshes import cached_torus_obj
from harness.processes import SETTINGS, run_c1surf, run_worker

ROOT = Path(__file__).resolve().parents[1]


def _show(name: str, mine: list, theirs: list) -> None:
    ratios = [b / a for a, b in zip(mine, theirs)]
    print(f"{name}: c1surf {min(mine):.2f}-{max(mine):.2f} s, libigl {min(theirs):.2f}-{max(theirs):.2f} s; "
          f"libigl / c1surf {min(ratios):.2f}-{max(ratios):.2f} (median {statistics.median(ratios):.2f})")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=5)
    parser.add_argument("--inputs", default=str(Path(tempfile.gettempdir()) / "c1surf-bench-inputs"),
                        help="folder of the generated tori (bench/run.py's --inputs), written if missing")
    args = parser.parse_args(argv)
    SETTINGS["root"] = ROOT
    folder = Path(args.inputs)
    folder.mkdir(parents=True, exist_ok=True)
    quads = str(cached_torus_obj(folder, "torus-quad-180000", 600, 300, False))
    triangles = str(cached_torus_obj(folder, "torus-tri-360000", 600, 300, True))
    memory, whole = ([], []), ([], [])
    with tempfile.TemporaryDirectory() as scratch:
        mine, theirs = f"{scratch}/c1surf.ply", f"{scratch}/igl.ply"
        for _ in range(args.pairs):
            os.sync()
            result = run_worker({"tool": "c1surf", "path": quads, "resolution": 2, "scratch": scratch,
                                 "update_repeats": 1}, 900)
            memory[0].append(result["seconds"]["convert"])
            os.sync()
            result = run_worker({"tool": "igl", "path": triangles, "levels": 2, "output": theirs}, 900)
            memory[1].append(result["seconds"]["convert"])
            whole[1].append(result["wall_seconds"])
            os.sync()
            whole[0].append(run_c1surf(["convert", quads, "-o", mine, "-r", "2"], 900)["seconds"])
    _show("in memory", *memory)
    _show("whole process", *whole)


if __name__ == "__main__":
    main()
