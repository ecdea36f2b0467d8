"""A dart's cell after refinement, built by hand: the n-sided hole, the quads around it, and a C0 crease that
arrives along one spoke (test helper for ``construction.stencils.holes.dart``; docs/research/c0_dart_hole.py prints it).

Sector i of the refined mesh around the n-gon is a grid G_i[r][s], r, s = 0..R, with G_i[0][0] = C_i,
G_i[1][0] = B_{i,2}, G_i[0][1] = B_{i,1}, G_i[1][1] = A_i; the strip between sectors i and i + 1 is the
quads (G_i[r][0], G_i[r+1][0], G_{i+1}[0][r+1], G_{i+1}[0][r]). The crease runs along the strip between
sector n - 1 (*before*) and sector 0 (*after*): each side's biquadratic patches read, across it, the mirrors
of their own side's points about crease points chi_r (as ``mesh.creases.sheets`` makes them), and the hole is
``dart_hole_coefficients`` with the same mirrors. Patches are measured side by side, matched by their
geometry here (``shared_sides``), independently of the construction's bookkeeping.
"""
from __future__ import annotations

import numpy as np

from c1surf.construction.stencils.holes.dart import dart_hole_coefficients
from c1surf.evaluation.bezier import bernstein_basis, raise_degree


def sector_grids(n: int, R: int = 4, noise: float = 0.05, slope: float = 1.0, seed: int = 0):
    """(n, R + 1, R + 1, 3) float grids and (R + 1, 3) crease points chi_r.

    The points lie on the roof z = slope |y| (90-degree dihedral angle at slope 1) whose ridge is the
    positive x axis, the crease strip's line; noise moves every point and every crease point.
    """
    rng = np.random.default_rng(seed)
    angle = 2 * np.pi * np.arange(n + 1) / n
    d = np.stack([np.cos(angle), np.sin(angle)], axis=1)  # d_i, d_n = d_0
    r = np.arange(R + 1)
    G = np.zeros((n, R + 1, R + 1, 3))
    for i in range(n):
        corner = 0.5 * (d[i] + d[(i + 1) % n]) / max(np.sin(np.pi / n), 0.5)
        xy = corner + r[:, None, None] * d[(i + 1) % n] + r[None, :, None] * d[i]
        G[i, ..., :2] = xy
    G[..., 2] = slope * np.abs(G[..., 1])
    G += noise * rng.standard_normal(G.shape)
    chi = (G[n - 1, :, 0] + G[0, 0, :]) / 2  # near the ridge, then moved off the midpoints
    chi[:, 1] = 0.0
    chi[:, 2] = 0.0
    chi += noise * rng.standard_normal(chi.shape)
    return G, chi


def neighbour(G: np.ndarray, chi: np.ndarray, i: int, r: int, s: int) -> np.ndarray:
    """The point at (r, s) of sector i's frame, r or s = -1 across a strip; across the crease strip a
    sector reads the mirrors of its own points."""
    n = G.shape[0]
    if r >= 0 and s >= 0:
        return G[i, r, s]
    if s == -1:  # across the strip i | i + 1: G_{i+1}[0][r]
        return 2 * chi[r] - G[i, r, 0] if i == n - 1 else G[(i + 1) % n, 0, r]
    # r == -1: across the strip i - 1 | i: G_{i-1}[s][0]
    return 2 * chi[s] - G[i, 0, s] if i == 0 else G[(i - 1) % n, s, 0]


def biquadratic_patches(G: np.ndarray, chi: np.ndarray):
    """(P, 3, 3, 3) Bezier coefficients of every refined point but the hole's corners whose 3 x 3
    neighbourhood is there, and (P, 3) int (sector, r, s) of its centre."""
    n, R = G.shape[0], G.shape[1] - 1
    half = np.array([[0.5, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.5, 0.5]])  # quadratic B-spline -> Bezier
    patches, where = [], []
    for i in range(n):
        for r in range(R):
            for s in range(R):
                if r == 0 and s == 0:
                    continue
                N = np.array([[neighbour(G, chi, i, r + a - 1, s + b - 1) for b in range(3)] for a in range(3)])
                # u along s, v along r: the hole's patches' handedness (p_i's u runs from L_i to M_i, across
                # the strip i | i + 1, i.e. along -s; its v along -r)
                patches.append(np.einsum("ka,lb,bad->kld", half, half, N))
                where.append((i, r, s))
    return np.array(patches), np.array(where)


def hole_patches(G: np.ndarray, chi: np.ndarray, **shape) -> np.ndarray:
    """(n, 4, 4, 3): the dart's hole, crease spoke n - 1 between p_{n-1} (sector n - 1) and p_0."""
    n = G.shape[0]
    A, B1, B2, C = G[:, 1, 1], G[:, 0, 1], G[:, 1, 0], G[:, 0, 0]
    before_C, before_B = 2 * chi[0] - C[n - 1], 2 * chi[1] - B2[n - 1]  # sector n - 1's view of C_0, B_{0,1}
    after_C, after_B = 2 * chi[0] - C[0], 2 * chi[1] - B1[0]  # sector 0's view of C_{n-1}, B_{n-1,2}
    return dart_hole_coefficients(A, B1, B2, C, (before_C, before_B, after_C, after_B), **shape)


