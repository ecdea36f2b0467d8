#!/usr/bin/env python3
"""Generate the c1surf sample meshes (OBJ files with polygon faces) and README.md.

Usage::

    python sample_meshes/generate.py            # writes into sample_meshes/
    python sample_meshes/generate.py --out DIR  # writes into DIR instead

Every mesh is closed, orientable and 2-manifold (each edge lies in exactly two
faces, used once in each direction), its faces are oriented counter-clockwise
seen from outside (outward normals), no vertex has valence 2, no face repeats a
vertex, and every vertex is used.  The script checks all this before writing.

Output is deterministic and byte-identical from run to run and across machines:

* only Python's ``math`` module is used for trigonometry (never numpy's SIMD
  kernels, which may differ in the last bit between CPUs),
* every coordinate is rounded to 12 decimals before it is written, so a one-ulp
  difference in a platform's ``sin``/``cos`` cannot change the file,
* floats are written with ``repr`` (shortest string that round-trips, i.e.
  full repr precision of the stored value),
* the "random" jitter comes from a fixed 64-bit LCG implemented here, not from
  a library generator whose stream could change between versions.

Only the standard library and numpy are needed (numpy is used for the checks).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections import Counter

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DECIMALS = 12

# --------------------------------------------------------------------------
# small helpers
# --------------------------------------------------------------------------


class Lcg:
    """Tiny deterministic PRNG (Knuth's MMIX 64-bit LCG); output in [-1, 1)."""

    def __init__(self, seed: int) -> None:
        self.state = (seed * 2862933555777941757 + 3037000493) % (1 << 64)

    def uniform(self) -> float:
        self.state = (self.state * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        return (self.state >> 11) / float(1 << 53) * 2.0 - 1.0


def jitter(verts, amount, seed):
    """Add a deterministic pseudo-random offset in [-amount, amount)^3 to each vertex."""
    rng = Lcg(seed)
    return [tuple(c + rng.uniform() * amount for c in v) for v in verts]


def rot_z(p, angle_deg):
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1], p[2])


def polygon_xy(n, radius, z, phase_deg=0.0, cx=0.0, cy=0.0, radii=None):
    """n points counter-clockwise (seen from +z) on a circle (or star of radii)."""
    pts = []
    for k in range(n):
        a = math.radians(phase_deg) + 2.0 * math.pi * k / n
        r = radius if radii is None else radii[k]
        pts.append((cx + r * math.cos(a), cy + r * math.sin(a), z))
    return pts


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def convex_faces(verts, normals, tol=1e-9):
    """Faces of a convex polyhedron: for each outward normal n, the vertices
    maximising <v, n>, ordered counter-clockwise seen from outside (from +n).
    Each face starts at its smallest vertex index."""
    faces = []
    for n in normals:
        d = [_dot(v, n) for v in verts]
        m = max(d)
        idx = [i for i, di in enumerate(d) if di > m - tol]
        c = tuple(sum(verts[i][k] for i in idx) / len(idx) for k in range(3))
        # orthonormal frame (e1, e2) with e1 x e2 parallel to n
        e1 = _sub(verts[idx[0]], c)
        e2 = _cross(n, e1)
        idx.sort(key=lambda i: math.atan2(_dot(_sub(verts[i], c), e2), _dot(_sub(verts[i], c), e1)))
        s = idx.index(min(idx))
        faces.append(idx[s:] + idx[:s])
    return faces


# --------------------------------------------------------------------------
# the meshes; each builder returns (vertices, faces) with 0-based faces
# --------------------------------------------------------------------------


def cube():
    verts = [(x, y, z) for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)]
    normals = [(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)]
    return verts, convex_faces(verts, normals)


def tetrahedron():
    verts = [(1.0, 1.0, 1.0), (1.0, -1.0, -1.0), (-1.0, 1.0, -1.0), (-1.0, -1.0, 1.0)]
    normals = [tuple(-c for c in v) for v in verts]  # face opposite each vertex
    return verts, convex_faces(verts, normals)


