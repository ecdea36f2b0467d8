"""Research prototype (session 6), not part of the package: an exact C0 crease by sheets and mirrored
level-1 points, measured on the all-sharp cube and OpenSubdiv's catmark_cube_creases2.

Design (docs/sharp-features.md, "Session 6: sheets and mirrored level-1 points"):

1. Cut the mesh along its infinitely sharp edges: every vertex gets one copy per *sector* (the faces
   between two consecutive crease edges around it), so every side of a crease is its own sheet.
2. Close every sheet along each crease edge with ghost quads, which are hole faces (they refine,
   they make no patches): one across each crease edge, and at a crease vertex whose sector has a
   single face one more, diagonal, so that every crease vertex copy has exactly four faces.
3. After the first Doo-Sabin step, set every ghost point at a crease vertex to the *mirror* of the
   real point across the crease: 2 chi - p, chi = (1 - a/2) v + (a/2) w, the point where the crease
   polygon's Chaikin refinement crosses that edge (a the blend ratio). The diagonal ghost of a
   one-face sector is p itself at a smooth crease vertex (the cell's centre lies on the crease
   polygon) and 4 v - p - m_e - m_e' at a corner (the cell's centre is the corner v).
4. The rest is the paper's construction. A Doo-Sabin step maps a cell of mirrored pairs to a cell
   of mirrored pairs (about Chaikin's points of the crossing points), so every patch side on the
   crease has control points made of crossing points only: both sheets build the same curve.

Run from the repository root: .venv/bin/python docs/research/c0_crease_sheets.py
"""
import sys
from collections import defaultdict

import numpy as np

from c1surf.construction.features import SharpFeatures
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.evaluation.adjacency import adjacency_from_geometry
from c1surf.evaluation.bezier import raise_degree
from c1surf.evaluation.smoothness import side_frames
from c1surf.io.meshes.obj import read_obj
from c1surf.mesh.halfedges import build_halfedges

BLEND = 0.5


def sectors(mesh, crease):
    """(H,) int: sector label of every corner (half-edge origin); (H,) bool crease edges; crease edges per vertex."""
    label = np.full(mesh.n_halfedges, -1)
    is_crease = np.array([crease.get((min(a, b), max(a, b)), False) for a, b in zip(mesh.origin, mesh.dest)])
    count = np.bincount(mesh.origin[is_crease], minlength=mesh.n_vertices)  # closed mesh: every edge leaves both ends
    n = 0
    for v in range(mesh.n_vertices):
        out = np.flatnonzero(mesh.origin == v)
        start = next((h for h in out if is_crease[h]), out[0])
        h = start
        for _ in range(out.size):
            label[h] = n
            h = mesh.twin[mesh.prev[h]]  # the next corner around v, across the edge (v, x) of h's face
            if is_crease[h] and h != start:
                n += 1
        n += 1
    return label, is_crease, count


def cut_and_close(points, sizes, fv, crease, corners=()):
    """The sheets and their ghost quads: (points, sizes, fv, n_real_faces, mirror rules)."""
    mesh = build_halfedges(sizes, fv, len(points))
    label, is_crease, count = sectors(mesh, crease)
    copies = {}  # (vertex, sector) -> new vertex
    P = []

    def copy(h):
        key = (int(mesh.origin[h]), int(label[h]))
        if key not in copies:
            copies[key] = len(P)
            P.append(points[key[0]])
        return copies[key]

    corner_of = np.array([copy(h) for h in range(mesh.n_halfedges)])  # corner -> vertex of the cut mesh
    is_corner = np.array([count[mesh.origin[h]] >= 3 or mesh.origin[h] in corners for h in range(mesh.n_halfedges)])
    faces = [list(corner_of[mesh.face_offsets[f]:mesh.face_offsets[f + 1]]) for f in range(mesh.n_faces)]
    ghost_at = {}  # (cut vertex, crease edge id) -> ghost vertex next to it

    def ghost(A, e):
        if (A, e) not in ghost_at:
            ghost_at[(A, e)] = len(P)
            P.append(np.zeros(3))
        return ghost_at[(A, e)]

    def edge_id(h):
        a, b = int(mesh.origin[h]), int(mesh.dest[h])
        return (min(a, b), max(a, b))

    # sector sizes (faces) per cut vertex
    k = defaultdict(int)
    for h in range(mesh.n_halfedges):
        k[corner_of[h]] += 1
    # k = 2: the two ghost quads at a crease vertex share their edge there; k = 1: a diagonal quad between
    merge = {}
    rules = []  # (ghost face, corner vertex, kind, data)
    G = []
    for h in np.flatnonzero(is_crease):  # h: A -> B in real face f, on a crease edge
        A, B = corner_of[h], corner_of[mesh.next[h]]
        e = edge_id(h)
        G.append((B, A, ghost(A, e), ghost(B, e)))
    # at every crease vertex copy: the crease half-edges leaving it (A -> B) and arriving (C -> A)
    leaving, arriving = defaultdict(list), defaultdict(list)
    for h in np.flatnonzero(is_crease):
        leaving[corner_of[h]].append(h)
        arriving[corner_of[mesh.next[h]]].append(h)
    diagonal = []
    for A in leaving:
        (h_out,), (h_in,) = leaving[A], arriving[A]  # one sector: one crease edge on each side
        g_out, g_in = ghost(A, edge_id(h_out)), ghost(A, edge_id(h_in))
        if k[A] == 2:
            merge[g_in] = g_out
        elif k[A] == 1:
            d = len(P)
            P.append(np.zeros(3))
            diagonal.append((A, g_in, d, g_out))
        else:
            raise ValueError(f"sector of {k[A]} faces at a crease vertex: not exact with this design")
    G = [tuple(merge.get(v, v) for v in g) for g in G]
    G += diagonal
    real_faces = len(faces)
    all_faces = faces + [list(g) for g in G]
    # ghost positions (only for a sane pipeline; the ones that matter are set after the first step)
    P = np.array(P, dtype=float)
    centroid = points.mean(axis=0)
    for i in range(len(P)):
        if not np.any(P[i]):
            P[i] = centroid
    crease_vertex = {A: bool(is_corner[h]) for A, hs in leaving.items() for h in hs}
    return P, all_faces, real_faces, crease_vertex, k


