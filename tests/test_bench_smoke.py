"""bench/run.py in --quick mode on the smallest inputs: it runs and writes results.json of the documented shape.

No timing is asserted here (timings belong to `make bench`, not to tests).
"""
from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

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


def test_bench_fit_smoke(tmp_path):
    """bench/fit.py on the smallest scan at few faces: a row with the fit's numbers and every baseline."""
    scans = ROOT.parent / "shared" / "scans"
    if not (scans / "goathead.obj").exists():
        import pytest

        pytest.skip("../shared/scans is not here")
    out = tmp_path / "fit.json"
    subprocess.run([sys.executable, str(ROOT / "bench" / "fit.py"), "--only", "goathead", "--faces", "100",
                    "--no-extras", "--pictures", "", "--out", str(out)],
                   check=True, capture_output=True, timeout=600)
    results = json.loads(out.read_text())
    assert results["format"] == "c1surf-fit-bench"
    (row,) = results["rows"]
    assert row["ok"] and row["scan"] == "goathead" and row["is_g1"] and row["g1_jump"] < 1e-9
    assert 50 <= row["control_faces"] <= 200 and row["patches"] >= row["control_faces"] and row["cad_faces"] > 0
    # 100 faces leave the horns coarse: 5 % of the diagonal at the worst vertex, 0.3 % RMS
    assert 0 < row["rms"] < 0.01 and row["rms"] <= row["p99"] <= row["max"] < 0.1 and 0 < row["surface_max"] < 0.1
    assert row["seconds"] > 0 and row["peak_mb"] > 0
    base = row["baselines"]
    assert base["direct"]["patches"] > 10 * row["patches"] and base["direct"]["ok"] and base["direct"]["seconds"] > 0
    assert base["control"]["faces"] == row["control_faces"]
    # fitting moves the surface nearer the scan than the unfitted control mesh's surface and Catmull-Clark's
    assert row["rms"] < base["control"]["rms"] and base["fit_rho"] > 0
    if importlib.util.find_spec("pymeshlab") is not None:  # a bench extra: the Catmull-Clark baseline
        assert row["rms"] < base["catmull_clark"]["rms"] and base["catmull_clark"]["rho"] > 0
    else:
        assert base["catmull_clark"] == {"error": "pymeshlab is not installed"}
    assert any(line.startswith("[") and "goathead RMS" in line for line in results["targets"])
    step = base["step"]
    assert step.get("error") == "OCP (Open CASCADE) is not installed" or (step["solids"] == 1 and step["valid"]), step


def test_bench_fit_curvature_on_a_sphere():
    """The shape column's discrete parts: the cotangent mean curvature of a fine sphere is 1/R, its ripple ~ 0."""
    import numpy as np
    import trimesh

    sys.path.insert(0, str(ROOT / "bench"))
    from fit import cotangent_mean_curvature, ripple

    sphere = trimesh.creation.icosphere(subdivisions=5, radius=2.0)
    H, area = cotangent_mean_curvature(np.asarray(sphere.vertices), np.asarray(sphere.faces))
    assert abs(area.sum() - 4 * np.pi * 4.0) < 1e-2 * 4 * np.pi * 4.0
    assert np.allclose(np.abs(H), 0.5, rtol=2e-2)
    assert ripple(np.asarray(sphere.vertices), H, area, 0.3) < 1e-2


def _bench_fit():
    spec = importlib.util.spec_from_file_location("bench_fit", ROOT / "bench" / "fit.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_cage_layout_counts_the_irregular_vertices_of_known_meshes():
    """Issue 43's layout column: a cube's 8 corners are all irregular (valence 3); a 3 x 3 sheet of quads has its
    4 rim corners irregular (valence 2), its 8 other rim vertices (3) and 4 interior ones (4) regular; a hexagon
    beside quads is one non-quad face."""
    layout = _bench_fit().cage_layout
    cube = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])
    assert layout(np.full(6, 4), cube.ravel(), 8) == {"vertices": 8, "irregular": 8, "non_quads": 0}
    i, j = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    v = (i * 4 + j).ravel()
    sheet = np.stack([v, v + 4, v + 5, v + 1], axis=1)
    assert layout(np.full(9, 4), sheet.ravel(), 16) == {"vertices": 16, "irregular": 4, "non_quads": 0}
    sizes = np.r_[np.full(9, 4), 6]
    assert layout(sizes, np.r_[sheet.ravel(), np.arange(16, 22)], 22)["non_quads"] == 1


def test_gaussian_ripple_is_zero_on_a_sphere_and_grows_with_a_bump():
    """The shape estimator of issue 43: H constant on a sphere leaves nothing after the Gaussian average; a ripple of
    amplitude a over the sphere's radius gives a rho that grows with a."""
    rng = np.random.default_rng(0)
    x = rng.normal(size=(40000, 3))
    x /= np.linalg.norm(x, axis=1)[:, None]
    weights = np.full(len(x), 4 * np.pi / len(x))
    ripple = _bench_fit().gaussian_ripple
    centres = np.arange(0, len(x), 10)
    assert ripple(x, np.ones(len(x)), weights, 0.1, centres) < 1e-12
    values = [ripple(x, 1 + a * np.sin(20 * x[:, 0]), weights, 0.1, centres) for a in (0.1, 0.2)]
    assert 0 < values[0] < values[1] and abs(values[1] / values[0] - 2) < 0.05


def test_layout_pictures_draws_a_cage_with_its_irregular_vertices(tmp_path):
    """bench/layout_pictures.py's cage panel (issue 43's before/after picture): a cube's cage is drawn and its 8
    corners are the irregular vertices it marks (the same count as ``cage_layout``); a 3 x 3 sheet marks its 4 rim
    corners."""
    sys.path.insert(0, str(ROOT / "bench"))
    spec = importlib.util.spec_from_file_location("layout_pictures", ROOT / "bench" / "layout_pictures.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    cube = tmp_path / "cube.obj"
    cube.write_text("".join(f"v {x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1))
                    + "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n")
    count, centre = module.cage_panel(cube, (25.0, 40.0), tmp_path / "cube.png")
    assert count == 8 and np.allclose([float(c) for c in centre], 0.5)
    assert (tmp_path / "cube.png").stat().st_size > 1000
    i, j = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    v = (i * 4 + j).ravel()
    sheet = np.stack([v, v + 4, v + 5, v + 1], axis=1)
    assert module.irregular_mask(np.full(9, 4), sheet.ravel(), 16).nonzero()[0].tolist() == [0, 3, 12, 15]
