"""Packing biquadratic patches into merged B-spline pieces (``convert --merge``, ``evaluation.merge``).

Every piece is the patches it replaces (scipy's B-spline against the Bezier patches, to 1e-13
of the bounding-box diagonal at 7 x 7 parameters per span); no patch is in two pieces; each
piece is a rectangle of truly adjacent patches (topological neighbours, sharing their control
points along the common side once turned); the faces a CAD file gets (pieces, the patches left
over, the bicubic patches) are still G1.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import BSpline

from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.adjacency import patch_adjacency
from c1surf.evaluation.bezier import evaluate_patches
from c1surf.evaluation import merge as merge_module
from c1surf.evaluation.merge import merge_biquadratic
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.io.meshes.obj import read_obj
from c1surf.io.patches.merged import piece_patches

from conftest import SAMPLES

MESHES = ["twisted.obj", "double_torus.obj", "cube.obj", "high_valence.obj", "hexagon_six_valent.obj"]


def build(name: str, rational: bool = False) -> Surface:
    mesh = read_obj(SAMPLES / name)
    kwargs = {"weights": np.random.default_rng(4).uniform(0.5, 2.0, mesh.n_vertices)} if rational else {}
    return Surface(mesh.face_sizes, mesh.face_vertices, mesh.points, SurfaceOptions(), **kwargs)


def turned(surface: Surface, p: int, k: int) -> np.ndarray:
    """Patch p's homogeneous (3, 3, 4) coefficients turned k quarter turns, as the piece sees them."""
    w = surface.biquadratic_weights[p] if surface.rational else np.ones((3, 3))
    return np.rot90(np.concatenate([surface.biquadratic[p] * w[..., None], w[..., None]], -1), k=k, axes=(0, 1))


def piece_values(piece, s: np.ndarray) -> np.ndarray:
    """(m, n, len(s), len(s), 3) values of the piece on span (a, b) at a + s, b + s."""
    m, n = piece.patches.shape
    w = np.ones(piece.points.shape[:2]) if piece.weights is None else piece.weights
    net = np.concatenate([piece.points * w[..., None], w[..., None]], -1)
    bu = BSpline(piece.knots_u, np.eye(m + 2), 2)(np.arange(m)[:, None] + s).reshape(m, len(s), m + 2)
    bv = BSpline(piece.knots_v, np.eye(n + 2), 2)(np.arange(n)[:, None] + s).reshape(n, len(s), n + 2)
    h = np.einsum("asi,btj,ijd->abstd", bu, bv, net)
    return h[..., :3] / h[..., 3:]


@pytest.mark.parametrize("name,rational", [(m, False) for m in MESHES] + [("twisted.obj", True)])
def test_pieces_are_their_patches_and_truly_adjacent(name, rational):
    surface = build(name, rational)
    pieces = merge_biquadratic(surface)
    covered = np.concatenate([p.patches.ravel() for p in pieces])
    assert len(np.unique(covered)) == len(covered)  # every patch in one piece at most
    diagonal = np.linalg.norm(np.ptp(np.concatenate([surface.biquadratic.reshape(-1, 3), surface.bicubic.reshape(-1, 3)]), axis=0))
    neighbours = patch_adjacency(surface.refined, surface.frames).neighbours()[..., 0]
    s = np.linspace(0, 1, 7)
    for piece in pieces:
        m, n = piece.patches.shape
        assert m * n >= 2 and piece.points.shape[:2] == (m + 2, n + 2)
        nets = np.array([[turned(surface, p, k) for p, k in zip(*row)] for row in zip(piece.patches, piece.rotation)])
        h = evaluate_patches(nets.reshape(m * n, 3, 3, 4), s, s).reshape(m, n, len(s), len(s), 4)
        assert np.abs(piece_values(piece, s) - h[..., :3] / h[..., 3:]).max() <= 1e-13 * diagonal
        for a, b, c, d in [(a, b, a + 1, b) for a in range(m - 1) for b in range(n)] + \
                          [(a, b, a, b + 1) for a in range(m) for b in range(n - 1)]:
            p, q = piece.patches[a, b], piece.patches[c, d]
            assert q in neighbours[p]  # the patches really share a side ...
            side = (np.s_[2], np.s_[0]) if c > a else (np.s_[:, 2], np.s_[:, 0])
            assert np.abs(nets[a, b][side[0]] - nets[c, d][side[1]]).max() <= 1e-13 * diagonal  # ... the piece's


@pytest.mark.parametrize("name", ["twisted.obj", "double_torus.obj"])
def test_cad_faces_of_the_pieces_stay_g1(name):
    surface = build(name)
    pieces = merge_biquadratic(surface)
    left = np.setdiff1d(np.arange(len(surface.biquadratic)), np.concatenate([p.patches.ravel() for p in pieces]))
    cut = np.concatenate([piece_patches(p)[0] for p in pieces])
    report = measure_smoothness([np.concatenate([cut.reshape(-1, 3, 3, 3), surface.biquadratic[left]]), surface.bicubic])
    assert report.overshared_edges == 0 and report.boundary_edges == 0
    assert report.relative_gap < 1e-12 and report.max_normal_jump < 1e-9


def one_row(length: int, end_meets: int, side: int):
    """A chart of one row of ``length`` cells (patch j at cell (0, j), unturned) whose last cell's +j side is glued
    to patch ``end_meets``'s local side ``side``: side 3 (its -j side) is a seam when ``end_meets`` is 0; side 2
    (its -i side) is a strip winding round onto its own side, as on hand_closed's QuadriFlow layout."""
    other = np.full((length, 4), -1)
    rot = np.zeros((length, 4), dtype=np.int64)
    other[:-1, 1], other[1:, 3] = np.arange(1, length), np.arange(length - 1)
    other[-1, 1], rot[-1, 1] = end_meets, (side + 1) % 4  # rot = (their side + 2 - our side) % 4
    other[end_meets, side], rot[end_meets, side] = length - 1, (3 - side) % 4
    return {(0, j): (j, 0) for j in range(length)}, other, rot


def test_a_whole_seam_stays_one_piece():
    cells, other, rot = one_row(12, 0, 3)
    assert merge_module._rectangles(cells, other, rot) == [(0, 0, 1, 12)]


@pytest.mark.parametrize("meets", [0, 4, 9])
def test_a_strip_winding_onto_its_own_side_is_cut(meets):
    """A face whose loop uses one edge at two unrelated places is invalid B-rep (BRepCheck: its wire is not closed
    in the face's domain): the strip is cut so that no piece meets itself there."""
    cells, other, rot = one_row(12, meets, 2)
    rectangles = merge_module._rectangles(cells, other, rot)
    covered = [j for _, j0, m, n in rectangles for j in range(j0, j0 + n)]
    assert sorted(covered) == list(range(12))  # every cell once
    assert all(not (j0 <= meets < j0 + n and j0 <= 11 < j0 + n) for _, j0, _, n in rectangles)
    assert rectangles[0] == (0, 0, 1, 11)  # only the last cell is cut off
