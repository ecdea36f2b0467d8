"""Processes: every measurement runs in one of its own, timed from outside, its peak memory from ``os.wait4``.

Two kinds: the c1surf command line exactly as a user runs it
(``python -m c1surf.cli.main convert ...`` from the repository being measured),
and the harness's own workers (``run.py --worker JOB RESULT``: the peers, and
c1surf's in-memory phases).
"""
from __future__ import annotations

import json
import os
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from functools import lru_cache
from pathlib import Path

RUN_PY = Path(__file__).resolve().parents[1] / "run.py"
SETTINGS = {
    "root": RUN_PY.parents[1],  # the repository whose c1surf is measured (--c1surf-root)
    "memory_cap": None,  # bytes of address space per process (--memory-cap-gb); None: 70 % of the machine's
}


def memory_cap_bytes() -> int:
    """The per-process address-space cap: a run too large for the machine fails cleanly instead of swapping others out."""
    if SETTINGS["memory_cap"]:
        return int(SETTINGS["memory_cap"])
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    return int(int(line.split()[1]) * 1024 * 0.7)
    except OSError:
        pass
    return 16 << 30


def _environment() -> dict:
    root = str(SETTINGS["root"])
    return dict(os.environ, PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))


def run_process(argv: list, timeout: float, cwd=None, cap: int | None = None) -> dict:
    """Run ``argv``; {"ok", "seconds" (wall, start to exit), "cpu_seconds" (user + system), "peak_mb" (its maximum
    resident set), "stderr", "error"}; CPU time tells how much of the wall time other processes took.

    ``cap``: its address-space limit in bytes (default ``memory_cap_bytes()``).
    """
    cap = int(cap or memory_cap_bytes())

    def limit_memory():
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    if hasattr(os, "sync"):  # the writes of the processes before (a peer's 200 MB PLY) go to the disk now, not
        os.sync()  # while this one runs: their writeback showed as iowait in the next process's time
    start = time.perf_counter()
    process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=cwd, env=_environment(),
                               preexec_fn=limit_memory)
    timer = threading.Timer(timeout, process.kill)
    timer.start()
    try:
        stderr = process.stderr.read().decode(errors="replace")
        _, status, usage = os.wait4(process.pid, 0)
    finally:
        timed_out = not timer.is_alive()
        timer.cancel()
    seconds = time.perf_counter() - start
    code = os.waitstatus_to_exitcode(status)
    result = {"ok": code == 0, "seconds": seconds, "cpu_seconds": usage.ru_utime + usage.ru_stime,
              "peak_mb": usage.ru_maxrss / 1024.0, "stderr": stderr[-2000:]}
    if code != 0:
        lines = [line for line in stderr.strip().splitlines() if line.strip()]
        if timed_out:
            result["error"] = f"timed out after {timeout:.0f} s"
        elif code == -signal.SIGKILL:
            result["error"] = "killed (out of memory?)"
        else:
            result["error"] = lines[-1] if lines else f"exit status {code}"
    return result


def c1surf_argv(*args) -> list:
    """The command line of ``c1surf ARGS`` from the repository being measured (its own code, not an installed copy)."""
    return [sys.executable, "-m", "c1surf.cli.main", *map(str, args)]


def run_c1surf(args: list, timeout: float, cap: int | None = None) -> dict:
    """``c1surf ARGS`` as a user runs it, in a process of its own (``run_process``)."""
    return run_process(c1surf_argv(*args), timeout, cwd=SETTINGS["root"], cap=cap)


@lru_cache(maxsize=None)
def convert_help() -> str:
    """The text of ``c1surf convert --help`` (which options this c1surf has)."""
    return subprocess.run(c1surf_argv("convert", "--help"), capture_output=True, text=True, cwd=SETTINGS["root"],
                          env=_environment()).stdout


def run_worker(job: dict, timeout: float) -> dict:
    """Run one harness worker (``run.py --worker``); its result, with the process's wall time and peak memory."""
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        result_path = f.name
    try:
        process = run_process([sys.executable, str(RUN_PY), "--worker", json.dumps(job), result_path], timeout,
                              cwd=SETTINGS["root"])
        text = Path(result_path).read_text() if os.path.getsize(result_path) else ""
    finally:
        os.unlink(result_path)
    if not process["ok"] or not text:
        return {"ok": False, "error": process.get("error", "no result"), "peak_mb": process["peak_mb"]}
    result = json.loads(text)
    result.update(ok=True, peak_mb=process["peak_mb"], wall_seconds=process["seconds"], cpu_seconds=process["cpu_seconds"])
    return result


def _median_tree(values: list):
    """Medians of numbers, key by key through nested dicts; anything else as the first value has it."""
    first = values[0]
    if isinstance(first, dict):
        return {k: _median_tree([v[k] for v in values if k in v]) for k in first}
    if isinstance(first, (int, float)) and not isinstance(first, bool):
        return statistics.median(values)
    return first


def median_of(results: list[dict]) -> dict:
    """Medians over repeated processes (times, peaks, phases); the first error if none succeeded."""
    good = [r for r in results if r["ok"]]
    if not good:
        return {"ok": False, "error": results[0]["error"], "peak_mb": max(r["peak_mb"] for r in results),
                "repeats": len(results)}
    summary = _median_tree([{k: v for k, v in r.items() if k not in ("output", "stderr")} for r in good])
    summary.update(output=good[0].get("output"), repeats=len(good), failures=len(results) - len(good))
    if isinstance(good[0].get("seconds"), float):
        summary["all_seconds"] = [r["seconds"] for r in good]
    return summary


def repeated(measure, count: int) -> dict:
    """``median_of`` ``count`` calls of ``measure()``, stopping at the first failure."""
    runs = []
    for _ in range(count):
        runs.append(measure())
        if not runs[-1]["ok"]:
            break
    return median_of(runs)