def octahedron():
    verts = [(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0),
             (0.0, -1.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]
    normals = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    return verts, convex_faces(verts, normals)


PHI = (1.0 + math.sqrt(5.0)) / 2.0


def _icosa_verts():
    v = []
    for a in (-1.0, 1.0):
        for b in (-PHI, PHI):
            v.append((0.0, a, b))
            v.append((a, b, 0.0))
            v.append((b, 0.0, a))
    return v


def _dodeca_verts():
    v = [(x, y, z) for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)]
    ip = 1.0 / PHI
    for a in (-ip, ip):
        for b in (-PHI, PHI):  # (0, b, a) cyclic: face centres of _icosa_verts()
            v.append((0.0, b, a))
            v.append((b, a, 0.0))
            v.append((a, 0.0, b))
    return v


def icosahedron():
    verts = _icosa_verts()
    return verts, convex_faces(verts, _dodeca_verts())  # faces <-> dual vertices


def dodecahedron():
    verts = _dodeca_verts()
    return verts, convex_faces(verts, _icosa_verts())


def prism(n, radius, height, phase_deg=0.0):
    bot = polygon_xy(n, radius, 0.0, phase_deg)
    top = polygon_xy(n, radius, height, phase_deg)
    verts = bot + top
    faces = [list(range(n - 1, -1, -1))]  # bottom, seen from below: clockwise from above
    for i in range(n):
        j = (i + 1) % n
        faces.append([i, j, n + j, n + i])
    faces.append(list(range(n, 2 * n)))  # top
    return verts, faces


def triangular_prism():
    return prism(3, 1.0, 1.5, 90.0)


def hexagonal_prism():
    return prism(6, 1.0, 1.25)


def truncate_vertex(verts, faces, v, frac):
    """Cut vertex v off the mesh: every edge v-w gets a new point
    v + frac[w] * (w - v); each face around v has v replaced by the two new
    points on its edges at v, and a new face (the cut face) closes the hole.
    Vertex v is left in the list unused (removed later by compact()).
    Returns (verts, faces, cut) with cut[w] = index of the new point on edge v-w."""
    verts = list(verts)
    cut = {}

    def cut_pt(w):
        if w not in cut:
            t = frac[w]
            cut[w] = len(verts)
            verts.append(tuple(verts[v][k] + t * (verts[w][k] - verts[v][k]) for k in range(3)))
        return cut[w]

    new_faces, succ = [], {}
    for f in faces:
        if v not in f:
            new_faces.append(list(f))
            continue
        i = f.index(v)
        prev, nxt = f[i - 1], f[(i + 1) % len(f)]
        cp, cn = cut_pt(prev), cut_pt(nxt)
        new_faces.append(f[:i] + [cp, cn] + f[i + 1:])
        succ[cn] = cp  # the cut face runs opposite to the new edge cp -> cn
    start = min(succ)
    cut_face, w = [start], succ[start]
    while w != start:
        cut_face.append(w)
        w = succ[w]
    new_faces.append(cut_face)
    return verts, new_faces, cut


def compact(verts, faces):
    """Drop unused vertices and renumber the rest, keeping their order."""
    used = sorted({i for f in faces for i in f})
    remap = {old: new for new, old in enumerate(used)}
    return [verts[i] for i in used], [[remap[i] for i in f] for f in faces]


