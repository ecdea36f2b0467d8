#!/usr/bin/env python
"""Issue 43's pictures: a scan's control mesh before and after, and the reflection lines of the fits over them.

    python bench/layout_pictures.py                           # boat and wingnut: docs/images/layout_<scan>.png
    python bench/layout_pictures.py --scan scorpion_low_resolution --before decimate

For each scan, ``c1surf fit SCAN --remesher BEFORE`` (the layout the default chose before QuadriFlow's was tried
first: ``decimate`` or ``instant``, docs/layout.md) and ``c1surf fit SCAN`` (the default), each with ``--cage``,
``--patches x.npz`` and ``--report``; one picture, a row per fit: the fitted cage flat shaded with its irregular
vertices in red (interior valence other than 4, rim valence other than 3: ``fit.irregular_mask``, the bench's
count) and the fit's reflection lines (``c1surf render --zebra``, the same camera for both rows), labelled with the remesher, control
faces, irregular vertices, STEP faces (the report's ``cad_faces``) and scan-to-surface max.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from fit import SCANS, irregular_mask  # noqa: E402
from harness.processes import SETTINGS, c1surf_argv, run_process  # noqa: E402

PANEL = (420, 330)  # pixels of each panel


def cage_panel(cage: Path, view: tuple, path: Path):
    """The cage flat shaded (matplotlib), irregular vertices as red dots; returns their count and the centre of the
    cage's bounding box (3 strings, for ``render --target``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from c1surf.io.meshes.obj import read_obj

    mesh = read_obj(cage)
    sizes, corners, points = mesh.face_sizes, mesh.face_vertices, mesh.points
    mask = irregular_mask(sizes, corners, points.shape[0])
    offsets = np.r_[0, np.cumsum(sizes)]
    polygons = [points[corners[a:b]] for a, b in zip(offsets[:-1], offsets[1:])]
    normals = np.array([np.cross(p[2] - p[0], p[-1] - p[1]) for p in polygons])
    normals /= np.maximum(np.linalg.norm(normals, axis=1), 1e-300)[:, None]
    light = np.abs(normals @ (np.array([0.3, 0.8, 0.5]) / np.linalg.norm([0.3, 0.8, 0.5])))
    colours = np.c_[np.repeat((0.45 + 0.5 * light)[:, None], 3, axis=1), np.ones(len(polygons))]
    figure = plt.figure(figsize=(PANEL[0] / 100, PANEL[1] / 100), dpi=100)
    axes = figure.add_subplot(projection="3d", proj_type="ortho")
    axes.add_collection3d(Poly3DCollection(polygons, facecolors=colours, edgecolors=(0.1, 0.1, 0.1, 0.8),
                                           linewidths=0.25))
    # the irregular vertices on the side facing the camera, drawn over the faces (matplotlib sorts whole collections
    # by depth, so a dot on the front could land behind the faces)
    vertex_normals = np.zeros_like(points)
    np.add.at(vertex_normals, corners, np.repeat(normals, sizes, axis=0))
    facing = mask & (vertex_normals @ view_direction(view) > 0)
    axes.computed_zorder = False
    axes.scatter(*points[facing].T, s=9, c="red", depthshade=False, zorder=10)
    low, high = points.min(0), points.max(0)
    centre, half = (low + high) / 2, (high - low).max() / 2
    for set_limits, c in zip((axes.set_xlim, axes.set_ylim, axes.set_zlim), centre):
        set_limits(c - half, c + half)
    axes.set_box_aspect((1, 1, 1), zoom=2.0)  # the cube of the limits fills the panel
    axes.view_init(elev=view[0], azim=view[1], vertical_axis="y")
    axes.set_axis_off()
    figure.subplots_adjust(0, 0, 1, 1)
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return int(mask.sum()), [f"{c:.9g}" for c in centre]


