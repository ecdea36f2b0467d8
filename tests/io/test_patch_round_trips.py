"""Weights (rational surfaces, A2a) and merged pieces (convert --merge) in every patch format.

JSON and NPZ give back the same coefficients, weights and merged pieces, bit for bit. IGES writes a
piece in place of its patches and gives back the same pieces and the patches cut out of them again.
STEP writes rational Bezier faces and B-spline faces that Open CASCADE reads back on the surface.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial import cKDTree

from c1surf.cli.main import main
from c1surf.construction.surface import Surface
from c1surf.evaluation.merge import merge_biquadratic
from c1surf.evaluation.patch_set import surface_patch_set
from c1surf.io.meshes.obj import read_obj
from c1surf.io.patches.formats import load_patch_set, write_patch_set
from c1surf.io.patches.merged import cad_patch_set, piece_patches, uncovered_groups

from conftest import SAMPLES, weighted_cube

UV = np.array([0.0, 0.3, 0.5, 0.77, 1.0])


def weighted_surface(rational: bool) -> Surface:
    mesh = read_obj(SAMPLES / "twisted.obj")
    weights = np.random.default_rng(1).uniform(0.5, 2.0, mesh.n_vertices) if rational else None
    return Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, weights=weights)


def merged_patch_set(surface: Surface, merge: bool = True):
    return dataclasses.replace(surface_patch_set(surface, "twisted.obj"), merged=merge_biquadratic(surface) if merge else [])


def assert_same_pieces(got: list, want: list, bookkeeping: bool = True):
    assert len(got) == len(want) > 0
    for a, b in zip(got, want):
        assert np.array_equal(a.points, b.points) and np.array_equal(a.knots_u, b.knots_u)
        assert np.array_equal(a.knots_v, b.knots_v)
        assert (a.weights is None) == (b.weights is None)
        assert a.weights is None or np.array_equal(a.weights, b.weights)
        if bookkeeping:
            assert np.array_equal(a.patches, b.patches) and np.array_equal(a.rotation, b.rotation)


@pytest.mark.parametrize("rational", [False, True])
@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_json_and_npz_give_back_weights_and_merged_pieces(tmp_path, suffix, rational):
    original = merged_patch_set(weighted_surface(rational))
    path = tmp_path / f"s{suffix}"
    write_patch_set(path, original)
    back = load_patch_set(path)
    assert len(back.groups) == len(original.groups)
    assert all(np.array_equal(a, b) for a, b in zip(back.groups, original.groups))
    assert (back.weights is None) == (not rational)
    if rational:
        assert all(np.array_equal(a, b) for a, b in zip(back.weights, original.weights))
    assert_same_pieces(back.merged, original.merged)
    write_patch_set(tmp_path / f"again{suffix}", back)  # what was read writes the same file again
    assert (tmp_path / f"again{suffix}").read_bytes() == path.read_bytes()


@pytest.mark.parametrize("rational", [False, True])
def test_iges_gives_back_weights_exactly(tmp_path, rational):
    surface = weighted_surface(rational)
    original = merged_patch_set(surface, merge=False)
    write_patch_set(tmp_path / "s.igs", original)
    back = load_patch_set(tmp_path / "s.igs")
    assert all(np.array_equal(a, b) for a, b in zip(back.groups, original.groups))
    assert (back.weights is None) == (not rational) and back.merged == []
    if rational:
        assert all(np.array_equal(a, b) for a, b in zip(back.weights, original.weights))


@pytest.mark.parametrize("rational", [False, True])
def test_iges_gives_back_merged_pieces_and_their_patches(tmp_path, rational):
    surface = weighted_surface(rational)
    original = merged_patch_set(surface)
    write_patch_set(tmp_path / "s.igs", original, strips=False)  # whole pieces (--cad-pieces)
    back = load_patch_set(tmp_path / "s.igs")
    assert_same_pieces(back.merged, original.merged, bookkeeping=False)
    # IGES holds the pieces instead of their patches: the reader cuts them out again, piece by piece
    cut = sum(piece.patches.size for piece in back.merged)
    quad = back.groups[0]
    assert len(quad) == len(surface.biquadratic) and back.groups[1].shape == surface.bicubic.shape
    scale = np.abs(surface.biquadratic).max()
    for got, want in zip(back.merged, original.merged):
        assert np.array_equal(got.rotation, np.zeros_like(want.rotation))
        for (a, b), k in zip(np.ndindex(want.patches.shape), got.patches.ravel()):
            turned = np.rot90(surface.biquadratic[want.patches[a, b]], k=want.rotation[a, b], axes=(0, 1))
            assert np.abs(quad[k] - turned).max() <= 1e-14 * scale
    # the patches no piece stands for follow, exactly as written
    kept, kept_weights = uncovered_groups(original)
    read = [quad[cut:], back.groups[1]]
    written = [next((g for g in kept if g.shape[1] == n), np.zeros((0, n, n, 3))) for n in (3, 4)]
    assert all(np.array_equal(a, b) for a, b in zip(read, written))
    assert (back.weights is None) == (not rational)
    if rational:
        read = [back.weights[0][cut:], back.weights[1]]
        written = [next((w for g, w in zip(kept, kept_weights) if g.shape[1] == n), np.zeros((0, n, n))) for n in (3, 4)]
        assert all(np.array_equal(a, b) for a, b in zip(read, written))


@pytest.mark.parametrize("rational", [False, True])
def test_convert_merge_writes_pieces_to_every_patch_format(tmp_path, rational):
    """convert --merge --cad-pieces: JSON and NPZ hold every patch and the pieces; IGES the pieces and the rest;
    all keep weights."""
    source = weighted_cube(tmp_path, rational)
    paths = [tmp_path / f"s{suffix}" for suffix in (".json", ".npz", ".igs")]
    args = ["convert", str(source), "-o", str(tmp_path / "s.ply"), "--merge", "--cad-pieces", "-q"]
    for path in paths:
        args += ["--patches", str(path)]
    assert CliRunner().invoke(main, args, catch_exceptions=False).exit_code == 0
    json_set, npz_set, iges_set = (load_patch_set(p) for p in paths)
    assert_same_pieces(npz_set.merged, json_set.merged)
    assert_same_pieces(iges_set.merged, json_set.merged, bookkeeping=False)
    assert iges_set.n_patches == json_set.n_patches
    assert all((s.weights is not None) == rational for s in (json_set, npz_set, iges_set))
    assert (json_set.merged[0].weights is not None) == rational


# ----------------------------------------------------------------------------
# STEP, read back with Open CASCADE


def rational_values(points: np.ndarray, weights: np.ndarray | None) -> np.ndarray:
    """Points of Bezier patches (p, n, n, 3) with weights (p, n, n) or None on the UV x UV grid: (p, 5, 5, 3)."""
    d = points.shape[1] - 1
    basis = np.array([[math.comb(d, i) * t**i * (1 - t) ** (d - i) for i in range(d + 1)] for t in UV])
    w = np.ones(points.shape[:3]) if weights is None else weights
    numerator = np.einsum("ai,bj,pij,pijc->pabc", basis, basis, w, points)
    return numerator / np.einsum("ai,bj,pij->pab", basis, basis, w)[..., None]


def step_spans(path) -> tuple[list, np.ndarray]:
    """(the faces' surfaces, (S, 5, 5, 3) their values on UV x UV of every unit span) of a STEP file."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepTools import BRepTools
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    reader = STEPControl_Reader()
    assert reader.ReadFile(str(path)) == IFSelect_RetDone and reader.TransferRoots() >= 1
    explorer = TopExp_Explorer(reader.OneShape(), TopAbs_FACE)
    surfaces, values = [], []
    while explorer.More():
        face = TopoDS.Face_s(explorer.Current()) if hasattr(TopoDS, "Face_s") else TopoDS.Face(explorer.Current())
        geom = BRep_Tool.Surface_s(face)
        u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
        surfaces.append(geom)
        for i, j in np.ndindex(round(u1 - u0), round(v1 - v0)):
            values.append([[[p.X(), p.Y(), p.Z()] for p in (geom.Value(u0 + i + u, v0 + j + v) for v in UV)] for u in UV])
        explorer.Next()
    return surfaces, np.array(values)


@pytest.mark.parametrize("strips", [True, False], ids=["strips", "pieces"])
def test_step_writes_rational_faces_and_merged_pieces(tmp_path, strips):
    surface = weighted_surface(True)
    patch_set = merged_patch_set(surface)
    write_patch_set(tmp_path / "s.step", patch_set, strips=strips)
    patch_set = cad_patch_set(patch_set) if strips else patch_set  # what the file holds
    surfaces, got = step_spans(tmp_path / "s.step")
    kept, kept_weights = uncovered_groups(patch_set)
    assert len(surfaces) == len(patch_set.merged) + sum(len(g) for g in kept)
    assert all(s.IsURational() and s.IsVRational() for s in surfaces)
    cut = [piece_patches(piece) for piece in patch_set.merged]
    want = np.concatenate([rational_values(p, w) for p, w in cut]
                          + [rational_values(g, w) for g, w in zip(kept, kept_weights)])
    assert got.shape == want.shape  # one unit span per patch
    distance, order = cKDTree(want[:, 2, 2]).query(got[:, 2, 2])
    assert np.array_equal(np.sort(order), np.arange(len(want)))
    scale = float(np.linalg.norm(np.ptp(want.reshape(-1, 3), axis=0)))
    assert np.abs(got - want[order]).max() <= 1e-9 * scale
