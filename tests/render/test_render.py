"""Rendering: EXR images read back with OpenEXR, exact per-pixel curvature, atlases,
previews, reflection lines that reveal a broken surface, curvature PLY output."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR
import pytest
from click.testing import CliRunner
from PIL import Image as PILImage

from c1surf.cli.main import main
from c1surf.evaluation.curvature import patch_tangents, surface_curvature, tessellation_curvature
from c1surf.evaluation.patch_set import PatchSet
from c1surf.evaluation.rational import dehomogenize
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.io.images.exr import write_exr
from c1surf.io.images.png import write_png
from c1surf.io.patches.formats import load_patch_set
from c1surf.render.camera import VIEWS, frame_camera
from c1surf.render.image import render
from c1surf.render.raycast import patch_grid_mesh
from c1surf.render.shading import reflection_phase, stripes

from conftest import SAMPLES, misprinted_bicubic, surface_of
from conftest import rational_sphere_patch
from render_reference import edge_discontinuity

GOLDEN = Path(__file__).resolve().parents[1] / "golden"
REQUIRED = {"kmax", "K", "H", "k1", "k2", "Z", "N.X", "N.Y", "N.Z", "patch", "u", "v", "R", "G", "B"}
CURVATURES = ("kmax", "K", "H", "k1", "k2")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def read_exr(path):
    """Every channel of an EXR file, with OpenEXR itself, and the header."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {name: np.array(c.pixels) for name, c in f.channels().items()}, dict(f.header())


def check_channels(channels, width, height, n_patches):
    assert REQUIRED <= set(channels)
    for name, data in channels.items():
        assert data.shape == (height, width), name
        assert data.dtype == np.float32, name
    patch = channels["patch"]
    on = patch >= 0
    assert on.any()
    assert np.all(patch[~on] == -1)
    assert np.all(patch == np.round(patch)) and patch.max() < n_patches
    for name, data in channels.items():
        assert np.all(np.isfinite(data[on])), name
    n = np.stack([channels[f"N.{a}"][on] for a in "XYZ"], axis=1)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    assert np.all((channels["u"][on] >= 0) & (channels["u"][on] <= 1) & (channels["v"][on] >= 0) & (channels["v"][on] <= 1))
    return on


def check_curvature_at_pixels(channels, groups, count=40, seed=0, weights=None):
    """Curvature stored at a pixel == direct evaluation at that pixel's (patch, u, v)."""
    rows, cols = np.nonzero(channels["patch"] >= 0)
    pick = np.random.default_rng(seed).choice(rows.size, size=min(count, rows.size), replace=False)
    r, c = rows[pick], cols[pick]
    patch = channels["patch"][r, c].astype(np.int64)
    direct = surface_curvature(groups, patch, channels["u"][r, c].astype(np.float64), channels["v"][r, c].astype(np.float64),
                               weights=weights)
    scale = max(1.0, float(np.max(direct.kmax)))
    for name in CURVATURES:
        np.testing.assert_allclose(channels[name][r, c], direct[name], rtol=1e-4, atol=1e-5 * scale, err_msg=name)
    for k, a in enumerate("XYZ"):
        np.testing.assert_allclose(channels[f"N.{a}"][r, c], direct.normal[:, k], atol=1e-5)
        np.testing.assert_allclose(channels[f"P.{a}"][r, c], direct.point[:, k], atol=1e-5 * scale)


