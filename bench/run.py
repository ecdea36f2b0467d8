#!/usr/bin/env python
"""c1surf against the subdivision libraries a user would pick instead (``make bench``).

    python bench/run.py            # full run (about 30 minutes on a 2-core machine)
    python bench/run.py --quick    # smoke run: small inputs, one repeat, under a minute

What it measures, every measurement in a process of its own (peak memory: the
process's maximum resident set from ``os.wait4``, interpreter and imports
included for every tool alike; times: medians over ``--repeats`` processes, one
process for the largest outputs):

1. whole process, the way a user runs it: ``c1surf convert in.obj -o out.ply -r 2``
   (``python -m c1surf.cli.main`` from the repository this script lives in, or
   ``--c1surf-root``), against each peer's whole job: read the OBJ with its own
   reader, subdivide 2 levels (pymeshlab and pyOpenSubdiv Catmull-Clark on the
   polygons, libigl and trimesh Loop on the triangles), write a binary PLY.
   -r 2 gives one vertex per refined face: the vertex count of two subdivision
   levels (2,880,000 for the 180,000-quad torus and for Loop x2 on its
   360,000-triangle split);
2. in memory: c1surf's build + N=2 tessellation through its Python API, phase by
   phase, and ``update_points``; the peers' subdivision call alone;
3. a 100,000-triangle torus at the default resolution (-r 8);
4. quad tori up to 4,000,000 faces (c1surf only above 400,000; its in-memory
   worker only up to ``--max-memory-faces``);
5. the tessellation throughput at N=8 against two numpy limits: all outputs (positions, unit normals,
   triangles of every sample, unwelded) and positions only (one GEMM);
6. fidelity: distances from the input's vertices to each tool's surface and the
   enclosed volume (spot, sword, small tori);
7. ``--tolerance`` (when this c1surf has it): triangles against the uniform
   resolution of the same measured chordal error, on the sample meshes and spot;
   ``check`` and ``measure`` of the 100,000-triangle torus's patch file (1.2 M patches) against the
   ``convert`` that wrote it, the three processes in turn (issues 30 and 36's targets), and of the meshes
   of ``--check-inputs`` (ogre.obj of the common-3d-test-models set: 1.49 M patches); ``--only-check`` runs
   these rows alone.
8. then (not with --quick or --no-fit) ``bench/fit.py``: ``c1surf fit`` on every scan of ../shared/scans
   against its baselines (issue 29), into bench/fit_results.json; docs/fit.md shows its table.

It writes bench/results.json and bench/results.png and prints the tables and
issue 15's targets (met, not met, or not measured and why). Generated inputs
are cached in ``--inputs``.
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from harness import tables
from harness.meshes import cached_torus_obj, ply_counts, read_polygon_obj
from harness.peers import PEERS
from harness.processes import SETTINGS, convert_help, median_of, repeated, run_c1surf, run_worker
from harness.report import DEFAULT_RESOLUTION_INPUT, Targets, comparisons, targets

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("C1SURF_SHARED_MESHES", HERE.parent.parent / "shared" / "meshes"))
REAL_MESHES = {"sword": SHARED / "odedstein-meshes" / "sword-quad-dominant.obj",
               "spot": SHARED / "spot" / "spot_quadrangulated.obj"}
SAMPLE_MESHES = HERE.parent / "sample_meshes"
# (nu, nv, triangles): quad tori of nu x nv faces, triangle tori of 2 nu nv
FULL_TORI = [(50, 20, False), (125, 80, False), (500, 200, False), (600, 300, False), (1250, 800, False),
             (2500, 1600, False), (50, 10, True), (125, 40, True), (500, 100, True), (600, 150, True), (600, 300, True)]
QUICK_TORI = [(50, 20, False), (50, 10, True)]
FIDELITY_INPUTS = ("spot", "sword", "torus-quad-1000", "torus-tri-1000")
QUICK_FIDELITY_INPUTS = ("torus-quad-1000",)
TOLERANCES = (1e-3, 3e-4)
FIDELITY_LEVELS = 3  # subdivision levels of the peers' surfaces
# what a worker process runs, imported there only (a peer's process imports numpy and the peer, not scipy)
WORKERS = {"c1surf": "workers:work_c1surf", "throughput": "workers:work_throughput", "limit": "workers:work_limit",
           "fidelity": "fidelity:work_fidelity", "tolerance": "tolerance:work_tolerance"}


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------------------------
# inputs


def make_inputs(directory: Path, args) -> list[dict]:
    """The generated tori (cached OBJ files) and the real meshes that are present."""
    inputs = []
    for nu, nv, tri in QUICK_TORI if args.quick else FULL_TORI:
        faces = nu * nv * (2 if tri else 1)
        if faces > args.max_faces:
            continue
        name = f"torus-{'tri' if tri else 'quad'}-{faces}"
        log(f"bench: input {name}")
        path = cached_torus_obj(directory, name, nu, nv, tri)
        inputs.append({"name": name, "kind": "triangle torus" if tri else "quad torus", "path": str(path),
                       "faces": faces, "vertices": nu * nv, "grid": [nu, nv]})
    for name, path in REAL_MESHES.items() if not (args.no_real or args.quick) else ():
        if path.exists():
            points, sizes, _ = read_polygon_obj(path)
            inputs.append({"name": name, "kind": "real mesh", "path": str(path), "faces": int(len(sizes)),
                           "vertices": int(len(points))})
    return inputs


def repeats_for(faces: int, resolution: int, repeats: int) -> int:
    """One process for outputs above 400,000 faces at -r 2 (minutes each), ``repeats`` below: the in-memory
    worker and the peers. c1surf's whole-process conversions at -r 2 always take ``repeats`` (``measure_c1surf``)."""
    return 1 if faces * resolution**2 > 1_600_000 else repeats


