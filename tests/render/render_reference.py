"""Test-only image statistics for the render tests."""
from __future__ import annotations

import numpy as np

from c1surf.render.shading import wrap


def edge_discontinuity(values: np.ndarray, patch: np.ndarray, angular: bool = True):
    """Jumps of an image field across patch edges, with the smooth trend removed.

    For four pixels in a row (or column) a b | c d with a, b on one patch and c, d on
    another, the jump is ``|(c - b) - ((b - a) + (d - c)) / 2|``: about zero where the
    field is continuous and differentiable along the line, of the order of a pixel times
    the change of slope where only its derivative jumps (a G1 surface's reflection lines
    have such kinks), and the size of the break where the field itself jumps (normals
    that jump across an edge). The same statistic for four pixels on one patch is
    returned for scale.

    Returns
    -------
    across : (k,) float, one value per edge crossing
    within : (l,) float, one value per run of four pixels on one patch
    """
    across, within = [], []
    for f, p in ((values, patch), (values.T, patch.T)):
        a, b, c, d = f[:, :-3], f[:, 1:-2], f[:, 2:-1], f[:, 3:]
        pa, pb, pc, pd = p[:, :-3], p[:, 1:-2], p[:, 2:-1], p[:, 3:]
        on = (pa >= 0) & (pd >= 0) & (pb >= 0) & (pc >= 0)
        on &= np.isfinite(a) & np.isfinite(b) & np.isfinite(c) & np.isfinite(d)
        step = wrap if angular else (lambda x: x)
        jump = np.abs(step(c - b) - 0.5 * (step(b - a) + step(d - c)))
        across.append(jump[on & (pa == pb) & (pc == pd) & (pb != pc)])
        within.append(jump[on & (pa == pb) & (pb == pc) & (pc == pd)])
    return np.concatenate(across), np.concatenate(within)