def twisted():
    """Two stacked boxes, the upper one smaller and rotated by 25 degrees about
    the vertical axis, so the mesh has no symmetry.  The upper box sits on a
    low sloped collar (its bottom square is 0.45 above the lower box's top),
    whose four quads run from the lower box's top corners to the upper box's
    bottom corners and are twisted (non-planar) but convex.  (On a flat ledge
    such corner-to-corner quads would be non-convex at a 25 degree twist.)
    Irregular cells:

    * the two lower-box top corners M0, M1 are cut off (by different amounts),
      turning the collar quad between them into the junction hexagon (convex,
      not symmetric) and creating further pentagons and hexagons around;
    * the lower box's bottom corner B3 is cut off: a triangle;
    * one upper side face is split by a diagonal into two triangles, giving a
      vertex of valence 5.
    """
    X, Y, H = 2.2, 1.8, 1.4  # lower box [0, X] x [0, Y] x [0, H]
    B = [(0.0, 0.0, 0.0), (X, 0.0, 0.0), (X, Y, 0.0), (0.0, Y, 0.0)]
    M = [(x, y, H) for (x, y, _) in B]
    # upper box: square of half-side 0.65 about (1.1, 0.9), rotated 25 deg,
    # from z = H + 0.45 to z = H + 0.45 + 1.1
    cx, cy, hs, G, H2 = 1.1, 0.9, 0.65, 0.45, 1.1
    sq = [(-hs, -hs, 0.0), (hs, -hs, 0.0), (hs, hs, 0.0), (-hs, hs, 0.0)]
    U = [(cx + p[0], cy + p[1], H + G) for p in (rot_z(q, 25.0) for q in sq)]
    T = [(x, y, H + G + H2) for (x, y, _) in U]
    verts = B + M + U + T
    b = [0, 1, 2, 3]
    m = [4, 5, 6, 7]
    u = [8, 9, 10, 11]
    t = [12, 13, 14, 15]
    faces = [[b[3], b[2], b[1], b[0]]]                                  # bottom
    faces += [[b[i], b[(i + 1) % 4], m[(i + 1) % 4], m[i]] for i in range(4)]  # lower sides
    faces += [[m[i], m[(i + 1) % 4], u[(i + 1) % 4], u[i]] for i in range(4)]  # collar
    faces += [[u[0], u[1], t[1], t[0]], [u[1], u[2], t[2], t[1]],
              [u[2], u[3], t[3]], [u[2], t[3], t[2]],                  # split side
              [u[3], u[0], t[0], t[3]]]                                # upper sides
    faces.append([t[0], t[1], t[2], t[3]])                             # top
    # cut the top corners M0 and M1 (fractions along each edge leaving the corner)
    verts, faces, cut0 = truncate_vertex(verts, faces, m[0], {m[1]: 0.13, m[3]: 0.16, b[0]: 0.2, u[0]: 0.45})
    # (after the first cut, M1's neighbour along the old edge M0-M1 is cut0[m[1]])
    verts, faces, _ = truncate_vertex(verts, faces, m[1], {cut0[m[1]]: 0.2, m[2]: 0.2, b[1]: 0.25, u[1]: 0.5})
    # cut the bottom corner B3 (valence 3: a triangle)
    verts, faces, _ = truncate_vertex(verts, faces, b[3], {b[2]: 0.22, b[0]: 0.25, m[3]: 0.3})
    return compact(verts, faces)


def torus(nu=12, nv=8, R=2.0, r=0.75):
    verts = []
    for i in range(nu):
        u = 2.0 * math.pi * i / nu
        for j in range(nv):
            v = 2.0 * math.pi * j / nv
            verts.append(((R + r * math.cos(v)) * math.cos(u),
                          (R + r * math.cos(v)) * math.sin(u),
                          r * math.sin(v)))
    faces = []
    for i in range(nu):
        i1 = (i + 1) % nu
        for j in range(nv):
            j1 = (j + 1) % nv
            # (u, v) counter-clockwise; d/du x d/dv points out of the tube
            faces.append([i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1])
    return verts, faces


def double_torus():
    """A slab with two rectangular holes through it (genus 2), all quads.
    Grid of 5 x 3 cells in the plane, cells (1,1) and (3,1) are holes."""
    xs = [0.0, 1.0, 1.8, 2.9, 3.6, 4.7]
    ys = [0.0, 0.9, 1.6, 2.6]
    zs = [0.0, 0.8]
    nx, ny = len(xs) - 1, len(ys) - 1
    holes = {(1, 1), (3, 1)}

    def vid(i, j, k):
        return (k * len(ys) + j) * len(xs) + i

    verts = [(xs[i], ys[j], zs[k]) for k in range(2) for j in range(len(ys)) for i in range(len(xs))]

    def solid(i, j):
        return 0 <= i < nx and 0 <= j < ny and (i, j) not in holes

    faces = []
    for j in range(ny):
        for i in range(nx):
            if not solid(i, j):
                continue
            faces.append([vid(i, j, 0), vid(i, j + 1, 0), vid(i + 1, j + 1, 0), vid(i + 1, j, 0)])  # bottom
            faces.append([vid(i, j, 1), vid(i + 1, j, 1), vid(i + 1, j + 1, 1), vid(i, j + 1, 1)])  # top
            # walls where a solid cell borders a non-solid one (outside or hole)
            if not solid(i, j - 1):  # wall facing -y
                faces.append([vid(i, j, 0), vid(i + 1, j, 0), vid(i + 1, j, 1), vid(i, j, 1)])
            if not solid(i, j + 1):  # wall facing +y
                faces.append([vid(i + 1, j + 1, 0), vid(i, j + 1, 0), vid(i, j + 1, 1), vid(i + 1, j + 1, 1)])
            if not solid(i - 1, j):  # wall facing -x
                faces.append([vid(i, j + 1, 0), vid(i, j, 0), vid(i, j, 1), vid(i, j + 1, 1)])
            if not solid(i + 1, j):  # wall facing +x
                faces.append([vid(i + 1, j, 0), vid(i + 1, j + 1, 0), vid(i + 1, j + 1, 1), vid(i + 1, j, 1)])
    return verts, faces