# ---------------------------------------------------------------------------------------------------------
# measurements


def convert_process(item: dict, options: list, args) -> dict:
    """``c1surf convert INPUT -o out.ply OPTIONS`` as a process of its own; output counts from the PLY's header.

    Above --max-memory-faces the process gets the smaller --large-memory-cap-gb.
    """
    target = Path(args.scratch) / f"convert-{os.getpid()}.ply"
    cap = args.large_memory_cap_gb * 2**30 if item["faces"] > args.max_memory_faces else None
    result = run_c1surf(["convert", item["path"], "-o", target, *options], args.timeout, cap)
    if result["ok"]:
        result["output"] = ply_counts(target)
    elif cap:
        result["error"] += f" (address-space cap {args.large_memory_cap_gb:g} GiB)"
    target.unlink(missing_ok=True)
    return result


def measure_c1surf(item: dict, args, count: int, process_count: int | None = None) -> dict:
    """c1surf on one input: the command line (whole process) and, up to --max-memory-faces, the in-memory worker.

    ``count`` processes of the worker, ``process_count`` (default ``count``) of the command line: the time per
    face target reads the whole-process medians up to 4,000,000 faces, and one process of the largest tori
    varied by a third between runs on this machine (its first touches of memory cost what the host makes them).
    """
    entry = {"process": repeated(lambda: convert_process(item, ["-r", "2"], args), process_count or count)}
    if item["faces"] > args.max_memory_faces:
        reason = f"skipped: in-memory worker above {args.max_memory_faces:,} faces"
        entry.update(ok=False, skipped=reason, error=reason)
        return entry
    job = {"tool": "c1surf", "path": item["path"], "resolution": 2, "scratch": args.scratch}
    memory = repeated(lambda: run_worker(job, args.timeout), count)
    if memory["ok"]:  # peak of read + build + tessellation, like the peers' read + subdivision; the worker's whole too
        memory.update(worker_peak_mb=memory["peak_mb"], peak_mb=memory["peak_mb_after"]["tessellation"])
    return {**memory, **entry}


def measure_peer(item: dict, tool: str, args, count: int) -> dict:
    """A peer's whole process (read, 2 levels, binary PLY); its subdivision call is the in-memory number."""
    job = {"tool": tool, "path": item["path"], "levels": 2, "output": str(Path(args.scratch) / f"{tool}-out.ply")}
    summary = repeated(lambda: run_worker(job, args.timeout), count)
    Path(job["output"]).unlink(missing_ok=True)
    if not summary["ok"]:
        return {**summary, "process": summary}
    process = {"ok": True, "seconds": summary["wall_seconds"], "cpu_seconds": summary["cpu_seconds"],
               "peak_mb": summary["peak_mb"], "output": summary["output"]}
    return {**summary, "peak_mb": summary["peak_mb_after"]["convert"], "process": process}


