"""Compiled loops (numba) for the integrals of ``measure``: one patch at a time, no temporaries of a block's size.

This is the only module that imports numba, and only the commands that run a kernel import it (``measure``
imports it on its first polynomial block): numba's import (about 0.4 s) and the loading of the compiled
kernels (cached, see ``compiled``) are paid there and nowhere else.

Every kernel loops over patches and computes each patch's value from that patch's coefficients alone, in a
fixed order of floating-point operations (no fast-math: no reassociation, no fused multiply-adds), so a
patch's value does not depend on the block it is computed in, nor on the thread: the streamed and the
in-memory ``measure`` stay equal to the last bit. The kernels release the GIL (``nogil``): ``parallel``'s
threads run them on disjoint ranges of patches.

The cache: ``cache=True`` writes the compiled machine code beside this file (``__pycache__``, in a clone) or,
where that folder is read-only (an installed package), in numba's per-user cache folder; where neither can be
written, the kernels are compiled at every first use of a process instead (a few seconds), never an error.
"""
from __future__ import annotations

import math

import numba
import numpy as np


def compiled(function):
    """``function`` compiled without the GIL, its machine code cached on the disk when a cache folder can be
    written (numba refuses ``cache=True`` at decoration when none can: then compiled in each process)."""
    try:
        return numba.njit(cache=True, nogil=True, error_model="numpy")(function)
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return numba.njit(nogil=True, error_model="numpy")(function)


LANES = 128  # patches computed side by side (each in its own lane of the vector units)


@compiled
def _lanes(points, k0, t1, cp):  # pragma: no cover - compiled
    """``cp[i, j, c, t] = points[k0 + t, i, j, c]`` for t < t1: a run of patches, coordinate-major."""
    for t in range(t1):
        for i in range(points.shape[1]):
            for j in range(points.shape[2]):
                for c in range(3):
                    cp[i, j, c, t] = points[k0 + t, i, j, c]


@compiled
def _rows(cp, t1, bv, bv1, b, q, qv):  # pragma: no cover - compiled
    """``q[i, c, t] = sum_j bv[b, j] cp[i, j, c, t]`` (j in order) and ``qv`` the same with ``bv1``: the rows of
    control points summed along v at the node ``v_b``, so that ``x(u, v_b) = sum_i B_i(u) q[i]``."""
    for i in range(cp.shape[0]):
        for c in range(3):
            for t in range(t1):
                q[i, c, t] = 0.0
                qv[i, c, t] = 0.0
            for j in range(cp.shape[1]):
                f, g = bv[b, j], bv1[b, j]
                for t in range(t1):
                    q[i, c, t] += f * cp[i, j, c, t]
                    qv[i, c, t] += g * cp[i, j, c, t]


@compiled
def _combine(q, t1, basis, a, out):  # pragma: no cover - compiled
    """``out[c, t] = sum_i basis[a, i] q[i, c, t]`` (i in order)."""
    for c in range(3):
        for t in range(t1):
            out[c, t] = 0.0
    for i in range(q.shape[0]):
        f = basis[a, i]
        for c in range(3):
            for t in range(t1):
                out[c, t] += f * q[i, c, t]


@compiled
def area_sums(points, rule, out):  # pragma: no cover - compiled (tests call it compiled)
    """``out[k] = sum_b wv[b] sum_a wu[a] |x_u x x_v|(u_a, v_b)`` of patch ``k``: the area by one tensor rule.

    points : (p, du+1, dv+1, 3) float64; rule : (bu, bu1, bv, bv1, wu, wv): bu, bu1 : (mu, du+1) float, the
    Bernstein basis and its derivative at the u nodes; bv, bv1 : (mv, dv+1) the same in v; wu, wv : (mu,), (mv,)
    float; out : (p,) float
    """
    bu, bu1, bv, bv1, wu, wv = rule
    p, m, n = points.shape[0], points.shape[1], points.shape[2]
    cp = np.empty((m, n, 3, LANES))
    q, qv = np.empty((m, 3, LANES)), np.empty((m, 3, LANES))
    xu, xv, row, total = np.empty((3, LANES)), np.empty((3, LANES)), np.empty(LANES), np.empty(LANES)
    for k0 in range(0, p, LANES):
        t1 = min(LANES, p - k0)
        _lanes(points, k0, t1, cp)
        total[:] = 0.0
        for b in range(bv.shape[0]):
            _rows(cp, t1, bv, bv1, b, q, qv)
            row[:] = 0.0
            for a in range(bu.shape[0]):
                _combine(q, t1, bu1, a, xu)
                _combine(qv, t1, bu, a, xv)
                w = wu[a]
                for t in range(t1):
                    nx = xu[1, t] * xv[2, t] - xu[2, t] * xv[1, t]
                    ny = xu[2, t] * xv[0, t] - xu[0, t] * xv[2, t]
                    nz = xu[0, t] * xv[1, t] - xu[1, t] * xv[0, t]
                    row[t] += w * math.sqrt(nx * nx + ny * ny + nz * nz)
            w = wv[b]
            for t in range(t1):
                total[t] += w * row[t]
        for t in range(t1):
            out[k0 + t] = total[t]