def fit_row(scan: Path, remesher: str | None, work: Path, view: tuple, timeout: float):
    """One fit and its two panels: ((cage image, zebra image), label)."""
    from PIL import Image

    name = remesher or "default"
    cage, npz, report, zebra = (work / f"{name}{s}" for s in ("_cage.obj", ".npz", ".json", "_zebra.png"))
    extra = ["--remesher", remesher] if remesher else []
    done = run_process(c1surf_argv("fit", scan, "--cage", cage, "--patches", npz, "--report", report, "--quiet",
                                   *extra), timeout, cwd=SETTINGS["root"])
    if not done["ok"]:
        raise SystemExit(f"layout_pictures: fit of {scan.name} ({name}) failed: {done.get('error', '')}")
    irregular, centre = cage_panel(cage, view, work / f"{name}_cage.png")
    run_process(c1surf_argv("render", npz, "--zebra", zebra, "--size", f"{PANEL[0]}x{PANEL[1]}", "--stripes", "16",
                            "--eye", *view_eye(view, centre), "--target", *centre, "--projection", "orthographic",
                            "-q"), timeout, cwd=SETTINGS["root"])
    document = json.loads(report.read_text())
    label = (f"{document['control_mesh'].get('remesher', name)}: {document['control_mesh']['faces']:,} control faces, "
             f"{irregular} irregular vertices, {document['cad_faces']:,} STEP faces, "
             f"max {document['scan_to_surface']['relative_max']:.2g} of the diagonal")
    return (Image.open(work / f"{name}_cage.png").convert("RGB"), Image.open(zebra).convert("RGB")), label


def view_direction(view: tuple) -> np.ndarray:
    """(3,): the unit vector towards the camera of matplotlib's (elevation, azimuth) with y up."""
    elevation, azimuth = np.radians(view)
    return np.array([np.cos(elevation) * np.sin(azimuth), np.sin(elevation), np.cos(elevation) * np.cos(azimuth)])


def view_eye(view: tuple, centre: list) -> list:
    """``render --eye`` looking at ``centre`` from ``view`` (orthographic: only the direction counts)."""
    return [f"{v:.9g}" for v in np.asarray(centre, dtype=float) + view_direction(view)]


def picture(scan: Path, before: str, out: Path, view: tuple, timeout: float) -> list:
    """The two rows (``before`` remesher, the default) as one PNG at ``out``; returns the two labels."""
    from PIL import Image, ImageDraw

    with tempfile.TemporaryDirectory(prefix="c1surf-layout-") as folder:
        rows = [fit_row(scan, remesher, Path(folder), view, timeout) for remesher in (before, None)]
    width, height = PANEL
    image = Image.new("RGB", (2 * width, 2 * (height + 22)), "white")
    draw = ImageDraw.Draw(image)
    for r, ((cage, zebra), label) in enumerate(rows):
        top = r * (height + 22)
        draw.text((6, top + 5), ("before: " if r == 0 else "after (the default): ") + label, fill=(0, 0, 0))
        image.paste(cage.resize(PANEL), (0, top + 22))
        image.paste(zebra.resize(PANEL), (width, top + 22))
    out.parent.mkdir(parents=True, exist_ok=True)
    image.quantize(colors=128, method=Image.Quantize.MEDIANCUT).save(out, optimize=True)
    return [label for _, label in rows]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scan", action="append", help="scan name in ../shared/scans (repeat; default boat, wingnut)")
    parser.add_argument("--before", action="append", help="the remesher of the 'before' row, one per --scan "
                                                           "(default decimate for boat, instant for wingnut)")
    parser.add_argument("--view", nargs=2, type=float, default=(25.0, 40.0), metavar=("ELEVATION", "AZIMUTH"))
    parser.add_argument("--images", default=str(HERE.parent / "docs" / "images"))
    parser.add_argument("--timeout", type=float, default=900.0)
    args = parser.parse_args(argv)
    SETTINGS.update(root=HERE.parent)
    scans = args.scan or ["boat", "wingnut"]
    before = args.before or (["decimate", "instant"] if not args.scan else ["decimate"] * len(scans))
    for name, remesher in zip(scans, before):
        out = Path(args.images) / f"layout_{name}.png"
        labels = picture(SCANS / f"{name}.obj", remesher, out, tuple(args.view), args.timeout)
        print(f"{out}:\n  " + "\n  ".join(labels))
    return 0


if __name__ == "__main__":
    sys.exit(main())