def guarded(measure, *args) -> dict:
    """``measure(*args)``, or a failed entry saying why: one broken measurement never stops the run."""
    try:
        return measure(*args)
    except Exception as e:  # noqa: BLE001 - recorded in results.json and shown in the tables
        log(f"bench: FAILED: {type(e).__name__}: {e}")
        return {"ok": False, "error": f"harness: {type(e).__name__}: {e}", "peak_mb": 0.0}


def save_partial(args, runs) -> None:
    """The speed runs so far, in case the run is stopped (the complete file replaces it at the end)."""
    Path(args.out).with_suffix(".partial.json").write_text(json.dumps(runs, indent=1) + "\n")


def measure_speed(inputs, tools, args, repeats: int) -> list[dict]:
    runs = []
    for item in inputs:
        for tool in tools:
            if tool != "c1surf" and item["faces"] > args.max_peer_faces:
                continue
            count = repeats_for(item["faces"], 2, repeats)
            if tool == "c1surf":
                entry = guarded(measure_c1surf, item, args, count, repeats)
            else:
                entry = guarded(measure_peer, item, tool, args, count)
            entry.setdefault("process", {"ok": False, "error": entry.get("error")})
            entry.update(input=item["name"], tool=tool, faces=item["faces"])
            runs.append(entry)
            save_partial(args, runs)
            p = entry["process"]
            memory = f"{entry['seconds']['convert']:.3f} s" if entry["ok"] else entry.get("skipped", "failed")
            log(f"bench: {item['name']:>20} {tool:>13} whole "
                + (f"{p['seconds']:7.2f} s {p['peak_mb']:7.0f} MB" if p["ok"] else f"FAILED ({p['error']})")
                + f"; in memory {memory}")
    return runs


def measure_default_resolution(inputs, args, repeats: int) -> dict | None:
    """The 100,000-triangle torus (quick: the largest triangle torus) converted at the default resolution."""
    tri = [i for i in inputs if i["kind"] == "triangle torus"]
    item = next((i for i in tri if i["name"] == DEFAULT_RESOLUTION_INPUT), tri[0] if args.quick and tri else None)
    if item is None:
        return None
    log(f"bench: {item['name']} at the default resolution ...")
    result = repeated(lambda: convert_process(item, [], args), repeats_for(item["faces"], 8, repeats))
    result.update(input=item["name"], faces=item["faces"], resolution="default (8)")
    return result


def measure_check(inputs, args, repeats: int) -> dict | None:
    """Issues 30 and 36: ``convert IN -r 2 --patches x.npz``, then ``check x.npz`` and ``measure x.npz``, the three
    processes taken in turn ``repeats`` times (medians), on the 100,000-triangle torus (quick: the largest
    triangle torus)."""
    tri = [i for i in inputs if i["kind"] == "triangle torus"]
    item = next((i for i in tri if i["name"] == DEFAULT_RESOLUTION_INPUT), tri[0] if args.quick and tri else None)
    return None if item is None else check_and_measure(item, args, repeats)


def measure_more_checks(args, repeats: int) -> list[dict]:
    """``measure_check``'s rows on the meshes of ``--check-inputs`` (ogre.obj of the common-3d-test-models set:
    issue 36's 1.49 M patches at -r 2), each named by its file's stem."""
    rows = []
    for path in filter(None, (p.strip() for p in args.check_inputs.split(","))):
        item = {"name": Path(path).stem, "path": str(Path(path).resolve()), "faces": None}
        rows.append(guarded(check_and_measure, item, args, repeats) if Path(path).exists()
                    else {"input": item["name"], "ok": False, "error": f"{path} does not exist"})
    return rows


def check_and_measure(item: dict, args, repeats: int) -> dict:
    """convert (writing the NPZ), check and measure of it, in turn, ``repeats`` times; their medians, and the
    machine's load average before the first and after the last (the 2-core VM is shared)."""
    log(f"bench: check and measure of {item['name']}'s patch file against the convert that wrote it ...")
    npz, ply = Path(args.scratch) / f"check-{os.getpid()}.npz", Path(args.scratch) / f"check-{os.getpid()}.ply"
    runs, load = {"convert": [], "check": [], "measure": []}, [os.getloadavg()]
    commands = {"convert": ["convert", item["path"], "-o", ply, "-r", "2", "-q", "--patches", npz],
                "check": ["check", npz, "-q"], "measure": ["measure", npz, "-q"]}
    for _ in range(repeats):
        for name, command in commands.items():
            runs[name].append(run_c1surf(command, args.timeout))
            if not runs[name][-1]["ok"]:
                break
        if not all(r[-1]["ok"] for r in runs.values() if r) or not runs["measure"]:
            break
    load.append(os.getloadavg())
    npz.unlink(missing_ok=True)
    ply.unlink(missing_ok=True)
    failed = {"ok": False, "error": "convert failed", "peak_mb": 0}
    return {"input": item["name"], "faces": item["faces"], "load_average": load,
            **{name: median_of(r) if r else failed for name, r in runs.items()}}


