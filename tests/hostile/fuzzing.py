"""Seeded mutation fuzzing of every reader and every command that reads a file (issue 42).

A case is a number: it picks one of twelve small valid files (a box with crease tags as OBJ, ASCII and binary
PLY, ASCII and binary STL, OFF, text and binary USD; its surface as JSON, NPZ, IGES and STEP), mutates it once
(``mutations.mutate``) and runs one command on it (convert, check, measure --json, tessellate, inspect, diff,
render, batch, as the file's kind allows), judged by the promise (``hostile_cases.assert_outcome``): exit 0
with finite outputs or one ``c1surf: error:`` line and exit 1 and no output; no traceback, nothing printed
past click (file descriptors 1 and 2 stay empty: no library's logging, no C++ chatter), within ``TIME_LIMIT``.

``tests/hostile/test_mutation_fuzz.py`` runs a few hundred cases in the test process; ``make fuzz`` runs this file
(20,000 cases by default) in worker processes that a crash cannot take down with the run: each worker says
which case it starts, and a worker that dies is replaced from the next case, its case a failure::

    python tests/hostile/fuzzing.py --cases 20000 --jobs 2 [--start 0] [--report fuzz.json]
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from hostile_cases import assert_batch_outcome, assert_outcome, run  # noqa: E402
from mutations import mutate  # noqa: E402

TIME_LIMIT = 150.0  # seconds a case may take (above c1surf's own limit on Open CASCADE: 60 s + 20 s per MB)
MESHES = ["box.obj", "box_ascii.ply", "box_binary.ply", "box_ascii.stl", "box_binary.stl", "box.off", "box.usda",
          "box.usdc"]
PATCHES = ["box.json", "box.npz", "box.igs", "box.step"]
MESH_COMMANDS = ["convert", "convert", "check", "measure", "inspect", "inspect", "diff", "render"]
BATCH_SHARE = 0.03  # of the mesh cases run by batch (a child c1surf convert each: seconds, where the others take 0.1)
PATCH_COMMANDS = ["check", "measure", "tessellate", "tessellate", "diff", "render"]

BOX_OBJ = """# a box with crease tags along its top rim and a corner
v 0 0 0
v 2 0 0
v 2 1 0
v 0 1 0
v 0 0 1
v 2 0 1
v 2 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
t crease 2/1/0 4 5 10
t crease 2/1/0 5 6 10
t crease 2/1/0 6 7 10
t crease 2/1/0 7 4 10
t corner 1/1/0 0 10
"""


def make_seeds(folder: Path) -> Path:
    """The twelve valid files in ``folder``: the box as every mesh format, its surface as every patch format."""
    import numpy as np
    import trimesh
    from plyfile import PlyData, PlyElement

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "box.obj").write_text(BOX_OBJ)
    points = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [0, 0, 1], [2, 0, 1], [2, 1, 1], [0, 1, 1]], float)
    quads = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])
    vertex = np.array([tuple(p) + (10.0 * (k == 0),) for k, p in enumerate(points)],
                      dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("corner", "f4")])
    face = np.array([(q,) for q in quads], dtype=[("vertex_indices", "i4", (4,))])
    edge = np.array([(4, 5, 10.0), (5, 6, 10.0), (6, 7, 10.0), (7, 4, 10.0)],
                    dtype=[("vertex1", "i4"), ("vertex2", "i4"), ("crease", "f4")])
    elements = [PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face"), PlyElement.describe(edge, "edge")]
    PlyData(elements, text=True).write(str(folder / "box_ascii.ply"))
    PlyData(elements, text=False).write(str(folder / "box_binary.ply"))
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    mesh = trimesh.Trimesh(points, triangles, process=False)
    (folder / "box_ascii.stl").write_bytes(trimesh.exchange.stl.export_stl_ascii(mesh).encode())
    (folder / "box_binary.stl").write_bytes(trimesh.exchange.stl.export_stl(mesh))
    _write_usd(folder, points, quads)
    (folder / "box.off").write_text("OFF\n8 6 0\n" + "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in points)
                                    + "".join("4 " + " ".join(map(str, q)) + "\n" for q in quads))
    result = run("convert", folder / "box.obj", "-o", folder / "box_out.ply", "-q",
                 *[a for name in PATCHES for a in ("--patches", folder / name)])
    assert result.exit_code == 0, result.output
    (folder / "box_out.ply").unlink()
    return folder


def _write_usd(folder: Path, points, quads) -> None:
    """The box as ``box.usda`` and ``box.usdc``, written by usd-core's own API with the OBJ's tags (the top rim
    creased at 10, vertex 0 a corner)."""
    from pxr import Usd, UsdGeom

    for name in ("box.usda", "box.usdc"):
        stage = Usd.Stage.CreateNew(str(folder / name))
        mesh = UsdGeom.Mesh.Define(stage, "/box")
        mesh.CreatePointsAttr([tuple(p) for p in points.tolist()])
        mesh.CreateFaceVertexCountsAttr([4] * len(quads))
        mesh.CreateFaceVertexIndicesAttr(quads.ravel().tolist())
        mesh.CreateCreaseIndicesAttr([4, 5, 6, 7, 4])
        mesh.CreateCreaseLengthsAttr([5])
        mesh.CreateCreaseSharpnessesAttr([10.0])
        mesh.CreateCornerIndicesAttr([0])
        mesh.CreateCornerSharpnessesAttr([10.0])
        stage.GetRootLayer().Save()


def case_plan(case: int) -> tuple[str, str]:
    """(seed file, command) of case number ``case``."""
    rng = random.Random(f"plan {case}")
    name = rng.choice(MESHES + PATCHES)
    if name in MESHES and rng.random() < BATCH_SHARE:
        return name, "batch"
    return name, rng.choice(MESH_COMMANDS if name in MESHES else PATCH_COMMANDS)


def command_line(command: str, path: Path, original: Path, work: Path):
    """Arguments of ``c1surf COMMAND`` on the mutated ``path``, its outputs, and whether exit 1 may be a verdict."""
    heads = {"convert": ([path, "-o", work / "out.ply", "-r", "2", "-q"], [work / "out.ply"]),
             "check": ([path, "--samples", "5"], []),
             "measure": ([path, "--json"], []),
             "tessellate": ([path, "-o", work / "out.ply", "-r", "2", "-q"], [work / "out.ply"]),
             "inspect": ([path], []),
             "diff": ([path, original], []),
             "render": ([path, "-o", work / "out.exr", "--size", "12"], [work / "out.exr"]),
             "batch": ([str(path), "-o", work / "batch", "-r", "2", "-q"], [work / "batch" / (path.stem + ".ply")])}
    args, outputs = heads[command]
    return [command, *args], outputs, command in ("check", "diff")


class CaseTimeout(BaseException):
    """A case ran past its time limit (a BaseException: no ``except Exception`` of c1surf's swallows it)."""


def _alarm(signum, frame):
    raise CaseTimeout


@contextlib.contextmanager
def _time_limit(seconds: float):
    try:
        previous = signal.signal(signal.SIGALRM, _alarm)
    except ValueError:  # not the main thread: no limit
        yield
        return
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@contextlib.contextmanager
def _descriptor_output(folder: Path):
    """File descriptors 1 and 2 sent to files for the block (what bypasses click: C++ output, a library's
    print to the real stderr); yields a function that returns what was written there."""
    saved = [os.dup(1), os.dup(2)]
    files = [open(folder / name, "w+b") for name in (".fd1", ".fd2")]
    sys.stdout.flush()
    sys.stderr.flush()
    os.dup2(files[0].fileno(), 1)
    os.dup2(files[1].fileno(), 2)
    try:
        yield lambda: b"".join(f.seek(0) or f.read() for f in files)
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved:
            os.close(fd)
        for f in files:
            f.close()
            os.unlink(f.name)


def run_case(case: int, seeds: Path, work: Path) -> tuple[str | None, str, str]:
    """Run case number ``case`` in ``work`` (emptied first): (None or what broke the promise, what was done,
    how it ended: the exit status and the error line, without the file's path)."""
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    name, command = case_plan(case)
    original = seeds / name
    data, label = mutate(case, original.read_bytes(), original.suffix)
    path = work / ("m" + original.suffix)
    path.write_bytes(data)
    args, outputs, verdict = command_line(command, path, original, work)
    what = f"case {case}: {command} {name}: {label}"
    ended = "no end"
    try:
        with _descriptor_output(work) as printed, _time_limit(TIME_LIMIT):
            result = run(*args)
            leaked = printed()
        errors = [line for line in result.stderr.splitlines() if "error:" in line or line.startswith("  ")]
        ended = f"exit {result.exit_code}" + (f": {errors[0].replace(str(path), 'FILE')[:160]}" if errors else "")
        assert not leaked, f"printed past click on file descriptors 1/2: {leaked[:300]!r}"
        if command == "batch":
            assert_batch_outcome(result, path, outputs[0])
        else:
            assert_outcome(result, work, outputs, verdict=verdict)
        assert path.read_bytes() == data, "the input was changed"
    except CaseTimeout:
        return f"over the time limit ({TIME_LIMIT:.0f} s)", what, "timeout"
    except AssertionError as error:
        return " ".join(str(error).split())[:1500], what, ended
    return None, what, ended


# ---------------------------------------------------------------------------------------------------------------
# the long run: workers a crash cannot take down with it


def worker(start: int, stop: int, seeds: Path, work: Path) -> None:
    """Run cases [start, stop), one JSON line each on stdout (``{"begin": case}`` before it)."""
    out = os.fdopen(os.dup(1), "w", buffering=1)
    for case in range(start, stop):
        out.write(json.dumps({"begin": case}) + "\n")
        began = time.perf_counter()
        failure, what, ended = run_case(case, seeds, work)
        out.write(json.dumps({"case": case, "failure": failure, "what": what, "ended": ended,
                              "seconds": round(time.perf_counter() - began, 3)}) + "\n")


def _run_worker(start: int, stop: int, seeds: Path, work: Path, results: list, progress=lambda: None) -> int:
    """Run cases [start, stop) in one worker process; returns the first case not done (a crash ends a worker)."""
    command = [sys.executable, __file__, "--worker", str(start), str(stop), "--seeds", str(seeds), "--work", str(work)]
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)  # its own process group: stopped with its children
    _WORKERS.append(child)
    current = start
    for line in child.stdout:
        record = json.loads(line)
        if "begin" in record:
            current = record["begin"]
        else:
            results.append(record)
            current = record["case"] + 1
            progress()
    status = child.wait()
    if current < stop:  # the worker died in case `current`
        name, command_name = case_plan(current)
        results.append({"case": current, "failure": f"the process died (status {status}): {child.stderr.read()[-500:]}",
                        "what": f"case {current}: {command_name} {name}", "ended": "died", "seconds": None})
        return current + 1
    return stop


