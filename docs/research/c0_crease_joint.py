"""Research prototype (session 5), not part of the package: a C0 crease where each side keeps the
*original* topology (the other side's faces at the crease become ghost copies whose refined points
are variables), and one joint least-norm correction (spread by an edge-difference energy) makes the
two crease curves equal.

Finding (docs/sharp-features.md, "Tried in session 5"): exact and non-degenerate on a folded grid with
split quads on both sides (gap 1.8e-15, G1 inside each side 1e-14 rad, shortest crease leg 0.048,
crease angle 1.14 rad), but the crease curve kinks by 34-39 degrees at every crease vertex whose
two sides have different face counts (a hole with n = valence puts the crease spokes k sectors
apart, so their tangents cannot be opposite), and planar sides do not stay planar (the correction
is split between the sides). Arguments: SPLITS (a Python set of grid cells split into triangles)
and FOLD (the slope of the V fold). Run: .venv/bin/python docs/research/c0_crease_joint.py
"""
import numpy as np, sys
from scipy.sparse import csr_matrix, coo_matrix
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.construction.features import SharpFeatures
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.evaluation.adjacency import patch_adjacency, match_patch_sides
from c1surf.evaluation.bezier import bernstein_basis, raise_degree
import c1surf.evaluation.smoothness as sm

rng = np.random.default_rng(1)
N = 6
SPLITS = set(eval(sys.argv[1])) if len(sys.argv) > 1 else {(2, 3), (3, 2), (3, 3)}
FOLD = float(sys.argv[2]) if len(sys.argv) > 2 else 0.8

