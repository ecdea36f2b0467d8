"""The deviation picture: a scan coloured by its distance, with a colour bar (render.deviation)."""
from __future__ import annotations

import numpy as np

from c1surf.io.images.png import write_png
from c1surf.render.camera import frame_camera
from c1surf.render.deviation import deviation_picture
from c1surf.render.pictures import colormap, rgb8


def _grid(n: int = 20):
    """A flat square [-1, 1]^2 at z = 0 as (n+1)^2 points and 2 n^2 triangles, facing +z."""
    x, y = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1), indexing="xy")
    points = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    v = (i * (n + 1) + j).ravel()
    triangles = np.concatenate([np.stack([v, v + 1, v + n + 2], 1), np.stack([v, v + n + 2, v + n + 1], 1)])
    return points, triangles


def test_known_scalar_gives_the_expected_colour_at_a_known_pixel():
    points, triangles = _grid()
    values = points[:, 0] + 1.0  # 0 at the left edge, 2 at the right: linear, so interpolation is exact
    width = height = 201
    picture = deviation_picture(points, triangles, values, width=width, height=height, view="front", legend=False)
    camera = frame_camera(points, width, height, "front")
    for x in (-0.5, 0.0, 0.5):
        row, column = np.floor(camera.project(np.array([[x, 0.0, 0.0]]))[0]).astype(int)
        origins, directions = camera.rays(slice(row, row + 1))
        d = directions[column]
        hit = origins[column] - d * origins[column, 2] / d[2]  # where the pixel's ray meets z = 0
        expected = rgb8(colormap(hit[0] + 1.0, 0.0, 2.0) * (0.45 + 0.55 * abs(d[2])))
        assert np.abs(picture[row, column].astype(int) - expected.astype(int)).max() <= 1


def test_colours_vary_with_the_scalar_and_the_bar_is_drawn(tmp_path):
    points, triangles = _grid()
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    values = 1e-3 * diagonal * (points[:, 0] + 1.0)
    plain = deviation_picture(points, triangles, values, diagonal=diagonal, width=320, height=240, legend=False)
    picture = deviation_picture(points, triangles, values, diagonal=diagonal, width=320, height=240)
    assert picture.shape == (240, 320, 3) and picture.dtype == np.uint8
    colours = np.unique(plain.reshape(-1, 3), axis=0)
    assert colours.shape[0] > 50  # a ramp, not one flat colour
    # the bar: a white panel in the lower right corner, with the colour map's ends inside it
    changed = np.any(picture != plain, axis=2)
    rows, columns = np.nonzero(changed)
    assert rows.min() > 240 * 0.3 and columns.min() > 320 * 0.6
    panel = picture[rows.min():rows.max() + 1, columns.min():columns.max() + 1].reshape(-1, 3)
    assert np.any(np.all(panel == 255, axis=1))
    for end in (0.0, 1.0):
        colour = rgb8(colormap(end, 0.0, 1.0))
        assert np.any(np.abs(panel.astype(int) - colour.astype(int)).max(axis=1) <= 2)
    write_png(tmp_path / "deviation.png", picture)
    assert (tmp_path / "deviation.png").stat().st_size > 0