def level1_overrides(s, faces, real_faces, crease_vertex, k, P):
    """Rows of the once-refined points to replace: (rows, rule) with the mirror rule of each."""
    top = s.topology
    coarse = top.input
    # corner (face, vertex of the cut mesh) -> coarse half-edge; the repaired mesh keeps faces in order
    src = top.vertex_source
    corner = {}
    for f in range(len(faces)):
        for h in range(coarse.face_offsets[f], coarse.face_offsets[f + 1]):
            corner[(f, int(src[coarse.origin[h]]))] = h
    real_corner = defaultdict(list)  # cut vertex -> real corners (half-edges) around it, rotation order
    for f in range(real_faces):
        for v in faces[f]:
            real_corner[v].append(corner[(f, v)])
    rules = []
    for g in range(real_faces, len(faces)):
        quad = faces[g]
        for j, v in enumerate(quad):
            if v not in crease_vertex:
                continue
            h = corner[(g, v)]
            rules.append((h, g, j, v))
    return corner, real_corner, rules


def build(points, sizes, fv, crease, corners=()):
    P, faces, real_faces, crease_vertex, k = cut_and_close(points, sizes, fv, crease, corners)
    face_sizes = np.array([len(f) for f in faces])
    s = Surface(face_sizes, np.concatenate([np.array(f) for f in faces]), P,
                SurfaceOptions(blend=BLEND), features=SharpFeatures(hole_faces=np.arange(real_faces, len(faces))))
    corner, real_corner, rules = level1_overrides(s, faces, real_faces, crease_vertex, k, P)
    origin = (P.min(0) + P.max(0)) / 2
    x = P - origin
    names = [st.name for st in s.stages]
    for st in s.stages[:-1]:
        x = st.apply(x)
        if st.name == "doo_sabin_1":
            x0 = (P - origin)
            x = mirror_ghosts(x, x0, faces, real_faces, corner, crease_vertex, k)
    patches = s.stages[-1].apply(x, offset=origin)
    nq = s.topology.quad_frames.shape[0]
    bq, bc = patches[: 9 * nq].reshape(-1, 3, 3, 3), patches[9 * nq:].reshape(-1, 4, 4, 3)
    return s, bq, bc, names, faces, real_faces


def mirror_ghosts(x, x0, faces, real_faces, corner, crease_vertex, k):
    """Once-refined points: the ghost corners at crease vertices mirrored across the crease."""
    x = x.copy()
    # a ghost quad across crease edge A -> B of real face f is (B, A, gA, gB): its corners at A and B
    # mirror f's corners at A and B through the crossing points chi
    real_edge = {}
    for f in range(real_faces):
        n = len(faces[f])
        for j in range(n):
            real_edge[(faces[f][j], faces[f][(j + 1) % n])] = f
    for g in range(real_faces, len(faces)):
        quad = faces[g]
        if (quad[1], quad[0]) in real_edge:  # a ghost across a crease edge
            B, A = quad[0], quad[1]
            f = real_edge[(A, B)]
            for v, w in ((A, B), (B, A)):
                chi = (1 - BLEND / 2) * x0[v] + (BLEND / 2) * x0[w]
                x[corner[(g, v)]] = 2 * chi - x[corner[(f, v)]]
    for g in range(real_faces, len(faces)):
        quad = faces[g]
        if (quad[1], quad[0]) in real_edge:
            continue
        A, g_in, d, g_out = quad  # the diagonal quad of a one-face sector
        f = next(f for f in range(real_faces) if A in faces[f])
        p = x[corner[(f, A)]]
        # the two mirrors of p at A are the corners at A of the two crease ghost quads holding g_in and g_out
        mirrors = [x[corner[(gg, A)]] for gg in range(real_faces, len(faces)) if gg != g and A in faces[gg]]
        assert len(mirrors) == 2
        if crease_vertex[A]:  # a corner: the cell's centre is the corner itself
            x[corner[(g, A)]] = 4 * x0[A] - p - mirrors[0] - mirrors[1]
        else:  # a smooth crease vertex: the centre lies on the crease polygon
            x[corner[(g, A)]] = p
    return x


