"""``io.patches.merged.strip_pieces`` / ``cad_patch_set``: the CAD faces are strips one span wide in u, at most
``max_spans`` long (None: the piece's length), each exactly the patches it covers (turned by its rotations), for
polynomial and rational surfaces; every covered patch in exactly one strip or left as a patch face; every second
strip half turned, so that neighbouring strips meet u = 1 to u = 1 and u = 0 to u = 0."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from c1surf.api import surface_from_file
from c1surf.evaluation.merge import merge_biquadratic, piece_patches
from c1surf.evaluation.patch_set import surface_patch_set
from c1surf.io.patches.merged import cad_patch_set, strip_pieces

from conftest import SAMPLES, surface_of, weighted_cube


def homogeneous(points, weights):
    return points if weights is None else np.concatenate([points * weights[..., None], weights[..., None]], axis=-1)


@pytest.mark.parametrize("source", ["twisted", "torus", "rational cube"])
@pytest.mark.parametrize("max_spans", [1, 3, 1000, None])
def test_strips_are_their_patches(tmp_path, source, max_spans):
    surface = (surface_from_file(weighted_cube(tmp_path, True))[0] if source == "rational cube"
               else surface_of(SAMPLES / f"{source}.obj"))
    pieces = merge_biquadratic(surface)
    quad = homogeneous(surface.biquadratic, surface.biquadratic_weights)
    for piece in pieces:
        strips = strip_pieces(piece, max_spans)
        covered = np.concatenate([s.patches.ravel() for s in strips])
        assert np.array_equal(np.sort(covered), np.sort(piece.patches.ravel()))  # each patch once
        m, n = piece.patches.shape
        cap = max_spans or max(m, n)
        turned = m * -(-n // cap) > n * -(-m // cap)
        assert len(strips) == (n * -(-m // cap) if turned else m * -(-n // cap))  # the fewer
        if max_spans is None:
            assert len(strips) == min(m, n)
        for s in strips:
            assert s.patches.shape[0] == 1 and s.patches.shape[1] <= cap
            assert (s.weights is None) == (surface.biquadratic_weights is None)
            cut = homogeneous(*piece_patches(s))
            want = np.stack([np.rot90(quad[p], k=r, axes=(0, 1)) for p, r in zip(s.patches.ravel(), s.rotation.ravel())])
            scale = np.abs(quad).max()
            if s.weights is not None:  # a rational patch is the same surface for any scale of its weights
                cut = cut / cut[..., -1:].max(axis=(1, 2), keepdims=True)
                want = want / want[..., -1:].max(axis=(1, 2), keepdims=True)
            assert np.abs(cut - want).max() <= 1e-13 * scale


def test_cad_patch_set_leaves_single_spans_as_patches():
    surface = surface_of(SAMPLES / "twisted.obj")
    raw = dataclasses.replace(surface_patch_set(surface), merged=merge_biquadratic(surface))
    whole = cad_patch_set(raw)  # strips as long as their pieces: a single span only from a 1 x 1 piece
    assert all(s.patches.shape[0] == 1 and s.patches.size > 1 for s in whole.merged)
    assert sum(s.patches.size for s in whole.merged) == sum(p.patches.size for p in raw.merged if p.patches.size > 1)
    cad = cad_patch_set(raw, 3)
    assert all(1 < s.patches.size <= 3 and s.patches.shape[0] == 1 for s in cad.merged)
    assert sum(s.patches.size for s in cad.merged) < sum(p.patches.size for p in raw.merged)  # some single spans
    assert cad.groups is raw.groups and cad_patch_set(surface_patch_set(surface)).merged == []


def test_neighbouring_strips_meet_side_to_same_side():
    """Strip i + 1 is strip i's neighbour across u; their shared line is u = 1 of both (i even) or u = 0 of both."""
    surface = surface_of(SAMPLES / "torus.obj")
    piece = max(merge_biquadratic(surface), key=lambda p: min(p.patches.shape))
    strips = strip_pieces(piece)
    assert len(strips) >= 3
    for i, (a, b) in enumerate(zip(strips, strips[1:])):
        side = 0 if i % 2 else -1  # the shared line: u = 1 of both after an upright strip, u = 0 after a turned one
        line_a, line_b = a.points[side], b.points[side]  # (k + 2, 3): the boundary curves' control points
        assert np.abs(line_a - line_b[::-1]).max() <= 1e-13 * np.abs(piece.points).max()  # the same curve, opposite v