def measure_limits(args, repeats: int) -> dict:
    grid = (50, 20) if args.quick else (250, 250)  # 16,000 / 1,000,000 patches
    log("bench: tessellation throughput at N=8, and the numpy limit ...")
    return {"throughput": run_worker({"tool": "throughput", "grid": list(grid), "resolution": 8, "repeats": repeats},
                                     args.timeout),
            "limit": run_worker({"tool": "limit", "patches": 16_000 if args.quick else 1_000_000,
                                 "repeats": max(3, repeats)}, args.timeout)}


def measure_fidelity(inputs, tools, args) -> list[dict]:
    """Every tool's surface against each fidelity input: c1surf at two blends, the peers after 3 levels."""
    variants = [("c1surf", "c1surf, default blend (0.5)", []), ("c1surf", "c1surf --blend 0.2", ["--blend", "0.2"])]
    variants = [v for v in variants[: 1 if args.quick else None] if "c1surf" in tools]
    variants += [(t, f"{PEERS[t].label} x{FIDELITY_LEVELS}", None) for t in tools if t in PEERS]
    out = []
    for item in [i for i in inputs if i["name"] in (QUICK_FIDELITY_INPUTS if args.quick else FIDELITY_INPUTS)]:
        for tool, label, options in variants:
            log(f"bench: fidelity {item['name']} {label} ...")
            job = {"tool": "fidelity", "root": str(SETTINGS["root"]), "path": item["path"], "scratch": args.scratch,
                   "timeout": args.timeout, "budget": 1_000_000 if args.quick else 6_000_000, "max_resolution": 16,
                   "coarse_resolution": 3, "options": options or [], "levels": FIDELITY_LEVELS}
            result = run_worker({**job, "measured": tool}, args.timeout)
            out.append({**result, "input": item["name"], "tool": tool, "label": label})
    return out


def measure_tolerance(inputs, args) -> dict:
    if "--tolerance" not in convert_help():
        return {"skipped": "this c1surf's convert has no --tolerance option"}
    meshes = sorted(SAMPLE_MESHES.glob("*.obj"))[: 1 if args.quick else None]
    meshes += [Path(i["path"]) for i in inputs if i["name"] == "spot" and not args.quick]
    out = []
    for path in meshes:
        log(f"bench: --tolerance on {path.stem} ...")
        job = {"tool": "tolerance", "root": str(SETTINGS["root"]), "path": str(path), "scratch": args.scratch,
               "timeout": args.timeout, "tolerances": list(TOLERANCES[:1] if args.quick else TOLERANCES),
               "budget": 500_000 if args.quick else 12_500_000 if path.stem == "spot" else 4_000_000, "max_resolution": 64}
        out.append({**run_worker(job, args.timeout), "input": path.stem})
    return {"meshes": out}


# ---------------------------------------------------------------------------------------------------------
# driver


def installed_peers(wanted) -> list[str]:
    found = []
    for tool in wanted:
        if subprocess.run([sys.executable, "-c", f"import {PEERS[tool].module}"], capture_output=True).returncode == 0:
            found.append(tool)
        else:
            log(f"bench: {tool} is not installed (pip install -e '.[bench]'); skipped")
    return found


def versions() -> dict:
    from importlib.metadata import version

    out = {"python": platform.python_version(), "numpy": np.__version__}
    for tool, dist in (("scipy", "scipy"), ("pymeshlab", "pymeshlab"), ("igl", "libigl"), ("trimesh", "trimesh"),
                       ("pyopensubdiv", "pyOpenSubdiv")):
        try:
            out[tool] = version(dist)
        except Exception:
            pass
    def git(*words):
        return subprocess.run(["git", "-C", str(SETTINGS["root"]), *words], capture_output=True, text=True).stdout.strip()

    out["c1surf"] = git("rev-parse", "--short", "HEAD") or "unknown"  # the checkout measured
    out["c1surf_code"] = git("log", "-1", "--format=%h", "--", "c1surf") or "unknown"  # its last change under c1surf/
    return out