def high_valence(n=12):
    """A 'pencil': n-gon bottom, n quad sides, n triangles meeting at an apex of
    valence n.  Radii vary a little so the shape is not rotationally symmetric
    (the bottom n-gon stays planar)."""
    radii = [1.0 + 0.04 * math.sin(3.0 * k + 0.5) for k in range(n)]
    bot = polygon_xy(n, 1.0, 0.0, 7.0, radii=radii)
    top = polygon_xy(n, 1.0, 1.6, 7.0, radii=radii)
    apex = (0.09, -0.05, 2.7)
    verts = bot + top + [apex]
    a = 2 * n
    faces = [list(range(n - 1, -1, -1))]
    for i in range(n):
        j = (i + 1) % n
        faces.append([i, j, n + j, n + i])
    for i in range(n):
        j = (i + 1) % n
        faces.append([n + i, n + j, a])
    return verts, faces


def hexagon_six_valent():
    """Hexagonal prism; the side faces next to top corner h0 are triangulated
    (diagonals from h0, plus a raised point q in one triangle) so that h0, a
    corner of the top hexagon, has valence 6 while the other corners do not.
    Vertex positions carry a small seeded non-symmetric jitter."""
    n = 6
    bot = polygon_xy(n, 1.0, 0.0, 10.0)
    top = polygon_xy(n, 0.9, 1.1, 10.0)
    b = list(range(n))
    h = list(range(n, 2 * n))
    # q: centroid of triangle (b0, b1, h0) pushed outward
    tri = [bot[0], bot[1], top[0]]
    g = tuple(sum(p[k] for p in tri) / 3.0 for k in range(3))
    rad = math.hypot(g[0], g[1])
    qpt = (g[0] * (1.0 + 0.25 / rad), g[1] * (1.0 + 0.25 / rad), g[2])
    verts = bot + top + [qpt]
    q = 2 * n
    faces = [list(reversed(b)), list(h)]
    for i in range(1, n - 1):  # untouched side quads 1..4
        j = i + 1
        faces.append([b[i], b[j], h[j], h[i]])
    # side 0 = (b0, b1, h1, h0): diagonal b1-h0, then (b0, b1, h0) split at q
    faces += [[b[0], b[1], q], [b[1], h[0], q], [h[0], b[0], q], [b[1], h[1], h[0]]]
    # side 5 = (b5, b0, h0, h5): diagonal b5-h0
    faces += [[b[5], b[0], h[0]], [b[5], h[0], h[5]]]
    return jitter(verts, 0.035, seed=6), faces