@compiled
def moment_sums(points, rule, origin, out):  # pragma: no cover - compiled
    """The divergence theorem's moments of patch ``k`` by one tensor rule, in ``measure.moment_integrand``'s
    columns: ``out[k] = (V, int_V y (3), int_V y y^T (9, row-major))`` with ``y = x - origin``: the sums over the
    nodes of ``w y.N``, ``w y (y.N)``, ``w y y^T (y.N)`` (``N = x_u x x_v``, ``w = wu[a] wv[b]``) over 3, 4, 5.

    points, rule : as ``area_sums``'; origin : (3,) float; out : (p, 13) float
    """
    bu, bu1, bv, bv1, wu, wv = rule
    p, m, n = points.shape[0], points.shape[1], points.shape[2]
    cp = np.empty((m, n, 3, LANES))
    q, qv = np.empty((m, 3, LANES)), np.empty((m, 3, LANES))
    x, xu, xv, acc = np.empty((3, LANES)), np.empty((3, LANES)), np.empty((3, LANES)), np.empty((10, LANES))
    for k0 in range(0, p, LANES):
        t1 = min(LANES, p - k0)
        _lanes(points, k0, t1, cp)
        acc[:] = 0.0  # flux; y flux (3); y_i y_j flux for ij = 00 01 02 11 12 22
        for b in range(bv.shape[0]):
            _rows(cp, t1, bv, bv1, b, q, qv)
            for a in range(bu.shape[0]):
                _combine(q, t1, bu, a, x)
                _combine(q, t1, bu1, a, xu)
                _combine(qv, t1, bu, a, xv)
                w = wu[a] * wv[b]
                for t in range(t1):
                    y0, y1, y2 = x[0, t] - origin[0], x[1, t] - origin[1], x[2, t] - origin[2]
                    flux = w * (y0 * (xu[1, t] * xv[2, t] - xu[2, t] * xv[1, t])
                                + y1 * (xu[2, t] * xv[0, t] - xu[0, t] * xv[2, t])
                                + y2 * (xu[0, t] * xv[1, t] - xu[1, t] * xv[0, t]))
                    f0, f1, f2 = flux * y0, flux * y1, flux * y2
                    acc[0, t] += flux
                    acc[1, t] += f0
                    acc[2, t] += f1
                    acc[3, t] += f2
                    acc[4, t] += f0 * y0
                    acc[5, t] += f0 * y1
                    acc[6, t] += f0 * y2
                    acc[7, t] += f1 * y1
                    acc[8, t] += f1 * y2
                    acc[9, t] += f2 * y2
        for t in range(t1):
            k = k0 + t
            out[k, 0] = acc[0, t] / 3.0
            out[k, 1] = acc[1, t] / 4.0
            out[k, 2] = acc[2, t] / 4.0
            out[k, 3] = acc[3, t] / 4.0
            out[k, 4] = acc[4, t] / 5.0
            out[k, 5] = out[k, 7] = acc[5, t] / 5.0
            out[k, 6] = out[k, 10] = acc[6, t] / 5.0
            out[k, 8] = acc[7, t] / 5.0
            out[k, 9] = out[k, 11] = acc[8, t] / 5.0
            out[k, 12] = acc[9, t] / 5.0


