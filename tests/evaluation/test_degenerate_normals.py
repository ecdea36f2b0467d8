"""Degenerate patches (zero blend ratio, Lemma 1.3.12) have points without a tangent plane: no output carries NaN."""
from __future__ import annotations

import numpy as np
from click.testing import CliRunner
from plyfile import PlyData

from c1surf.api import surface_from_file, tessellate_surface
from c1surf.cli.main import main

from conftest import SAMPLES


def test_a_zero_blend_cube_tessellates_without_nan():
    surface, _ = surface_from_file(SAMPLES / "cube.obj", blend=0.0)
    tess = tessellate_surface(surface, 8)
    assert np.isfinite(tess.points).all() and np.isfinite(tess.normals).all()
    length = np.linalg.norm(tess.normals, axis=1)
    assert np.allclose(length[length > 0], 1.0)
    # zero only where no neighbour has a normal either: the coalesced cube corners
    corners = np.isclose(np.abs(tess.points), 1.0).all(axis=1)
    assert np.all(corners[length == 0])
    # away from the coalesced edges the surface is the cube's faces, with their exact normals
    face_middle = np.isclose(np.abs(tess.points).max(axis=1), 1.0) & (np.sort(np.abs(tess.points), axis=1)[:, 1] < 0.5)
    assert np.allclose(np.abs(tess.normals[face_middle]).max(axis=1), 1.0)


def test_convert_writes_no_nan_normals_or_curvature(tmp_path):
    out = tmp_path / "zero.ply"
    result = CliRunner().invoke(main, ["convert", str(SAMPLES / "cube.obj"), "-o", str(out), "--blend", "0", "-q",
                                       "--curvature"])
    assert result.exit_code == 0, result.output
    vertex = PlyData.read(str(out))["vertex"].data
    assert all(np.isfinite(np.asarray(vertex[name])).all() for name in vertex.dtype.names)