def machine() -> dict:
    info = {"cores": os.cpu_count(), "platform": platform.platform(), "load_average_at_start": os.getloadavg()}
    with open("/proc/meminfo") as f:
        info["memory_gb"] = round(int(f.readline().split()[1]) / 2**20, 1)
    return info


def compile_bytecode(package: Path) -> str:
    """Write the measured checkout's bytecode before anything is timed, as ``pip install`` does for the peers'
    packages: without it a ``PYTHONDONTWRITEBYTECODE`` environment (or a read-only checkout) makes every c1surf
    process compile its ~80 modules again (0.15 s of each whole-process time here), which no installed tool pays."""
    import compileall

    ok = compileall.compile_dir(str(package), quiet=1)
    return "compiled" if ok else "compiled with errors"


def run(args) -> dict:
    repeats = args.repeats or (1 if args.quick else 3)
    Path(args.scratch).mkdir(parents=True, exist_ok=True)
    inputs = make_inputs(Path(args.inputs), args)
    tools = (["c1surf"] if "c1surf" in args.tools else []) + installed_peers([t for t in args.tools if t in PEERS])
    results = {"format": "c1surf-bench", "version": 2, "quick": bool(args.quick), "repeats": repeats,
               "machine": machine(), "versions": versions(), "c1surf_root": str(SETTINGS["root"]), "inputs": inputs}
    started = time.perf_counter()
    if "c1surf" in tools:
        results["bytecode"] = compile_bytecode(Path(SETTINGS["root"]) / "c1surf")
        results["startup"] = repeated(lambda: run_c1surf(["--version"], args.timeout), repeats)
    results["runs"] = measure_speed(inputs, tools, args, repeats)
    if "c1surf" in tools:
        results["default_resolution"] = guarded(measure_default_resolution, inputs, args, repeats)
        results["check"] = guarded(measure_check, inputs, args, repeats)
        results["check_more"] = measure_more_checks(args, repeats)
        limits = guarded(measure_limits, args, repeats)
        results.update(limits if "limit" in limits else {"throughput": limits, "limit": limits})
        results["tolerance"] = guarded(measure_tolerance, inputs, args)
    fidelity = guarded(measure_fidelity, inputs, tools, args)
    results["fidelity"] = fidelity if isinstance(fidelity, list) else [{**fidelity, "input": "-", "tool": "-", "label": "-"}]
    results["elapsed_seconds"] = time.perf_counter() - started
    results["machine"]["load_average_at_end"] = os.getloadavg()
    results["comparisons"] = comparisons(results)
    results["targets"] = targets(results)
    return results


def check_rows_only(args) -> int:
    """``--only-check``: the torus's and ``--check-inputs``' check and measure rows, printed and written to --out."""
    repeats = args.repeats or (1 if args.quick else 3)
    SETTINGS["root"] = Path(args.c1surf_root).resolve()
    args.max_faces, args.no_real = min(args.max_faces, 100_000), True  # the torus of the rows and the smaller ones
    inputs = make_inputs(Path(args.inputs), args)
    results = {"format": "c1surf-bench-check", "repeats": repeats, "machine": machine(), "versions": versions(),
               "check": guarded(measure_check, inputs, args, repeats), "check_more": measure_more_checks(args, repeats)}
    rows = Targets(results)
    rows.check_at_scale()
    results["targets"] = rows.rows
    Path(args.out).write_text(json.dumps(results, indent=1) + "\n")
    for t in results["targets"]:
        print(f"[{t['status']}] {t['target']}: {t['value']} (goal {t['goal']}) {t['note']}")
    return 0