@compiled
def side_frames(points, edges, layout, out):  # pragma: no cover - compiled
    """Points and unit normals along patch sides (``smoothness.side_frames``' values, one side at a time).

    points : (P, (d+1)^2, >= 3) float64, patches flattened (a group's whole array: only the sides' two rows are
    read);
    edges : (ids, slots, sides, reverse): ids : (c,) int, the patch of each side; slots : (c,) int, the row of
    ``x_out`` and ``n_out`` each side fills; sides : (c,) int, 0..3; reverse : (c,) bool, run the side from 1 to 0;
    layout : (offsets, basis, dbasis, across): offsets : (4, 2, d+1) int, ``adjacency.side_offsets(d)``; basis,
    dbasis : (m, d+1) float, the Bernstein basis and its derivative at the parameters along the side; across :
    (4,) float, d or -d, the sign and factor of the derivative across side s from its two rows;
    out : (x_out, n_out), (K, m, 3) float each, NaN normals where x_u x x_v = 0
    """
    ids, slots, sides, reverse = edges
    offsets, basis, dbasis, across = layout
    x_out, n_out = out
    n1 = offsets.shape[2]
    rows = np.empty((n1, 3))  # the side's control points, in the side's direction
    steps = np.empty((n1, 3))  # the next row inwards minus the side's
    for k in range(ids.shape[0]):
        e, s, slot, flip = ids[k], sides[k], slots[k], reverse[k]
        for i in range(n1):
            r = n1 - 1 - i if flip else i
            o, q = offsets[s, 0, r], offsets[s, 1, r]
            for c in range(3):
                rows[i, c] = points[e, o, c]
                steps[i, c] = points[e, q, c] - points[e, o, c]
        c = across[s]
        for a in range(basis.shape[0]):
            x0 = x1 = x2 = g0 = g1 = g2 = h0 = h1 = h2 = 0.0
            for i in range(n1):
                f, g = basis[a, i], dbasis[a, i]
                x0 += f * rows[i, 0]
                x1 += f * rows[i, 1]
                x2 += f * rows[i, 2]
                g0 += g * rows[i, 0]
                g1 += g * rows[i, 1]
                g2 += g * rows[i, 2]
                h0 += f * steps[i, 0]
                h1 += f * steps[i, 1]
                h2 += f * steps[i, 2]
            if flip:  # along the side, in the patch's own direction
                g0, g1, g2 = -g0, -g1, -g2
            h0, h1, h2 = c * h0, c * h1, c * h2
            if s % 2 == 1:  # sides 1 and 3: across is x_u, along x_v
                u0, u1, u2, v0, v1, v2 = h0, h1, h2, g0, g1, g2
            else:
                u0, u1, u2, v0, v1, v2 = g0, g1, g2, h0, h1, h2
            m0 = u1 * v2 - u2 * v1
            m1 = u2 * v0 - u0 * v2
            m2 = u0 * v1 - u1 * v0
            length = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
            x_out[slot, a, 0], x_out[slot, a, 1], x_out[slot, a, 2] = x0, x1, x2
            n_out[slot, a, 0], n_out[slot, a, 1], n_out[slot, a, 2] = m0 / length, m1 / length, m2 / length


@compiled
def frame_jumps(xa, na, xb, nb, unoriented, gap, angle):  # pragma: no cover - compiled
    """Gap ``|xa - xb|`` and normal jump ``atan2(|na x nb|, na . nb)`` (``|na . nb|`` when ``unoriented``; 0 where
    a normal is undefined) at every sample: xa, na, xb, nb : (k, m, 3) float; gap, angle : (k * m,) float."""
    m = xa.shape[1]
    for e in range(xa.shape[0]):
        for a in range(m):
            d0, d1, d2 = xa[e, a, 0] - xb[e, a, 0], xa[e, a, 1] - xb[e, a, 1], xa[e, a, 2] - xb[e, a, 2]
            gap[e * m + a] = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            p0, p1, p2 = na[e, a, 0], na[e, a, 1], na[e, a, 2]
            q0, q1, q2 = nb[e, a, 0], nb[e, a, 1], nb[e, a, 2]
            c0, c1, c2 = p1 * q2 - p2 * q1, p2 * q0 - p0 * q2, p0 * q1 - p1 * q0
            dot = p0 * q0 + p1 * q1 + p2 * q2
            t = math.atan2(math.sqrt(c0 * c0 + c1 * c1 + c2 * c2), abs(dot) if unoriented else dot)
            angle[e * m + a] = 0.0 if math.isnan(t) else t