def measure(bq, bc, sheet_of_patch, tol=1e-9):
    """(largest gap on crease sides, largest normal jump on other shared sides, crease sides, smooth sides)."""
    groups = [bq, bc]
    cubic = np.concatenate([raise_degree(bq, 3, 3) if len(bq) else np.zeros((0, 4, 4, 3)), bc])
    adj = adjacency_from_geometry(groups, tol)
    nb = adj.neighbours()
    t = np.linspace(0, 1, 11)
    gap = jump = 0.0
    n_crease = n_smooth = 0
    for p in range(nb.shape[0]):
        for sd in range(4):
            q, sq = nb[p, sd]
            if q < 0 or q < p:
                continue
            rev = np.array([adj.reversed[p, sd] != adj.reversed[q, sq]])
            a, na = side_frames(cubic, np.array([4 * p + sd]), t)
            b, nb_ = side_frames(cubic, np.array([4 * q + sq]), t, reverse=rev)
            g = np.abs(a - b).max()
            if sheet_of_patch[p] != sheet_of_patch[q]:
                gap = max(gap, g)
                n_crease += 1
            else:
                # the angle between the unit normals, from their cross product (arccos loses half the digits)
                ang = np.arctan2(np.linalg.norm(np.cross(na, nb_), axis=1), np.abs(np.einsum("ij,ij->i", na, nb_)))
                jump = max(jump, float(ang.max()))
                n_smooth += 1
    return gap, jump, n_crease, n_smooth


def sheet_labels(s, faces, real_faces):
    """(P,) int: the sheet (component of real faces joined by uncut edges) of every patch."""
    n = real_faces
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    edge_face = {}
    for f in range(n):
        m = len(faces[f])
        for j in range(m):
            e = (min(faces[f][j], faces[f][(j + 1) % m]), max(faces[f][j], faces[f][(j + 1) % m]))
            if e in edge_face:
                parent[find(f)] = find(edge_face[e])
            edge_face[e] = f
    top = s.topology
    centre = top.refined.origin[top.frames[:, 0]]  # level-2 vertex = level-1 half-edge
    h0 = top.level1.origin[centre]  # level-1 vertex = coarse half-edge (its corner)
    face = top.input.face[h0]
    return np.array([find(int(f)) for f in face])


def cube(all_sharp=True):
    m = read_obj("sample_meshes/cube.obj")
    offs = np.r_[0, np.cumsum(m.face_sizes)]
    edges = {}
    for f in range(m.n_faces):
        c = m.face_vertices[offs[f]:offs[f + 1]]
        for a, b in zip(c, np.roll(c, -1)):
            edges[(min(a, b), max(a, b))] = True
    return m.points, m.face_sizes, m.face_vertices, edges


def obj_with_tags(path):
    m = read_obj(path)
    t = m.tags
    edges = {(int(min(a, b)), int(max(a, b))): True for (a, b), s in zip(t.crease_edges, t.crease_sharpness) if s >= 10}
    return m.points, m.face_sizes, m.face_vertices, edges


def report(name, points, sizes, fv, crease):
    s, bq, bc, names, faces, real_faces = build(points, sizes, fv, crease)
    sheet = sheet_labels(s, faces, real_faces)
    gap, jump, nc, ns = measure(bq, bc, sheet)
    diag = float(np.linalg.norm(points.max(0) - points.min(0)))
    allp = np.concatenate([bq.reshape(-1, 3), bc.reshape(-1, 3)])
    print(f"{name}: {len(bq)} biquadratic + {len(bc)} bicubic patches, {nc} crease side pairs (gap {gap / diag:.1e} of the diagonal), "
          f"{ns} smooth pairs (normal jump {jump:.1e} rad)")
    return s, bq, bc, sheet


if __name__ == "__main__":
    s, bq, bc, sheet = report("all-sharp cube", *cube())
    # the cube's faces: every coefficient on its face plane, the corners reached
    pts = np.concatenate([bq.reshape(-1, 3), bc.reshape(-1, 3)])
    off_plane = np.min(np.abs(np.abs(pts) - 1.0), axis=1).max()
    print(f"  every coefficient on a face plane of the cube to {off_plane:.1e}; coefficients within the cube: {np.abs(pts).max() <= 1 + 1e-12}")
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    reach = max(np.min(np.linalg.norm(pts - c, axis=1)) for c in corners)
    print(f"  every corner of the cube is a patch corner to {reach:.1e}")
    report("catmark_cube_creases2 (11 infinitely sharp edges; its one semi-sharp edge taken as smooth)",
           *obj_with_tags("../shared/meshes/opensubdiv/catmark_cube_creases2.obj"))
