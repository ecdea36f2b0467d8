"""Markdown tables of results.json, and the plot (time per input face against faces)."""
from __future__ import annotations

from pathlib import Path

from .peers import PEERS
from .report import run_of

TOOLS = ("c1surf",) + tuple(PEERS)
PHASES = ("read", "topology", "refinement", "patches", "geometry", "tessellation", "write", "update_points")


def markdown(header: list, rows: list) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(str(c) for c in row) + " |" for row in rows])


def _g(value, digits=3) -> str:
    return "" if value is None else f"{value:.{digits}g}"


def _cell(entry, seconds, peak) -> str:
    """"s (peak MB)" of a measurement, "failed: why", or blank when not run."""
    if entry is None:
        return ""
    if not entry.get("ok"):
        return entry.get("skipped") or f"failed at {entry.get('peak_mb', 0):.0f} MB: " + entry.get("error", "")[:60]
    return f"{seconds(entry):.3g} ({peak(entry):.0f})"


def _tools(results) -> list:
    return [t for t in TOOLS if any(r["tool"] == t for r in results["runs"])]


def _per_input(results, cell, extra=None) -> str:
    tools = _tools(results)
    header = ["input", "faces"] + [f"{t} s (peak MB)" for t in tools] + ([extra[0]] if extra else [])
    rows = []
    for item in results["inputs"]:
        row = [item["name"], f"{item['faces']:,}"] + [cell(run_of(results, item["name"], t)) for t in tools]
        rows.append(row + ([extra[1](item)] if extra else []))
    return markdown(header, rows)


def process_table(results) -> str:
    """Whole processes: c1surf's command line at -r 2 and each peer's read + 2 levels + binary PLY."""
    def vertices(item):
        r = run_of(results, item["name"], "c1surf")
        return f"{r['process']['output']['vertices']:,}" if r and r.get("process", {}).get("ok") else ""

    return _per_input(results, lambda r: _cell(r and r.get("process"), lambda e: e["seconds"], lambda e: e["peak_mb"]),
                      ("c1surf output vertices", vertices))


def memory_table(results) -> str:
    """In memory: c1surf build + N=2 tessellation, the peers' subdivision call; peak after it."""
    def update(item):
        r = run_of(results, item["name"], "c1surf")
        return _g(r["seconds"]["update_points"]) if r and r["ok"] else ""

    return _per_input(results, lambda r: _cell(r, lambda e: e["seconds"]["convert"], lambda e: e["peak_mb"]),
                      ("c1surf update_points s", update))


def phase_table(results) -> str:
    rows = [[r["input"]] + [_g(r["seconds"].get(p)) for p in PHASES] + [_g(r["seconds"]["convert"]), f"{r['peak_mb']:.0f}",
                                                                       f"{r['worker_peak_mb']:.0f}"]
            for r in results["runs"] if r["tool"] == "c1surf" and r["ok"]]
    return markdown(["input", *PHASES, "convert", "peak MB (to tessellation)", "peak MB (worker)"], rows)


def default_resolution_table(results) -> str:
    d = results.get("default_resolution")
    if not d:
        return "(default resolution: not run)"
    if not d.get("ok"):
        return f"(default resolution on {d.get('input')}: failed: {d.get('error')})"
    return markdown(["input", "faces", "resolution", "seconds", "peak MB", "output vertices", "output triangles"],
                    [[d["input"], f"{d['faces']:,}", d["resolution"], _g(d["seconds"]), f"{d['peak_mb']:.0f}",
                      f"{d['output']['vertices']:,}", f"{d['output']['triangles']:,}"]])


def fidelity_table(results) -> str:
    rows = []
    for f in results.get("fidelity", []):
        if not f.get("ok"):
            rows.append([f["input"], f["label"], "failed: " + f.get("error", "")[:80], "", "", "", ""])
            continue
        coarse = f.get("coarse")
        rows.append([f["input"], f["label"], f"-r {f['resolution']}" if "resolution" in f else f"{f['levels']} levels",
                     f"{f['mean']:.2g}", f"{f['max']:.2g}", _g(f["volume_ratio"], 5),
                     f"-r {coarse['resolution']}: {coarse['mean']:.2g} / {coarse['max']:.2g} / {_g(coarse['volume_ratio'], 5)}"
                     if coarse else ""])
    return markdown(["input", "surface", "measured on", "mean distance", "max distance", "volume / input's",
                     "coarser tessellation: mean / max / volume"], rows)


def _uniform(match, triangles=None) -> str:
    """"-r N: T triangles (ratio to the tolerance output)" of a uniform match, or "not reached"."""
    if not match:
        return "not reached"
    ratio = f" ({match['triangles'] / triangles:.2f}x)" if triangles else ""
    return f"-r {match['resolution']}: {match['triangles']:,}{ratio}"


def tolerance_table(results) -> str:
    tol = results.get("tolerance", {})
    if "skipped" in tol:
        return f"(--tolerance: not measured: {tol['skipped']})"
    rows = []
    for m in tol.get("meshes", []):
        if not m.get("ok"):
            rows.append([m["input"], "", "failed: " + m.get("error", "")[:80]] + [""] * 5)
            continue
        for t in m["tolerances"]:
            if "triangles" not in t:
                rows.append([m["input"], f"{t['tolerance']:g}", "failed: " + t["error"][:80]] + [""] * 5)
                continue
            rows.append([m["input"], f"{t['tolerance']:g}", f"{t['triangles']:,}", _g(t["measured"]), _g(t["reported"]),
                         _uniform(t["uniform"], t["triangles"]), _uniform(t["uniform_within_t"], t["triangles"]),
                         f"-r {m['reference_resolution']} (~{m['reference_error_estimate']:.1g})"])
    return markdown(["input", "T", "triangles", "measured error", "c1surf's own measure",
                     "uniform with that measured error (x tolerance's triangles)", "uniform within T", "reference (its error)"],
                    rows)


def plot(results, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    styles = {"c1surf": "o", "pymeshlab": "s", "pyopensubdiv": "D", "igl": "^", "trimesh": "v"}
    measures = (("whole process (read, subdivide/convert, write PLY)", lambda r: r.get("process", {}).get("ok")
                 and r["process"]["seconds"]), ("in memory (convert / subdivision call)", lambda r: r["ok"] and r["seconds"]["convert"]))
    for ax, (title, seconds) in zip(axes, measures):
        for tool, marker in styles.items():
            for prefix, line in (("torus-quad", "-"), ("torus-tri", "--")):
                pts = sorted((r["faces"], seconds(r) / r["faces"] * 1e6) for r in results["runs"]
                             if r["tool"] == tool and r["input"].startswith(prefix) and seconds(r))
                if pts:
                    label = f"{tool if tool == 'c1surf' else PEERS[tool].label}, {prefix[6:]} tori"
                    ax.plot(*zip(*pts), marker + line, label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("input faces")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        for r in results["runs"]:  # conversions that did not finish, at the top of the whole-process panel
            if ax is axes[0] and r["tool"] == "c1surf" and not r.get("process", {}).get("ok", True):
                ax.annotate(f"{r['faces']:,} faces: failed", (r["faces"], ax.get_ylim()[1]), xytext=(0, -12),
                            textcoords="offset points", ha="right", fontsize=7, color="C0")
                ax.plot([r["faces"]], [ax.get_ylim()[1]], "x", color="C0")
    axes[0].set_ylabel("time per input face (microseconds)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=5, fontsize=7)
    fig.suptitle("Two levels of subdivision (c1surf -r 2: the same output vertex count)")
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)