def hexagon_all_six_valent():
    """A lens/drum: a top hexagon and a bottom hexagon, each joined to a common
    equatorial ring of 18 vertices by triangle fans, such that every corner of
    both hexagons has valence 6 (2 hexagon edges + 4 edges to the ring).  The
    bottom hexagon is rotated against the top one and all positions carry a
    small seeded non-symmetric jitter."""
    n, per = 6, 3
    m = n * per
    top = polygon_xy(n, 0.8, 0.6, 0.0)
    ring = polygon_xy(m, 1.5, 0.0, -30.0)  # o[3i .. 3i+3] centred on h_i's angle
    bot = polygon_xy(n, 0.7, -0.55, 12.0)
    verts = top + ring + bot
    h = list(range(n))
    o = [n + k for k in range(m)]
    g = [n + m + k for k in range(n)]
    faces = [list(h), list(reversed(g))]
    for i in range(n):
        # top cap: fan of h_i over ring vertices o[3i] .. o[3i+3], then the
        # triangle on hexagon edge h_i h_{i+1}; all counter-clockwise from outside
        for k in range(per):
            faces.append([h[i], o[(per * i + k) % m], o[(per * i + k + 1) % m]])
        faces.append([h[i], o[(per * i + per) % m], h[(i + 1) % n]])
        # bottom cap: same combinatorics mirrored (reverse orientation)
        for k in range(per):
            faces.append([g[i], o[(per * i + k + 1) % m], o[(per * i + k) % m]])
        faces.append([g[i], g[(i + 1) % n], o[(per * i + per) % m]])
    return jitter(verts, 0.035, seed=66), faces


# --------------------------------------------------------------------------
# registry: name -> (builder, intended genus, description)
# --------------------------------------------------------------------------

MESHES = [
    ("cube", cube, 0, "Cube, 6 quads. Regular case: all cells 4-sided, all vertices valence 3."),
    ("tetrahedron", tetrahedron, 0, "Regular tetrahedron, 4 triangles, valence 3."),
    ("octahedron", octahedron, 0, "Regular octahedron, 8 triangles, valence 4."),
    ("icosahedron", icosahedron, 0, "Regular icosahedron, 20 triangles, valence 5."),
    ("dodecahedron", dodecahedron, 0, "Regular dodecahedron, 12 pentagons, valence 3."),
    ("triangular_prism", triangular_prism, 0, "Prism: 2 triangles + 3 quads (mixed 3/4-gons)."),
    ("hexagonal_prism", hexagonal_prism, 0, "Prism: 2 hexagons + 6 quads (even 6-sided cells)."),
    ("twisted", twisted, 0,
     "Two stacked boxes, upper one smaller and rotated 25 deg (no symmetry), joined by a twisted "
     "collar; three box corners cut off, a convex non-symmetric junction hexagon in the collar, "
     "a side split into triangles; 3-, 4-, 5-, 6-sided cells, valences 3, 4, 5. "
     "In the spirit of Peters' Section 4 example; `make demo` input."),
    ("torus", torus, 1, "Quad torus 12 x 8, genus 1, all vertices valence 4."),
    ("double_torus", double_torus, 2,
     "Slab with two rectangular holes, all quads, genus 2 (V - E + F = -2); valences 3, 4, 5."),
    ("high_valence", high_valence, 0,
     "'Pencil': 12-gon bottom, 12 quad sides, 12 triangles at an apex of valence 12."),
    ("hexagon_six_valent", hexagon_six_valent, 0,
     "Jittered hexagonal prism with a top-hexagon corner of valence 6 "
     "(even cell and even vertex sharing a point)."),
    ("hexagon_all_six_valent", hexagon_all_six_valent, 0,
     "Jittered lens: two hexagons whose six corners all have valence 6, joined by "
     "triangle fans through an 18-vertex equator."),
]


# --------------------------------------------------------------------------
# validation and statistics
# --------------------------------------------------------------------------


def clean_coord(x: float) -> float:
    x = round(float(x), DECIMALS) + 0.0  # + 0.0 turns -0.0 into 0.0
    return x