def test_render_mesh_to_exr_png_and_zebra(tmp_path):
    exr, png, zebra = tmp_path / "t.exr", tmp_path / "t.png", tmp_path / "z.png"
    result = run("render", SAMPLES / "twisted.obj", "-o", exr, "--png", png, "--zebra", zebra, "--size", "120x90")
    assert result.exit_code == 0, result.output
    assert result.output == ""  # no progress when not on a terminal
    surface = surface_of(SAMPLES / "twisted.obj")
    groups = [surface.biquadratic, surface.bicubic]
    channels, header = read_exr(exr)
    on = check_channels(channels, 120, 90, surface.n_patches)
    assert 0.2 < on.mean() < 0.95  # framed: the surface fills much of the picture, with a border
    assert not on[0].any() and not on[-1].any() and not on[:, 0].any() and not on[:, -1].any()
    check_curvature_at_pixels(channels, groups)
    assert np.all(np.isinf(channels["Z"][~on]))
    assert np.all(channels["A"][on] == 1) and np.all(channels["A"][~on] == 0)
    assert header["c1surfProjection"] == "perspective" and header["c1surfColorBy"] == "kmax"
    for path in (png, zebra):
        with PILImage.open(path) as im:
            assert im.size == (120, 90) and im.mode == "RGB"
            pixels = np.asarray(im)
        assert pixels.std() > 10  # a picture, not a blank
    with PILImage.open(zebra) as im:
        grey = np.asarray(im)[on]
    assert (grey < 60).mean() > 0.1 and (grey > 180).mean() > 0.1  # black and white stripes on the surface


def test_hits_are_exact_points_on_the_pixel_rays():
    """Newton steps move the tessellation hit onto the patch: the point is on the ray, and
    depth, position, (patch, u, v) agree with each other."""
    patch_set = load_patch_set(GOLDEN / "double_torus.json")
    groups = patch_set.groups
    for projection in ("perspective", "orthographic"):
        mesh = patch_grid_mesh(groups, 3)  # a coarse mesh: the Newton steps do the work
        camera = frame_camera(mesh.points, 160, 120, "iso", projection=projection)
        image = render(patch_set, camera, mesh=mesh)
        ch = image.channels
        on = image.mask
        origins, dirs = camera.rays()
        flat = np.flatnonzero(on.ravel())
        p = np.stack([ch[f"P.{a}"].ravel()[flat] for a in "XYZ"], axis=1)
        rel = p - origins[flat]
        off_ray = np.linalg.norm(rel - np.einsum("md,md->m", rel, dirs[flat])[:, None] * dirs[flat], axis=1)
        size = np.ptp(mesh.points, axis=0).max()
        assert np.quantile(off_ray, 0.99) < 1e-10 * size
        np.testing.assert_allclose(ch["Z"].ravel()[flat], camera.depth(p), rtol=1e-12)
        direct = surface_curvature(groups, ch["patch"].ravel()[flat].astype(int), ch["u"].ravel()[flat], ch["v"].ravel()[flat])
        np.testing.assert_allclose(direct.point, p, atol=1e-12 * size)
        np.testing.assert_allclose(direct.kmax, ch["kmax"].ravel()[flat], rtol=1e-12)