@compiled
def _root(parent, i):  # pragma: no cover - compiled
    """The root of ``i`` in the union-find ``parent``, the path halved on the way."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@compiled
def _join(parent, a, b):  # pragma: no cover - compiled
    ra, rb = _root(parent, a), _root(parent, b)
    if ra != rb:
        if ra < rb:
            parent[rb] = ra
        else:
            parent[ra] = rb


@compiled
def cell_components(points, key, order, tolerance, pairs, labels):  # pragma: no cover - compiled
    """``mesh.points.clusters.cluster_points``' components: the points of one cell hash within ``tolerance`` of
    each other (squared distance, summed x, y, z, against tolerance squared, as its ``_within``) and the ``pairs``
    joined; ``labels`` (n,) int64 filled 0, 1, 2, ... in order of each component's first point (scipy's
    ``connected_components`` numbering).

    points : (n, 3) float; key : (k,) int64, cell hashes sorted; order : (k,) int, the points in that order;
    pairs : (m, 2) int, more pairs to join (exact duplicates, pairs across cell faces)
    """
    n = points.shape[0]
    parent = np.arange(n)
    limit = tolerance * tolerance
    k = key.shape[0]
    start = 0
    while start < k:
        stop = start + 1
        while stop < k and key[stop] == key[start]:
            stop += 1
        for i in range(start, stop):
            a = order[i]
            for j in range(i + 1, stop):
                b = order[j]
                d0 = points[a, 0] - points[b, 0]
                d1 = points[a, 1] - points[b, 1]
                d2 = points[a, 2] - points[b, 2]
                if d0 * d0 + d1 * d1 + d2 * d2 <= limit:
                    _join(parent, a, b)
        start = stop
    for r in range(pairs.shape[0]):
        _join(parent, pairs[r, 0], pairs[r, 1])
    count = 0
    for i in range(n):  # a component's root is its lowest point (a join keeps the lower root): labelled first
        root = _root(parent, i)
        if root == i:
            labels[i] = count
            count += 1
        else:
            labels[i] = labels[root]


@compiled
def side_keys(points, basis_u, basis_v, corners, samples, box):  # pragma: no cover - compiled
    """What the side matcher compares (``adjacency._side_points``): corners[e] the corner control points 0..3 of
    patch ``e``, samples[e, s] side s's points at the parameters of ``basis_u`` (sides 0, 2) or ``basis_v``
    (sides 1, 3); ``box`` (2, 3) the running minimum and maximum of the control points, updated.

    points : (c, du+1, dv+1, >= 3) float64; basis_u : (r, du+1), basis_v : (r, dv+1) float; corners : (c, 4, 3),
    samples : (c, 4, r, 3) float
    """
    du, dv = points.shape[1] - 1, points.shape[2] - 1
    for e in range(points.shape[0]):
        for c in range(3):
            corners[e, 0, c] = points[e, 0, 0, c]
            corners[e, 1, c] = points[e, du, 0, c]
            corners[e, 2, c] = points[e, du, dv, c]
            corners[e, 3, c] = points[e, 0, dv, c]
            for a in range(basis_u.shape[0]):
                s0 = s2 = 0.0
                for i in range(du + 1):
                    s0 += basis_u[a, i] * points[e, i, 0, c]
                    s2 += basis_u[a, i] * points[e, i, dv, c]
                s1 = s3 = 0.0
                for j in range(dv + 1):
                    s1 += basis_v[a, j] * points[e, du, j, c]
                    s3 += basis_v[a, j] * points[e, 0, j, c]
                samples[e, 0, a, c], samples[e, 1, a, c], samples[e, 2, a, c], samples[e, 3, a, c] = s0, s1, s2, s3
            low, high = box[0, c], box[1, c]
            for i in range(du + 1):
                for j in range(dv + 1):
                    x = points[e, i, j, c]
                    low, high = min(low, x), max(high, x)
            box[0, c], box[1, c] = low, high


@compiled
def shortest_side(corners, ends, floor):  # pragma: no cover - compiled
    """The shortest chord between the end corners of a patch side longer than ``floor`` (``inf`` if none), as
    ``sides.matching.matching_tolerance`` takes it: corners (P, 4, 3) float, ends (4, 2) int (``SIDE_CORNERS``)."""
    shortest = np.inf
    for p in range(corners.shape[0]):
        for s in range(4):
            a, b = ends[s, 0], ends[s, 1]
            d0 = corners[p, b, 0] - corners[p, a, 0]
            d1 = corners[p, b, 1] - corners[p, a, 1]
            d2 = corners[p, b, 2] - corners[p, a, 2]
            length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if length > floor and length < shortest:
                shortest = length
    return shortest


@compiled
def same_curves(points, ends, a, b, tolerance, out):  # pragma: no cover - compiled
    """``sides.matching._same_curves`` pair by pair, without its block-sized copies: out[k] says that the side
    points of sides a[k] and b[k] (flat ids) lie within ``tolerance`` of each other (squared distances summed
    x, y, z, against tolerance squared), b's taken backwards where it starts at a's end.

    points : (S, r, 3) float, the side points; ends : (S, 2) int, the start and end corner labels of each side;
    a, b : (k,) int; out : (k,) bool
    """
    limit = tolerance * tolerance
    r = points.shape[1]
    for k in range(a.shape[0]):
        i, j = a[k], b[k]
        backwards = ends[i, 0] != ends[j, 0]
        same = True
        for q in range(r):
            w = r - 1 - q if backwards else q
            d0 = points[i, q, 0] - points[j, w, 0]
            d1 = points[i, q, 1] - points[j, w, 1]
            d2 = points[i, q, 2] - points[j, w, 2]
            if not d0 * d0 + d1 * d1 + d2 * d2 <= limit:
                same = False
                break
        out[k] = same