def print_report(results) -> None:
    sections = [
        ("Whole process, seconds (peak MB): `c1surf convert in.obj -o out.ply -r 2`; each peer reads the OBJ, "
         "subdivides 2 levels, writes a binary PLY", tables.process_table),
        ("In memory, seconds (peak MB after it): c1surf build + N=2 tessellation; the peers' subdivision call",
         tables.memory_table),
        ("c1surf's phases in memory (seconds)", tables.phase_table),
        ("The default resolution (`c1surf convert in.obj -o out.ply`)", tables.default_resolution_table),
        ("Fidelity: distance from the input's vertices to each surface (relative to the bounding-box diagonal), "
         "enclosed volume over the input's", tables.fidelity_table),
        ("--tolerance against uniform resolution", tables.tolerance_table),
    ]
    for title, table in sections:
        print(f"{title}\n\n{table(results)}\n")
    print(f"start-up of the c1surf command line (`--version`): {results.get('startup', {}).get('seconds', float('nan')):.2f} s\n")
    for t in results["targets"]:
        print(f"[{t['status']}] {t['target']}: {t['value']} (goal {t['goal']}) {t['note']}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="small inputs, one repeat (a smoke run)")
    parser.add_argument("--repeats", type=int, default=0, help="processes per measurement (default 3, quick 1)")
    parser.add_argument("--tools", default=",".join(tables.TOOLS), help=f"comma-separated subset of {','.join(tables.TOOLS)}")
    parser.add_argument("--max-faces", type=int, default=10**9, help="skip generated inputs with more faces")
    parser.add_argument("--max-peer-faces", type=int, default=400_000, help="run the peers only up to this many faces")
    parser.add_argument("--max-memory-faces", type=int, default=1_000_000,
                        help="run c1surf's in-memory worker only up to this many faces (it holds the whole surface)")
    parser.add_argument("--no-real", action="store_true", help="skip the meshes of ../shared/meshes (--quick skips them too)")
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds per process")
    parser.add_argument("--memory-cap-gb", type=float, default=0.0,
                        help="address-space cap per process (default: 70%% of the machine's memory)")
    parser.add_argument("--large-memory-cap-gb", type=float, default=12.0,
                        help="address-space cap of the conversions above --max-memory-faces (the 4,000,000-quad torus, "
                             "whose target is 8 GB): a conversion that needs more fails there instead of crowding the machine")
    parser.add_argument("--c1surf-root", default=str(HERE.parent), help="repository whose c1surf is measured (default: this one)")
    parser.add_argument("--inputs", default=str(Path(tempfile.gettempdir()) / "c1surf-bench-inputs"),
                        help="folder for the generated input files, kept between runs")
    parser.add_argument("--out", default=str(HERE / "results.json"))
    parser.add_argument("--plot", default=str(HERE / "results.png"), help="PNG plot ('' for none)")
    parser.add_argument("--no-fit", action="store_true",
                        help="skip bench/fit.py (c1surf fit on ../shared/scans; --quick skips it too)")
    parser.add_argument("--check-inputs", default="",
                        help="more meshes for the check and measure rows, comma-separated (issue 36: ogre.obj of the "
                             "common-3d-test-models set, 1.49 M patches at -r 2; not in ../shared)")
    parser.add_argument("--only-check", action="store_true",
                        help="run the check and measure rows only (convert, check and measure of the torus's and "
                             "--check-inputs' patch files, in turn), into --out (default bench/check_results.json)")
    parser.add_argument("--worker", nargs=2, metavar=("JOB", "RESULT"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        job = json.loads(args.worker[0])
        module, function = WORKERS.get(job["tool"], "workers:work_peer").split(":")
        result = getattr(importlib.import_module(f"harness.{module}"), function)(job)
        Path(args.worker[1]).write_text(json.dumps(result))
        return 0
    args.tools = [t.strip() for t in args.tools.split(",") if t.strip()]
    unknown = set(args.tools) - set(tables.TOOLS)
    if unknown:
        parser.error(f"unknown tools {sorted(unknown)}; choose from {', '.join(tables.TOOLS)}")
    SETTINGS.update(root=Path(args.c1surf_root).resolve(), memory_cap=args.memory_cap_gb * 2**30)
    Path(args.inputs).mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="c1surf-bench-") as scratch:
        args.scratch = scratch
        if args.only_check:
            if Path(args.out) == HERE / "results.json":  # the whole bench's file is not replaced by these rows
                args.out = str(HERE / "check_results.json")
            return check_rows_only(args)
        results = run(args)
    Path(args.out).write_text(json.dumps(results, indent=1) + "\n")
    Path(args.out).with_suffix(".partial.json").unlink(missing_ok=True)
    if args.plot:
        tables.plot(results, Path(args.plot))
    print_report(results)
    print(f"\nwrote {args.out}" + (f" and {args.plot}" if args.plot else "") + f" in {results['elapsed_seconds']:.0f} s")
    if not (args.quick or args.no_fit):  # issue 29's section: its own results file (bench/fit_results.json)
        print("\nc1surf fit on ../shared/scans (bench/fit.py)\n", flush=True)
        return subprocess.run([sys.executable, str(HERE / "fit.py"), "--c1surf-root", args.c1surf_root]).returncode
    return 0


if __name__ == "__main__":
    sys.exit(main())
