"""Regenerate the pictures of the README and docs/: `.venv/bin/python docs/images/make_images.py`.

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
    c0_crease_pair(HERE / "c0_creases.png")
    cad_part(HERE / "cad_creases.png")
    dart_trio(HERE / "dart_edgeonly.png")
    valence_two_diagram(HERE / "valence_two.png")


def crease_strip(path):
    """The sample cube with its 12 edges tagged as creases of sharpness 0, 0.5, 1, 2 and 10, side by side (the G1
    rule of every sharpness, --g1-creases: by default sharpness 10 is a C0 seam, ``c0_crease_pair``)."""
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
            c1surf("render", mesh, "--png", png, "--size", "220x200", "--range", "0", "8", "--g1-creases")
            tiles.append((Image.open(png).convert("RGB"), f"sharpness {s:g}"))
    labelled_row(tiles, 220, path)


def labelled_row(tiles, step: int, path):
    """The (image, label) tiles side by side, ``step`` pixels apart, each label above its tile."""
    width, height = tiles[0][0].size
    out = Image.new("RGB", ((len(tiles) - 1) * step + width, height + 20), (255, 255, 255))
    draw = ImageDraw.Draw(out)
    for k, (tile, label) in enumerate(tiles):
        out.paste(tile, (k * step, 20))
        draw.text((k * step + 6, 4), label, fill=(0, 0, 0))
    out.save(path, optimize=True)


def c0_crease_pair(path):
    """Reflection lines of the sample cube with every edge an infinitely sharp crease (--crease-angle 40):
    the sharpest G1 crease (--g1-creases: narrow fillets) and the C0 seams of the default (the cube)."""
    import tempfile

    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, extra in (("--g1-creases: the sharpest G1 crease", ("--g1-creases",)), ("default: C0 seams", ())):
            patches, png = Path(tmp) / "p.json", Path(tmp) / "z.png"
            c1surf("convert", ROOT / "sample_meshes" / "cube.obj", "-o", Path(tmp) / "m.ply", "-r", "2",
                   "--crease-angle", "40", "--patches", patches, *extra)
            c1surf("render", patches, "--zebra", png, "--size", "300x280", "--stripes", "10", "--view", "iso")
            tiles.append((Image.open(png).convert("RGB"), label))
    labelled_row(tiles, 310, path)


def cad_part(path):
    """A CAD-like triangle mesh (tests/cad_meshes.py: a box with a filleted boss) at --crease-angle 40: its
    triangles, reflection lines with --g1-creases, and the default C0 seams (sectors merged first)."""
    import tempfile

    from cad_meshes import boss_box, write_obj

    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        mesh = Path(tmp) / "part.obj"
        write_obj(mesh, *boss_box(6, 0))
        for label, extra in (("--g1-creases", ("--g1-creases",)), ("default: C0 seams", ())):
            patches, png = Path(tmp) / "p.json", Path(tmp) / "z.png"
            c1surf("convert", mesh, "-o", Path(tmp) / "m.ply", "-r", "2", "--crease-angle", "40", "--patches", patches,
                   *extra)
            c1surf("render", patches, "--zebra", png, "--size", "300x280", "--stripes", "14", "--eye", "2.2", "-2.8", "2.4",
                   "--target", "0", "0", "0", "--up", "0", "0", "1")
            tiles.append((Image.open(png).convert("RGB"), f"{label}: reflection lines"))
    labelled_row(tiles, 310, path)


def dart_trio(path):
    """Reflection lines of OpenSubdiv's catmark_dart_edgeonly (a crease 8 - 17 - 20 from the boundary to the dart
    20): its own tags (sharpness 2: the G1 pull), the crease made infinitely sharp (a --creases file) with
    --g1-creases (the sharpest G1 crease), and by default (C0 up to the dart, the dart's hole)."""
    import tempfile

    mesh = ROOT.parent / "shared" / "meshes" / "opensubdiv" / "catmark_dart_edgeonly.obj"
    if not mesh.exists():
        return
    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        creases = Path(tmp) / "dart.json"
        creases.write_text('{"creases": [[8, 17, 20, 10]]}')
        for label, extra in (("file's tags (sharpness 2): G1", ()), ("sharpness 10, --g1-creases", ("--creases", creases, "--g1-creases")),
                             ("sharpness 10: C0 up to the dart", ("--creases", creases))):
            patches, png = Path(tmp) / "p.json", Path(tmp) / "z.png"
            c1surf("convert", mesh, "-o", Path(tmp) / "m.ply", "-r", "2", "--patches", patches, *extra)
            c1surf("render", patches, "--zebra", png, "--size", "300x280", "--stripes", "16", "--eye", "2.5", "-3.5", "4.5",
                   "--target", "0", "0", "0.3", "--up", "0", "0", "1")
            tiles.append((Image.open(png).convert("RGB"), label))
    labelled_row(tiles, 310, path)


def valence_two_diagram(path):
    """The valence-2 rule (mesh/valence_two.py) drawn: v between two quads, and v between a face and a triangle."""
    out = Image.new("RGB", (780, 230), (255, 255, 255))
    draw = ImageDraw.Draw(out)
    blue, orange, yellow, ink, red = (170, 200, 235), (245, 200, 150), (250, 230, 110), (40, 40, 40), (200, 30, 30)

    def polygon(points, dx, fill):
        draw.polygon([(x + dx, y) for x, y in points], fill=fill, outline=ink)

    def dot(point, dx, label, colour=ink):
        x, y = point[0] + dx, point[1]
        draw.ellipse((x - 4, y - 4, x + 4, y + 4), fill=colour)
        draw.text((x + 6, y - 14), label, fill=colour)

    a, b = (90, 40), (90, 180)
    # v on the edge a - b between two quads: both faces lose v and share a - b
    v = (90, 110)
    polygon([(20, 40), a, v, b, (20, 180)], 0, blue)
    polygon([a, (160, 40), (160, 180), b, v], 0, orange)
    polygon([(20, 40), a, b, (20, 180)], 190, blue)
    polygon([a, (160, 40), (160, 180), b], 190, orange)
    # v off the edge, in the left face and in a triangle a, v, b: the triangle would keep two corners,
    # so it goes, and the left face meets the right one along a - b
    w = (55, 110)
    polygon([(10, 40), a, w, b, (10, 180)], 400, blue)
    polygon([a, b, w][::-1], 400, yellow)
    polygon([a, (160, 40), (160, 180), b], 400, orange)
    polygon([(10, 40), a, b, (10, 180)], 590, blue)
    polygon([a, (160, 40), (160, 180), b], 590, orange)
    for dx, point in ((0, v), (400, w)):
        dot(point, dx, "v", red)
    for dx in (0, 190, 400, 590):
        dot(a, dx, "a")
        dot(b, dx, "b")
    for dx in (170, 570):
        draw.text((dx, 102), "->", fill=(0, 0, 0))
    draw.text((10, 200), "v in two quads: out of both, they share a - b", fill=(0, 0, 0))
    draw.text((400, 200), "v in a face and a triangle a, v, b: the triangle goes", fill=(0, 0, 0))
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