def side_rows(patch: np.ndarray, side: int):
    """(boundary row, next row) of a (d+1, d+1, 3) patch on side 0 (v = 0), 1 (u = 1), 2 (v = 1), 3 (u = 0),
    and the sign that makes next - boundary point into the patch."""
    if side == 0:
        return patch[:, 0], patch[:, 1]
    if side == 1:
        return patch[-1, :], patch[-2, :]
    if side == 2:
        return patch[:, -1], patch[:, -2]
    return patch[0, :], patch[1, :]


def side_samples(patch: np.ndarray, side: int, t: np.ndarray):
    """(points (m, 3), unit normals (m, 3)) along one side of a patch, normals from the patch's own u x v."""
    d = patch.shape[0] - 1
    # derivatives of the whole patch at the side's parameters, so the normal is u x v whatever the side
    u = t if side in (0, 2) else np.full(t.size, 1.0 if side == 1 else 0.0)
    v = t if side in (1, 3) else np.full(t.size, 1.0 if side == 2 else 0.0)
    bu, bv = bernstein_basis(d, u), bernstein_basis(d, v)
    dbu, dbv = bernstein_basis(d, u, 1), bernstein_basis(d, v, 1)
    point = np.einsum("mk,ml,kld->md", bu, bv, patch)
    pu = np.einsum("mk,ml,kld->md", dbu, bv, patch)
    pv = np.einsum("mk,ml,kld->md", bu, dbv, patch)
    normal = np.cross(pu, pv)
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return point, normal / length


def shared_sides(patches: list, tolerance: float):
    """Pairs ((patch a, side a), (patch b, side b), reversed) of sides with the same end and middle points."""
    ids, ends = [], []
    for p, patch in enumerate(patches):
        for side in range(4):
            row, _ = side_rows(patch, side)
            mid = np.einsum("k,kd->d", bernstein_basis(row.shape[0] - 1, np.array([0.5]))[0], row)
            ids.append((p, side))
            ends.append((row[0], row[-1], mid))
    start, end, mid = (np.array([e[k] for e in ends]) for k in range(3))
    close = lambda x, y: np.linalg.norm(x[:, None] - y[None], axis=2) <= tolerance
    patch = np.array([i[0] for i in ids])
    other = (patch[:, None] != patch[None]) & close(mid, mid)
    forward = other & close(start, start) & close(end, end)
    backward = other & close(start, end) & close(end, start)
    pairs = []
    for x, y in zip(*np.nonzero(np.triu(forward | backward, 1))):
        pairs.append((ids[x], ids[y], bool(backward[x, y] and not forward[x, y])))
    return pairs


def measure_pairs(patches: list, pairs, samples: int = 21):
    """(gaps (k,), normal jumps (k, samples)) of every shared side pair, samples from the pair's first patch's
    side start."""
    t = np.linspace(0.0, 1.0, samples)
    gaps, jumps = [], []
    for (pa, sa), (pb, sb), reverse in pairs:
        xa, na = side_samples(patches[pa], sa, t)
        xb, nb = side_samples(patches[pb], sb, t[::-1] if reverse else t)
        gaps.append(np.linalg.norm(xa - xb, axis=1).max())
        angle = np.arctan2(np.linalg.norm(np.cross(na, nb), axis=1), np.einsum("md,md->m", na, nb))
        jumps.append(np.where(np.isnan(angle), 0.0, angle))
    return np.array(gaps), np.array(jumps)


def dart_cell(n: int, R: int = 4, **kwargs):
    """Everything of one cell: dict with the patches (list of (d+1, d+1, 3)), the hole's indices in it, the
    crease groups (patches on each side of the crease line) and the size (bounding box diagonal)."""
    shape = {k: kwargs.pop(k) for k in ("alpha", "beta", "tangent_rule") if k in kwargs}
    G, chi = sector_grids(n, R, **kwargs)
    quads, where = biquadratic_patches(G, chi)
    hole = hole_patches(G, chi, **shape)
    patches = [hole[i] for i in range(n)] + [q for q in quads]
    before = {n - 1} | {n + k for k, (i, r, s) in enumerate(where) if i == n - 1 and s == 0}
    after = {0} | {n + k for k, (i, r, s) in enumerate(where) if i == 0 and r == 0}
    everything = np.concatenate([p.reshape(-1, 3) for p in patches])
    size = float(np.linalg.norm(everything.max(axis=0) - everything.min(axis=0)))
    return {"patches": patches, "hole": list(range(n)), "before": before, "after": after, "size": size,
            "G": G, "chi": chi}


def crease_pair(pair, cell) -> bool:
    """Is this side pair a piece of the crease (one patch on each side of it)?"""
    (pa, _), (pb, _), _ = pair
    return (pa in cell["before"] and pb in cell["after"]) or (pa in cell["after"] and pb in cell["before"])


def uniform_patches(patches: list) -> np.ndarray:
    """(P, 4, 4, 3): every patch raised to bicubic (for ``measure_smoothness``)."""
    return np.array([raise_degree(p[None], 3, 3)[0] for p in patches])