def grid_mesh():
    pts, idx = [], {}
    for i in range(N + 1):
        for j in range(N + 1):
            idx[i, j] = len(pts); pts.append([i, j - N // 2, 0.0])
    pts = np.array(pts, float)
    pts[:, :2] += 0.08 * rng.standard_normal((len(pts), 2))
    pts[:, 1][np.abs(np.array([j for i in range(N + 1) for j in range(N + 1)]) - N // 2) == 0] = 0.0 + 0.05 * rng.standard_normal(N + 1)
    pts[:, 2] = FOLD * np.abs(pts[:, 1]) + 0.05 * rng.standard_normal(len(pts))
    faces = []
    for i in range(N):
        for j in range(N):
            q = [idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]]
            faces += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] if (i, j) in SPLITS else [q]
    crease = [idx[i, N // 2] for i in range(N + 1)]
    side = np.array([np.sign(j - N // 2) for i in range(N + 1) for j in range(N + 1)])
    return pts, faces, crease, side

pts, faces, crease, vside = grid_mesh()
cset = set(crease)
face_side = [int(max(vside[f])) if max(vside[f]) > 0 else int(min(vside[f])) for f in faces]
nbr = {}
for f in faces:
    for a, b in zip(f, f[1:] + f[:1]):
        nbr.setdefault(a, set()).add(b); nbr.setdefault(b, set()).add(a)

def c_of(q):
    cn = [u for u in nbr[q] if u in cset]
    return pts[cn].mean(0) if cn else None

def extended(sign):
    """Faces of side `sign` (real) + copies of the other side's faces touching the crease (ghost); ghost defaults."""
    real = [f for f, s in zip(faces, face_side) if s == sign]
    other = [f for f, s in zip(faces, face_side) if s == -sign and any(v in cset for v in f)]
    used = sorted({v for f in real for v in f})
    new = {v: k for k, v in enumerate(used)}
    P = [pts[v] for v in used]
    ghost_of = {}
    for f in other:
        for v in f:
            if v not in cset and v not in ghost_of:
                ghost_of[v] = len(P)
                # sharp default: reflect the own side's first ring through the crease point c(v)
                cn = [u for u in nbr[v] if u in cset] or [u for u in f if u in cset]
                own = [w for u in cn for w in nbr[u] if vside[w] == sign]
                c = pts[cn].mean(0)
                P.append(2 * c - pts[own].mean(0))
    G = [[new[v] if v in cset else ghost_of[v] for v in f] for f in other]
    F = [[new[v] for v in f] for f in real]
    P = np.array(P)
    # the collapsed points: non-crease points -> mean of their crease neighbours (vertices without: unchanged)
    collapsed = P.copy()
    inv = {k: v for v, k in new.items()}
    inv.update({k: v for v, k in ghost_of.items()})
    for k, v in inv.items():
        if v not in cset:
            c = c_of(v)
            if c is not None:
                collapsed[k] = c
    return P, F, G, collapsed, len(used)

def build(P, F, G):
    fs = F + G
    sizes = np.array([len(f) for f in fs]); fv = np.concatenate([np.array(f) for f in fs])
    return Surface(sizes, fv, P, SurfaceOptions(), features=SharpFeatures(hole_faces=np.arange(len(F), len(fs))))

def chain(s, points):
    names = [st.name for st in s.stages]
    i2 = names.index("doo_sabin_2")
    x = points
    for st in s.stages[: i2 + 1]:
        x = st.apply(x)
    K = None
    for st in s.stages[i2 + 1:]:
        M = st.matrix(); K = M if K is None else M @ K
    return csr_matrix(K), x

def side_rows(nq, p, side):
    d, base = (2, 9 * p) if p < nq else (3, 9 * nq + 16 * (p - nq))
    i = np.arange(d + 1)
    a, b = [(i, 0 * i), (d + 0 * i, i), (i, d + 0 * i), (0 * i, i)][side]
    return base + a * (d + 1) + b, d

res = {}
for sign in (1, -1):
    P, F, G, collapsed, n_real = extended(sign)
    s = build(P, F, G)
    K, x2 = chain(s, P)
    _, t2 = chain(s, collapsed)  # the collapsed mesh through the same refinement (the target's refined points)
    c = K @ x2
    nq = len(s.biquadratic)
    adj = patch_adjacency(s.refined, s.frames)
    cnt = np.bincount(adj.edges.ravel())
    crease_rows, degs = [], []
    for p, sd in np.argwhere(cnt[adj.edges] == 1):
        rows, d = side_rows(nq, p, sd)
        poly = c[rows]
        if np.all(np.abs(poly[:, 1]) < 0.4) and np.all(poly[:, 0] > 0.6) and np.all(poly[:, 0] < N - 0.6):
            crease_rows.append(rows); degs.append(d)
    R = np.concatenate(crease_rows)
    T = K[R] @ t2  # the target: the collapsed mesh's curve (crease-only)
    real = s.topology.real_vertex
    # variables: ghost refined points, spread smoothly (edge differences), then solve
    var = np.flatnonzero(~real)
    o, dd = np.asarray(s.refined.origin), np.asarray(s.refined.dest)
    keep = (o < dd) & (~real[o] | ~real[dd])
    o, dd = o[keep], dd[keep]
    col = -np.ones(len(x2), int); col[var] = np.arange(len(var))
    rows_, cols_, vals_ = [], [], []
    for e, (a, b) in enumerate(zip(o, dd)):
        if col[a] >= 0: rows_.append(e); cols_.append(col[a]); vals_.append(1.0)
        if col[b] >= 0: rows_.append(e); cols_.append(col[b]); vals_.append(-1.0)
    D = coo_matrix((vals_, (rows_, cols_)), shape=(len(o), len(var))).toarray()
    M = K[R][:, var].toarray()
    r = T - K[R] @ x2
    Q = D.T @ D + 1e-8 * np.eye(len(var))
    KKT = np.block([[Q, M.T], [M, np.zeros((len(R), len(R)))]])
    sol = np.linalg.lstsq(KKT, np.vstack([np.zeros((len(var), 3)), r]), rcond=None)[0][: len(var)]
    print("side", sign, "crease pieces", len(crease_rows), np.bincount(degs), "rank M", np.linalg.matrix_rank(M), "of rows", len(R),
          "| residual %.1e" % np.abs(M @ sol - r).max(), "| ghost moves max %.3f" % np.abs(sol).max())
    x = x2.copy(); x[var] += sol
    c2 = K @ x
    groups = [c2[:9 * nq].reshape(-1, 3, 3, 3), c2[9 * nq:].reshape(-1, 4, 4, 3)]
    rep = measure_smoothness(groups)
    legs = [np.linalg.norm(np.diff(c2[rows], axis=0), axis=1).min() for rows in crease_rows]
    print("   G1 inside %.1e rad; shortest crease leg %.3f; natural vs target curve max %.3f" % (rep.max_normal_jump, min(legs), np.abs(r).max()))
    res[sign] = dict(groups=groups, rows=crease_rows, c=c2, K=K, x2=x2, var=var, D=D, nq=nq, c0=c, degs=degs)

both = measure_smoothness(res[1]["groups"] + res[-1]["groups"])
print("A+B: shared sides %d, boundary %d, max gap %.1e, jump incl. crease %.2f rad" % (both.shared_edges, both.boundary_edges, both.max_gap, both.max_normal_jump))
# crease gap by matching pieces by their end points
ends = lambda S: {tuple(np.round(S["c"][r][[0, -1]].ravel(), 9)) for r in S["rows"]}
print("pieces with identical end points:", len(ends(res[1]) & ends(res[-1])), "of", len(res[1]["rows"]))

print("=== joint: both sides' ghosts so that the two crease curves agree (pieces paired by order along the crease)")
def order(S):
    mids = np.array([S["c0"][r].mean(0)[0] for r in S["rows"]])
    return np.argsort(mids)
A, B = res[1], res[-1]
oa, ob = order(A), order(B)
rowsA, rowsB = [], []
for i, j in zip(oa, ob):
    ra, rb = A["rows"][i], B["rows"][j]
    assert len(ra) == len(rb), (len(ra), len(rb))
    if np.linalg.norm(A["c0"][ra][0] - B["c0"][rb][-1]) < np.linalg.norm(A["c0"][ra][0] - B["c0"][rb][0]):
        rb = rb[::-1]
    rowsA.append(ra); rowsB.append(rb)
RA, RB = np.concatenate(rowsA), np.concatenate(rowsB)
MA = A["K"][RA][:, A["var"]].toarray(); MB = B["K"][RB][:, B["var"]].toarray()
M = np.hstack([MA, -MB])
r = B["K"][RB] @ B["x2"] - A["K"][RA] @ A["x2"]
nA, nB = len(A["var"]), len(B["var"])
Q = np.zeros((nA + nB, nA + nB)); Q[:nA, :nA] = A["D"].T @ A["D"]; Q[nA:, nA:] = B["D"].T @ B["D"]; Q += 1e-8 * np.eye(nA + nB)
KKT = np.block([[Q, M.T], [M, np.zeros((len(RA), len(RA)))]])
sol = np.linalg.lstsq(KKT, np.vstack([np.zeros((nA + nB, 3)), r]), rcond=None)[0][: nA + nB]
print("rank M", np.linalg.matrix_rank(M), "rows", len(RA), "residual %.1e" % np.abs(M @ sol - r).max(), "moves max %.3f" % np.abs(sol).max())
out = {}
for S, dx, rows in ((A, sol[:nA], rowsA), (B, sol[nA:], rowsB)):
    x = S["x2"].copy(); x[S["var"]] += dx
    c2 = S["K"] @ x; nq = S["nq"]
    groups = [c2[:9 * nq].reshape(-1, 3, 3, 3), c2[9 * nq:].reshape(-1, 4, 4, 3)]
    rep = measure_smoothness(groups)
    legs = min(np.linalg.norm(np.diff(c2[rr], axis=0), axis=1).min() for rr in rows)
    print("  G1 inside %.1e rad, shortest crease leg %.3f, coefficients moved max %.3f" % (rep.max_normal_jump, legs, np.abs(c2 - S["c0"]).max()))
    S["final"] = groups
both = measure_smoothness(A["final"] + B["final"])
print("A+B: shared sides %d, boundary %d, max gap %.1e, jump incl. crease %.2f rad" % (both.shared_edges, both.boundary_edges, both.max_gap, both.max_normal_jump))
print("=== tangent turn between consecutive crease pieces (A, final), degrees")
x = A["x2"].copy(); x[A["var"]] += sol[:nA]
cA = A["K"] @ x
seq = [cA[r] for r in rowsA]
# orient consecutive pieces into a chain
chain_ = [seq[0] if np.linalg.norm(seq[0][-1] - seq[1][0]) < 1e-9 or np.linalg.norm(seq[0][-1] - seq[1][-1]) < 1e-9 else seq[0][::-1]]
for p in seq[1:]:
    chain_.append(p if np.linalg.norm(p[0] - chain_[-1][-1]) < 1e-9 else p[::-1])
turns = []
for a, b in zip(chain_, chain_[1:]):
    ta, tb = a[-1] - a[-2], b[1] - b[0]
    cosang = ta @ tb / (np.linalg.norm(ta) * np.linalg.norm(tb))
    turns.append(np.degrees(np.arccos(np.clip(cosang, -1, 1))))
print(np.round(turns, 1), "joined:", all(np.linalg.norm(a[-1] - b[0]) < 1e-9 for a, b in zip(chain_, chain_[1:])))
print("natural (sharp, unmatched) A turns for comparison:")
seq = [A["c0"][r] for r in rowsA]
chain_ = [seq[0] if np.linalg.norm(seq[0][-1] - seq[1][0]) < 1e-9 or np.linalg.norm(seq[0][-1] - seq[1][-1]) < 1e-9 else seq[0][::-1]]
for p in seq[1:]:
    chain_.append(p if np.linalg.norm(p[0] - chain_[-1][-1]) < 1e-9 else p[::-1])
print(np.round([np.degrees(np.arccos(np.clip((a[-1] - a[-2]) @ (b[1] - b[0]) / np.linalg.norm(a[-1] - a[-2]) / np.linalg.norm(b[1] - b[0]), -1, 1))) for a, b in zip(chain_, chain_[1:])], 1))
