"""bench/run.py in --quick mode on the smallest inputs: it runs and writes results.json of the documented shape.

No timing is asserted here (timings belong to `make bench`, not to tests).
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_bench_quick_smoke(tmp_path):
    out = tmp_path / "results.json"
    subprocess.run(
        [sys.executable, str(ROOT / "bench" / "run.py"), "--quick", "--max-faces", "1000", "--no-real",
         "--tools", "c1surf,trimesh", "--repeats", "1", "--inputs", str(tmp_path / "inputs"),
         "--out", str(out), "--plot", str(tmp_path / "plot.png")],
        check=True, capture_output=True, timeout=120,
    )
    results = json.loads(out.read_text())
    assert results["format"] == "c1surf-bench" and results["quick"] is True
    names = {i["name"] for i in results["inputs"]}
    assert names == {"torus-quad-1000", "torus-tri-1000"}
    runs = {(r["input"], r["tool"]): r for r in results["runs"]}
    for name in names:
        mine = runs[(name, "c1surf")]
        assert mine["ok"], mine
        phases = mine["seconds"]
        for phase in ("read", "topology", "refinement", "patches", "geometry", "tessellation", "write", "update_points", "convert"):
            assert phase in phases and phases[phase] >= 0
        assert mine["peak_mb"] > 0 and mine["output"]["vertices"] > 0
        assert runs[(name, "trimesh")]["ok"]
        # the whole process, as a user runs it: c1surf convert's command line and the peer's read + subdivide + write
        for tool in ("c1surf", "trimesh"):
            process = runs[(name, tool)]["process"]
            assert process["ok"] and process["seconds"] > 0 and process["peak_mb"] > 0, process
        assert runs[(name, "c1surf")]["process"]["output"]["vertices"] == mine["output"]["vertices"]
    # quad torus at resolution 2: one vertex per refined face, as many as two Catmull-Clark levels
    quad = runs[("torus-quad-1000", "c1surf")]["output"]
    assert quad["vertices"] == 16 * 1000
    assert results["throughput"]["ok"] and results["limit"]["ok"]
    assert {c["peer"] for c in results["comparisons"]} == {"trimesh"}
    assert all({"target", "value", "goal", "met"} <= set(t) for t in results["targets"])
    fidelity = {(f["input"], f["tool"]): f for f in results["fidelity"]}
    for tool in ("c1surf", "trimesh"):
        f = fidelity[("torus-quad-1000", tool)]
        assert f["ok"] and 0 <= f["mean"] <= f["max"] < 0.01 and 0.95 < f["volume_ratio"] < 1.0, f
    assert (tmp_path / "plot.png").stat().st_size > 0


def test_bench_floors_runs():
    """bench/floors.py (what bounds update_points) on a small torus: it runs and prints its four readings."""
    done = subprocess.run([sys.executable, str(ROOT / "bench" / "floors.py"), "--grid", "20", "10", "--repeats", "1"],
                          check=True, capture_output=True, text=True, timeout=120)
    lines = done.stdout.splitlines()
    assert lines[0].startswith("3,200 biquadratic patches") and len(lines) == 5, done.stdout
    assert lines[2].startswith("update_points:") and lines[4].startswith("floor, gather 9 points per patch")