def long_run(start: int, count: int, jobs: int, folder: Path, progress=None, results=None) -> list:
    """Cases [start, start + count) over ``jobs`` worker processes in ``folder``; the records of all cases
    (appended to ``results`` as they come; ``progress()`` called after each)."""
    import threading

    seeds = make_seeds(folder / "seeds")
    signal.signal(signal.SIGTERM, _interrupt)  # make_seeds ran c1surf, whose handler would outlive it
    signal.signal(signal.SIGINT, _interrupt)
    bounds = [start + count * k // jobs for k in range(jobs + 1)]
    results = [] if results is None else results

    def share(k):
        position, stop = bounds[k], bounds[k + 1]
        while position < stop:
            position = _run_worker(position, stop, seeds, folder / f"work{k}", results, progress or (lambda: None))

    threads = [threading.Thread(target=share, args=(k,), daemon=True) for k in range(jobs)]
    for thread in threads:
        thread.start()
    try:
        while any(thread.is_alive() for thread in threads):
            threads[0].join(0.5) if threads[0].is_alive() else time.sleep(0.5)
    except KeyboardInterrupt:  # Ctrl-C, SIGTERM: the workers and their children stop, the report says so
        for child in _WORKERS:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(child.pid, signal.SIGKILL)
        raise
    return sorted(results, key=lambda r: r["case"])


_WORKERS: list = []  # the worker processes started by long_run


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=20000)
    parser.add_argument("--start", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--report", default="fuzz-report.json")
    parser.add_argument("--write", type=int, metavar="CASE", help="write case CASE's mutated file and command, run it")
    parser.add_argument("--worker", nargs=2, type=int)
    parser.add_argument("--seeds")
    parser.add_argument("--work")
    args = parser.parse_args()
    if args.worker:
        worker(*args.worker, Path(args.seeds), Path(args.work))
        return
    if args.write is not None:
        _write_case(args.write)
        return
    began = time.perf_counter()
    running: list = []

    def progress():  # the report so far, every 100 cases (a run cut short still says what it found)
        if len(running) % 100 == 0:
            _report(args, list(running), began, finished=False)

    with tempfile.TemporaryDirectory(prefix="c1surf-fuzz-") as folder:
        try:
            results = long_run(args.start, args.cases, args.jobs, Path(folder), progress, running)
        except KeyboardInterrupt:
            summary = _report(args, list(running), began, finished=False)
            print(f"interrupted after {summary['cases']} cases, {summary['failures']} failures (report: {args.report})")
            sys.exit(130)
    summary = _report(args, results, began, finished=True)
    failures = summary["failed"]
    print(f"{len(results)} cases, {len(failures)} failures, {summary['seconds']} s (report: {args.report})")
    for record in failures[:20]:
        print(f"  {record['what']}: {record['failure'][:300]}")
    sys.exit(1 if failures else 0)


def _report(args, results: list, began: float, finished: bool) -> dict:
    """Write the report of ``results`` (so far, or ``finished``) to ``args.report``; the report."""
    failures = sorted((r for r in results if r["failure"]), key=lambda r: r["case"])
    summary = {"finished": finished, "cases": len(results), "failures": len(failures),
               "seconds": round(time.perf_counter() - began, 1), "start": args.start, "asked": args.cases,
               "by_command": _counts(results), "endings": _endings(results), "failed": failures}
    Path(args.report).write_text(json.dumps(summary, indent=1) + "\n")
    return summary


def _write_case(case: int) -> None:
    """Case ``case``'s input in ./fuzz-case-CASE/ (with the seeds), its command line, and its verdict."""
    folder = Path(f"fuzz-case-{case}").resolve()
    seeds = make_seeds(folder / "seeds")
    failure, what, ended = run_case(case, seeds, folder / "work")
    name, command = case_plan(case)
    args, _, _ = command_line(command, folder / "work" / ("m" + Path(name).suffix), seeds / name, folder / "work")
    print(what)
    print("c1surf " + " ".join(map(str, args)))
    print(ended)
    print(failure or "meets the promise")


def _endings(results) -> dict:
    """How the cases ended: exit 0, exit 1 (refused or a verdict), Open CASCADE's crashes and time limits."""
    kinds = {"exit 0": "exit 0", "exit 1": "exit 1", "Open CASCADE crashed": "Open CASCADE crashed (contained)",
             "Open CASCADE took more than": "Open CASCADE stopped at its limit"}
    counts: dict = {}
    for record in results:
        for text, kind in kinds.items():
            if text in (record.get("ended") or ""):
                counts[kind] = counts.get(kind, 0) + 1
    return counts


def _counts(results) -> dict:
    counts: dict = {}
    for record in results:
        name, command = case_plan(record["case"])
        key = f"{command} {Path(name).suffix}"
        counts[key] = counts.get(key, 0) + 1
    return dict(sorted(counts.items()))


if __name__ == "__main__":
    main()