def mesh_stats(verts, faces):
    """Validate (raises AssertionError) and return a dict of statistics."""
    V, F = len(verts), len(faces)
    P = np.asarray(verts, dtype=float)
    directed = Counter()
    for f in faces:
        assert len(f) >= 3, f
        assert len(set(f)) == len(f), f"repeated vertex in face {f}"
        for a, b in zip(f, f[1:] + f[:1]):
            directed[(a, b)] += 1
    for (a, b), c in directed.items():
        assert c == 1, f"directed edge {(a, b)} used {c} times"
        assert directed.get((b, a), 0) == 1, f"edge {(a, b)} has no opposite half-edge"
    E = len(directed) // 2
    used = sorted({v for f in faces for v in f})
    assert used == list(range(V)), "unused vertex"
    valence = Counter()
    for a, b in directed:
        valence[a] += 1
    assert min(valence.values()) >= 3, "vertex of valence < 3"
    # vertex manifoldness: the faces around each vertex form one cycle
    nxt = {}
    for f in faces:
        k = len(f)
        for i in range(k):
            nxt[(f[i], f[(i + 1) % k])] = f[(i - 1) % k]  # rotate around f[i]
    for v in range(V):
        start = next(b for (a, b) in directed if a == v)
        w, steps = start, 0
        while True:
            w = nxt[(v, w)]
            steps += 1
            if w == start:
                break
        assert steps == valence[v], f"vertex {v} is not a manifold vertex"
    # non-degenerate faces and outward orientation
    vol = 0.0
    for f in faces:
        Q = P[f]
        normal = np.zeros(3)
        for i in range(len(f)):
            normal += np.cross(Q[i], Q[(i + 1) % len(f)])
        assert np.linalg.norm(normal) > 1e-6, f"degenerate face {f}"
        for i in range(1, len(f) - 1):
            vol += np.dot(Q[0], np.cross(Q[i], Q[i + 1])) / 6.0
    assert vol > 0, "faces are oriented inward"
    chi = V - E + F
    assert chi % 2 == 0
    return {
        "V": V, "E": E, "F": F, "chi": chi, "genus": (2 - chi) // 2,
        "sizes": dict(sorted(Counter(len(f) for f in faces).items())),
        "valences": dict(sorted(Counter(valence.values()).items())),
        "volume": vol,
    }


# --------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------


def fmt_hist(h):
    return ", ".join(f"{k}:{v}" for k, v in h.items())


def obj_text(name, desc, verts, faces, st):
    lines = [
        f"# c1surf sample mesh: {name}.obj",
        f"# {desc}",
        "# Generated by sample_meshes/generate.py -- do not edit by hand; rerun the script.",
        f"# V={st['V']} E={st['E']} F={st['F']} genus={st['genus']}",
        f"# face sizes (sides:count) {fmt_hist(st['sizes'])}",
        f"# vertex valences (valence:count) {fmt_hist(st['valences'])}",
    ]
    for v in verts:
        lines.append("v " + " ".join(repr(c) for c in v))
    for f in faces:
        lines.append("f " + " ".join(str(i + 1) for i in f))
    return "\n".join(lines) + "\n"


def readme_text(rows):
    out = [
        "# Sample meshes",
        "",
        "Generated by `generate.py` (run `python sample_meshes/generate.py`); do not edit",
        "the `.obj` files or this README by hand. The output is deterministic and",
        "byte-identical (checked by `tests/test_sample_meshes.py`).",
        "",
        "All meshes are closed, orientable 2-manifolds: every edge lies in exactly two",
        "faces, once in each direction; faces are counter-clockwise seen from outside",
        "(outward normals); no vertex has valence 2; no face repeats a vertex; every",
        "vertex is used. OBJ files keep polygons as polygons (`f a b c ...`, 1-based).",
        "Coordinates are rounded to 12 decimals and written with Python `repr`.",
        "",
        "| file | V | E | F | face sizes (sides:count) | valences (valence:count) | max valence | genus | purpose |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, desc, st in rows:
        out.append(
            f"| `{name}.obj` | {st['V']} | {st['E']} | {st['F']} | {fmt_hist(st['sizes'])} | "
            f"{fmt_hist(st['valences'])} | {max(st['valences'])} | {st['genus']} | {desc} |"
        )
    return "\n".join(out) + "\n"


def build_all():
    """Return [(name, description, verts, faces, stats)] for all sample meshes."""
    result = []
    for name, builder, genus, desc in MESHES:
        verts, faces = builder()
        verts = [tuple(clean_coord(c) for c in v) for v in verts]
        faces = [[int(i) for i in f] for f in faces]
        st = mesh_stats(verts, faces)
        assert st["genus"] == genus, f"{name}: genus {st['genus']} != {genus}"
        result.append((name, desc, verts, faces, st))
    return result


def write_text(path, text):
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=HERE, help="output directory (default: this script's directory)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for name, desc, verts, faces, st in build_all():
        write_text(os.path.join(args.out, f"{name}.obj"), obj_text(name, desc, verts, faces, st))
        rows.append((name, desc, st))
    write_text(os.path.join(args.out, "README.md"), readme_text(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