def test_atlas_of_a_patch_file(tmp_path):
    patches = GOLDEN / "cube.json"
    groups = load_patch_set(patches).groups
    n_patches = sum(len(g) for g in groups)
    exr = tmp_path / "atlas.exr"
    result = run("render", patches, "-o", exr, "--atlas", "--tile", 6)
    assert result.exit_code == 0, result.output
    channels, header = read_exr(exr)
    columns = int(np.ceil(np.sqrt(n_patches)))
    rows = int(np.ceil(n_patches / columns))
    assert header["c1surfKind"] == "atlas" and header["c1surfColumns"] == columns
    on = check_channels(channels, columns * 6, rows * 6, n_patches)
    assert on.sum() == n_patches * 36
    i, j = np.mgrid[0 : rows * 6, 0 : columns * 6]
    k = (i // 6) * columns + j // 6
    np.testing.assert_array_equal(channels["patch"], np.where(k < n_patches, k, -1))
    np.testing.assert_allclose(channels["u"][on], ((j % 6 + 0.5) / 6)[on], atol=1e-7)
    np.testing.assert_allclose(channels["v"][on], (1 - (i % 6 + 0.5) / 6)[on], atol=1e-7)
    check_curvature_at_pixels(channels, groups, count=60)


def test_patch_file_renders_like_its_mesh(tmp_path):
    """The golden patch file holds the surface of the sample mesh, in the same patch order."""
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    assert run("render", SAMPLES / "cube.obj", "-o", a, "--size", "64", "--view", "front").exit_code == 0
    assert run("render", GOLDEN / "cube.json", "-o", b, "--size", "64", "--view", "front").exit_code == 0
    ca, _ = read_exr(a)
    cb, _ = read_exr(b)
    groups = load_patch_set(GOLDEN / "cube.json").groups
    for channels in (ca, cb):
        check_channels(channels, 64, 64, sum(len(g) for g in groups))
        check_curvature_at_pixels(channels, groups, count=20)
    same = (ca["patch"] == cb["patch"]) & (ca["patch"] >= 0)
    assert same.mean() > 0.98 * (ca["patch"] >= 0).mean()
    np.testing.assert_allclose(ca["kmax"][same], cb["kmax"][same], rtol=1e-5, atol=1e-6)


def test_rational_patches_render_with_their_exact_curvature():
    radius = 1.7
    q = rational_sphere_patch(radius, np.zeros(3))
    group, weights = dehomogenize(np.stack([q, q * np.array([-1, 1, 1, 1]), q * np.array([1, -1, 1, 1])]))  # 3 pieces
    camera = frame_camera(patch_grid_mesh([group], 8, [weights]).points, 80, 80, eye=(3.0, 2.0, 1.0))
    image = render(PatchSet([group], weights=[weights]), camera)
    on = image.mask
    assert on.mean() > 0.2
    np.testing.assert_allclose(image.channels["kmax"][on], 1 / radius, rtol=1e-9)
    np.testing.assert_allclose(image.channels["K"][on], 1 / radius**2, rtol=1e-9)
    p = np.stack([image.channels[f"P.{a}"][on] for a in "XYZ"], axis=1)
    np.testing.assert_allclose(np.linalg.norm(p, axis=1), radius, rtol=1e-12)


def test_render_keeps_the_weights_of_a_rational_patch_file(tmp_path):
    """A rational patch file renders its rational surface (``render`` used to drop the weights):
    every pixel's position, normal and curvature are the rational patches' at its (patch, u, v)."""
    rng = np.random.default_rng(5)
    lines = (SAMPLES / "twisted.obj").read_text().splitlines()
    weighted = [f"{line} {rng.uniform(0.5, 2.0):.6f}" if line.startswith("v ") else line for line in lines]
    obj, patches, exr = tmp_path / "weighted.obj", tmp_path / "weighted.json", tmp_path / "weighted.exr"
    obj.write_text("\n".join(weighted) + "\n")
    assert run("convert", obj, "-o", tmp_path / "weighted.ply", "--patches", patches).exit_code == 0
    patch_set = load_patch_set(patches)
    assert patch_set.weights is not None
    result = run("render", patches, "-o", exr, "--size", "80x60")
    assert result.exit_code == 0, result.output
    channels, _ = read_exr(exr)
    on = check_channels(channels, 80, 60, patch_set.n_patches)
    check_curvature_at_pixels(channels, patch_set.groups, count=60, weights=patch_set.weights)
    # the same control points without their weights are another surface
    patch, u, v = channels["patch"][on].astype(np.int64), channels["u"][on], channels["v"][on]
    polynomial = surface_curvature(patch_set.groups, patch, u.astype(np.float64), v.astype(np.float64))
    p = np.stack([channels[f"P.{a}"][on] for a in "XYZ"], axis=1)
    assert np.abs(p - polynomial.point).max() > 1e-3 * np.ptp(p, axis=0).max()


@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_default_camera_frames_the_whole_surface(projection):
    points = patch_grid_mesh(load_patch_set(GOLDEN / "twisted.json").groups, 4).points
    for view in VIEWS:
        camera = frame_camera(points, 200, 100, view, projection=projection)
        rc = camera.project(points)
        assert rc[:, 0].min() >= 0 and rc[:, 0].max() <= 100 and rc[:, 1].min() >= 0 and rc[:, 1].max() <= 200
        # tight: the surface spans most of the height or the width
        assert max(np.ptp(rc[:, 0]) / 100, np.ptp(rc[:, 1]) / 200) > 0.85, view


def misprinted_surface():
    """twisted.obj with the transcription's misprinted P_12 (as in test_construction)."""
    surface = surface_of(SAMPLES / "twisted.obj")
    bad = misprinted_bicubic(surface)
    return [surface.biquadratic, surface.bicubic], [surface.biquadratic, bad]


def worst_edge_point(groups, pair):
    """Point, unit normal and unit tangent of the shared side of ``pair`` where the normals jump most."""
    nq = len(groups[0])

    def patch(k):
        return groups[0][k] if k < nq else groups[1][k - nq]

    t = np.linspace(0, 1, 201)
    best = None
    for side_a in ((0.0, None), (1.0, None), (None, 0.0), (None, 1.0)):
        for side_b in ((0.0, None), (1.0, None), (None, 0.0), (None, 1.0)):
            curves = []
            for k, side in ((pair[0], side_a), (pair[1], side_b)):
                u = np.full(t.size, side[0]) if side[0] is not None else t
                v = np.full(t.size, side[1]) if side[1] is not None else t
                x, xu, xv = patch_tangents(patch(k)[None], u, v, index=np.zeros(t.size, int))
                n = np.cross(xu, xv)
                curves.append((x, n / np.linalg.norm(n, axis=1, keepdims=True)))
            (xa, na), (xb, nb) = curves
            for flip in (False, True):
                xb2, nb2 = (xb[::-1], nb[::-1]) if flip else (xb, nb)
                gap = np.abs(xa - xb2).max()
                if best is None or gap < best[0]:
                    best = (gap, xa, na, nb2)
    gap, x, na, nb = best
    assert gap < 1e-12
    i = int(np.argmax(np.arccos(np.clip(np.einsum("md,md->m", na, nb), -1, 1))))
    tangent = x[min(i + 1, t.size - 1)] - x[max(i - 1, 0)]
    return x[i], na[i], tangent / np.linalg.norm(tangent)


def test_reflection_lines_break_on_a_broken_surface():
    """Reflection lines of the misprinted-P_12 surface jump across the patch edge where its
    normals jump; those of the correct (G1) surface are continuous there.

    Close-up of the worst edge point, light lines along the edge (normals that jump
    across an edge turn about it). The statistic is the jump of the stripe phase
    (64 stripes per turn) across the edge, trend removed (``edge_discontinuity``).
    """
    good, bad = misprinted_surface()
    report = measure_smoothness(bad)
    assert report.max_normal_jump > 1e-3
    point, normal, tangent = worst_edge_point(bad, report.worst_pair)
    size = np.ptp(good[0].reshape(-1, 3), axis=0).max()
    across = np.cross(normal, tangent)
    window = 0.01 * size * np.array([tangent, -tangent, across, -across]) + point
    camera = frame_camera(window, 160, 160, eye=point + normal, target=point, projection="orthographic")
    jumps, within, pictures = {}, {}, {}
    for name, groups in (("good", good), ("bad", bad)):
        image = render(PatchSet(groups), camera)
        assert image.mask.all() and len(np.unique(image.channels["patch"])) >= 2
        phase = reflection_phase(image, axis=tangent)
        a, w = edge_discontinuity(64 * phase, image.channels["patch"])
        assert a.size > 100
        jumps[name], within[name] = np.median(a), np.median(w)
        pictures[name] = stripes(phase, 64)
    expected = 2 * 64 * report.max_normal_jump  # the reflected ray turns twice as far as the normal
    assert jumps["bad"] == pytest.approx(expected, rel=0.2)
    assert jumps["good"] < 0.02 * expected
    assert within["good"] < 1e-3 and within["bad"] < 1e-3
    # the pictures themselves differ: the stripes are displaced on one side of the edge
    assert np.mean(np.abs(pictures["bad"] - pictures["good"]) > 0.5) > 0.05


def test_convert_curvature_ply_readable_by_plyfile_and_trimesh(tmp_path):
    import plyfile
    import trimesh

    out = tmp_path / "c.ply"
    result = run("convert", SAMPLES / "twisted.obj", "-o", out, "-r", 4, "--curvature")
    assert result.exit_code == 0, result.output
    ply = plyfile.PlyData.read(str(out))
    vertex = ply["vertex"]
    names = [p.name for p in vertex.properties]
    assert names == ["x", "y", "z", "nx", "ny", "nz", "kmax", "K", "H", "quality", "red", "green", "blue"]
    assert vertex["x"].dtype == np.float64  # like the plain PLY output
    mesh = trimesh.load(out, process=False)
    plain = tmp_path / "p.ply"
    assert run("convert", SAMPLES / "twisted.obj", "-o", plain, "-r", 4).exit_code == 0
    reference = trimesh.load(plain, process=False)
    np.testing.assert_array_equal(mesh.faces, reference.faces)
    np.testing.assert_array_equal(mesh.vertices, reference.vertices)
    assert mesh.is_watertight
    from c1surf.evaluation.tessellate import patch_adjacency, tessellate_patches

    surface = surface_of(SAMPLES / "twisted.obj")
    groups = [surface.biquadratic, surface.bicubic]
    tess = tessellate_patches(groups, patch_adjacency(surface.refined, surface.frames), 4)
    want = tessellation_curvature(groups, tess.grid, tess.points.shape[0])
    for name in ("kmax", "K", "H"):
        np.testing.assert_allclose(vertex[name], want[name].astype(np.float32), rtol=1e-6, err_msg=name)
    np.testing.assert_array_equal(vertex["quality"], vertex["kmax"])
    # an interior grid vertex carries exactly its patch's curvature
    v = tess.grid[5, 1, 2]
    direct = surface_curvature(groups, np.array([5]), np.array([1 / 3]), np.array([2 / 3]))
    assert vertex["K"][v] == pytest.approx(direct.K[0], rel=1e-6)


def test_usage_errors_are_one_line(tmp_path):
    twisted = SAMPLES / "twisted.obj"
    assert run("render", twisted).exit_code == 2  # nothing to write
    assert run("render", twisted, "-o", tmp_path / "x.png").exit_code == 2
    assert run("render", twisted, "--png", tmp_path / "x.png", "--size", "0x5").exit_code == 2
    result = run("render", tmp_path / "missing.obj", "--png", tmp_path / "x.png")
    assert result.exit_code == 1 and result.output.count("\n") == 1 and "c1surf: error:" in result.output
    assert not (tmp_path / "x.png").exists()


def test_exr_writer_copes_with_strided_arrays(tmp_path):
    """OpenEXR's binding writes wrong pixels from non-contiguous arrays; ours copies first."""
    a = np.arange(60, dtype=np.float64).reshape(6, 10)
    channels = {"x": a[:, ::2], "y": a.T.copy().T[:, 1::2], "z": np.asfortranarray(a[:, :5])}
    write_exr(tmp_path / "s.exr", channels, {"note": "strided"})
    back, header = read_exr(tmp_path / "s.exr")
    for name, data in channels.items():
        np.testing.assert_array_equal(back[name], data.astype(np.float32))
    assert header["note"] == "strided"


def test_png_writer_takes_rgb8_pictures(tmp_path):
    """Pictures are (H, W, 3) uint8 arrays (``render.pictures``); the writer keeps them exactly."""
    picture = np.random.default_rng(0).integers(0, 256, (5, 7, 3), dtype=np.uint8)
    write_png(tmp_path / "p.png", picture)
    with PILImage.open(tmp_path / "p.png") as im:
        assert im.mode == "RGB" and np.array_equal(np.asarray(im), picture)
    with pytest.raises(ValueError, match="uint8"):
        write_png(tmp_path / "f.png", picture / 255.0)


def test_without_embree_the_numpy_fallback_gives_the_same_image(monkeypatch):
    patch_set = load_patch_set(GOLDEN / "tetrahedron.json")
    mesh = patch_grid_mesh(patch_set.groups, 4)
    camera = frame_camera(mesh.points, 40, 30, "iso")
    fast = render(patch_set, camera, mesh=mesh)
    assert fast.info["engine"] == "embree"
    monkeypatch.setitem(__import__("sys").modules, "embreex", None)  # import embreex now fails
    with pytest.warns(RuntimeWarning, match="embreex"):
        slow = render(patch_set, camera, mesh=mesh)
    assert slow.info["engine"] == "trimesh"
    same = fast.channels["patch"] == slow.channels["patch"]
    assert same.mean() > 0.99
    on = same & fast.mask
    np.testing.assert_allclose(slow.channels["kmax"][on], fast.channels["kmax"][on], rtol=1e-9)
