"""Regenerate the README pictures: `.venv/bin/python docs/images/make_images.py`.

Curvature previews and reflection lines of sample meshes, and a close-up of the
reflection lines of a surface with the paper's misprinted P_12 next to the
correct one (the test tests/render/test_render.py::test_reflection_lines_break_on_a_broken_surface
measures the same thing).
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "tests" / "render"))


def c1surf(*args):
    subprocess.run([sys.executable, "-m", "c1surf.cli.main", *map(str, args), "-q"], check=True, cwd=ROOT)


def main():
    samples = ROOT / "sample_meshes"
    spot = ROOT.parent / "shared" / "meshes" / "spot" / "spot_control_mesh.obj"
    c1surf("render", samples / "twisted.obj", "--png", HERE / "twisted_kmax.png", "--zebra", HERE / "twisted_zebra.png",
           "--size", "360x300", "--stripes", "12")
    c1surf("render", samples / "double_torus.obj", "--png", HERE / "double_torus_gray.png", "--colormap", "gray",
           "--size", "360x240", "--view", "front")
    if spot.exists():
        c1surf("render", spot, "--png", HERE / "spot_kmax.png", "--size", "360x300", "--eye", "2.4", "1.0", "-2.4",
               "--range", "0", "10")
    broken_pair(HERE / "misprint_zebra.png")
    crease_strip(HERE / "crease_sharpness.png")


def crease_strip(path):
    """The sample cube with its 12 edges tagged as creases of sharpness 0, 0.5, 1, 2 and 10, side by side."""
    import tempfile

    cube = (ROOT / "sample_meshes" / "cube.obj").read_text()
    faces = [[int(v) - 1 for v in line.split()[1:]] for line in cube.splitlines() if line.startswith("f ")]
    edges = sorted({tuple(sorted((f[i], f[(i + 1) % 4]))) for f in faces for i in range(4)})
    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        for s in (0, 0.5, 1, 2, 10):
            mesh = Path(tmp) / f"cube_{s}.obj"
            mesh.write_text(cube + "".join(f"t crease 2/1/0 {a} {b} {s}\n" for a, b in edges))
            png = Path(tmp) / f"cube_{s}.png"
            c1surf("render", mesh, "--png", png, "--size", "220x200", "--range", "0", "8")
            tiles.append((Image.open(png).convert("RGB"), f"sharpness {s:g}"))
    out = Image.new("RGB", (5 * 220, 220), (255, 255, 255))
    draw = ImageDraw.Draw(out)
    for k, (tile, label) in enumerate(tiles):
        out.paste(tile, (k * 220, 20))
        draw.text((k * 220 + 6, 4), label, fill=(0, 0, 0))
    out.save(path, optimize=True)


def broken_pair(path):
    from c1surf.evaluation.patch_set import PatchSet
    from c1surf.evaluation.smoothness import measure_smoothness
    from c1surf.render.camera import frame_camera
    from c1surf.render.image import render
    from c1surf.render.shading import reflection_phase, stripes
    from test_render import misprinted_surface, worst_edge_point

    good, bad = misprinted_surface()
    report = measure_smoothness(bad)
    point, normal, tangent = worst_edge_point(bad, report.worst_pair)
    size = np.ptp(good[0].reshape(-1, 3), axis=0).max()
    across = np.cross(normal, tangent)
    window = 0.03 * size * np.array([tangent, -tangent, across, -across]) + point
    # Lines at 45 degrees to the edge: stripes cross it, and still turn with the normals
    # that jump about the edge.
    axis = (tangent + across) / np.sqrt(2)
    camera = frame_camera(window, 180, 180, eye=point + normal, target=point, projection="orthographic")
    tiles = []
    for groups in (good, bad):
        image = render(PatchSet(groups), camera)
        z = stripes(reflection_phase(image, axis=axis), 48)
        rgb = np.repeat(np.nan_to_num(z)[..., None], 3, axis=2)
        tiles.append((np.clip(rgb, 0, 1) * 255).astype(np.uint8))
    out = Image.new("RGB", (370, 200), (255, 255, 255))
    draw = ImageDraw.Draw(out)
    for k, (tile, label) in enumerate(zip(tiles, ("correct P_12 (G1)", "misprinted P_12: stripes break"))):
        out.paste(Image.fromarray(tile), (k * 190, 20))
        draw.text((k * 190 + 4, 4), label, fill=(0, 0, 0))
    out.save(path, optimize=True)


if __name__ == "__main__":
    main()
