"""Research prototype (session 5), not part of the package: a C0 crease by cutting the mesh along it,
closing each side with a *mirror* strip of ghost faces (a copy of the side's own faces at the crease,
so a crease vertex with k faces on a side gets a 2k-sided hole whose crease spokes are opposite),
then a least-norm correction of ghost refined points so that both sides' crease curves agree.

Finding (docs/sharp-features.md, "Tried in session 5"): the curves can be made equal (residual
8e-16), but where the two sides have different k the hole's spoke next to the crease and the
biquadratic piece before it keep a speed ratio fixed by n (a = c/(1-c)), so the common curve is
forced to have zero-length control legs there (degenerate patches, 0.03-0.24 rad "jumps" at those
corners). Run from the repository root: .venv/bin/python docs/research/c0_crease_mirror.py
"""
import numpy as np, sys
from scipy.sparse import csr_matrix
from scipy.spatial import cKDTree
from c1surf.construction.surface import Surface, SurfaceOptions
from c1surf.construction.features import SharpFeatures
from c1surf.evaluation.smoothness import measure_smoothness
from c1surf.evaluation.adjacency import patch_adjacency

rng = np.random.default_rng(1)

def grid_mesh(n=6, split=True):
    pts, idx = [], {}
    for i in range(n + 1):
        for j in range(n + 1):
            idx[i, j] = len(pts)
            pts.append([i, j - n // 2, 0.0])
    pts = np.array(pts)
    pts[:, 2] = 0.15 * rng.standard_normal(len(pts))
    pts[:, :2] += 0.1 * rng.standard_normal((len(pts), 2))
    faces = []
    for i in range(n):
        for j in range(n):
            q = [idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]]
            if split and (i, j) in SPLITS:
                faces += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
            else:
                faces.append(q)
    crease = [idx[i, n // 2] for i in range(n + 1)]
    return pts, faces, crease, idx

SPLITS = {(2, 3), (3, 2), (3, 3)}

def side_mesh(pts, faces, crease, above):
    cset = set(crease)
    side = [f for f in faces if all(pts[v, 1] >= -0.5 if above else pts[v, 1] <= 0.5 for v in f) and
            all((v in cset) or ((pts[v, 1] > 0.5) if above else (pts[v, 1] < -0.5)) for v in f)]
    # vertices of the side, renumbered
    used = sorted({v for f in side for v in f})
    new = {v: k for k, v in enumerate(used)}
    P = [pts[v] for v in used]
    F = [[new[v] for v in f] for f in side]
    # crease neighbours of each vertex
    nbr = {}
    for f in side:
        for a, b in zip(f, f[1:] + f[:1]):
            nbr.setdefault(a, set()).add(b); nbr.setdefault(b, set()).add(a)
    touching = [f for f in side if any(v in cset for v in f)]
    ghost = {}
    G = []
    for f in touching:
        g = []
        for v in f:
            if v in cset:
                g.append(new[v])
            else:
                if v not in ghost:
                    cn = [u for u in nbr[v] if u in cset]
                    if not cn:  # a vertex of a touching face not next to the crease: reflect through the face's crease vertices
                        cn = [u for u in f if u in cset]
                    c = pts[cn].mean(axis=0)
                    ghost[v] = len(P)
                    P.append(2 * c - pts[v])
                g.append(ghost[v])
        G.append(g[::-1])
    return np.array(P), F, G, [new[v] for v in crease if v in new]

def build(P, F, G):
    faces = F + G
    sizes = np.array([len(f) for f in faces])
    fv = np.concatenate([np.array(f) for f in faces])
    feats = SharpFeatures(hole_faces=np.arange(len(F), len(faces)))
    return Surface(sizes, fv, P, SurfaceOptions(), features=feats)

def pipeline_after_refine(s):
    """(K, x2): coefficient rows as a matrix of the level-2 refined points, and those points."""
    names = [st.name for st in s.stages]
    i2 = names.index("doo_sabin_2")
    x = s.points - 0.0
    for st in s.stages[: i2 + 1]:
        x = st.apply(x)
    K = None
    for st in s.stages[i2 + 1:]:
        M = st.matrix()
        K = M if K is None else M @ K
    return csr_matrix(K), x

def boundary_sides(s):
    adj = patch_adjacency(s.refined, s.frames)
    count = np.bincount(adj.edges.ravel())
    lone = np.argwhere(count[adj.edges] == 1)  # (patch, side)
    return lone

def side_rows(s, p, side):
    nq = len(s.biquadratic)
    if p < nq:
        d, base = 2, 9 * p
    else:
        d, base = 3, 9 * nq + 16 * (p - nq)
    i = np.arange(d + 1)
    idx = [(i, 0 * i), (d + 0 * i, i), (i, d + 0 * i), (0 * i, i)][side]
    return base + idx[0] * (d + 1) + idx[1], d

def coeffs(s):
    return np.concatenate([s.biquadratic.reshape(-1, 3), s.bicubic.reshape(-1, 3)])

pts, faces, crease, idx = grid_mesh()
sides = {}
for name, above in (("A", True), ("B", False)):
    P, F, G, cr = side_mesh(pts, faces, crease, above)
    s = build(P, F, G)
    K, x2 = pipeline_after_refine(s)
    c = coeffs(s)
    assert np.allclose(K @ x2, c, atol=1e-12), np.abs(K @ x2 - c).max()
    lone = boundary_sides(s)
    crease_sides = []
    for p, sd in lone:
        rows, d = side_rows(s, p, sd)
        poly = c[rows]
        if np.all(np.abs(poly[:, 1]) < 0.35) and np.all(poly[:, 0] > 0.6) and np.all(poly[:, 0] < 5.4):
            crease_sides.append((p, sd, rows, d))
    sides[name] = dict(s=s, K=K, x2=x2, c=c, cs=crease_sides, real=s.topology.real_vertex)
    print(name, "patches", s.n_patches, "crease sides", len(crease_sides), "degrees", np.bincount([d for *_, d in crease_sides]))

# match sides by midpoints
A, B = sides["A"], sides["B"]
mid = lambda S: np.array([S["c"][rows].mean(0) for _, _, rows, _ in S["cs"]])
oa, ob = np.argsort(mid(A)[:, 0]), np.argsort(mid(B)[:, 0])
A["cs"] = [A["cs"][k] for k in oa]
match = ob
print("pairs (deg A, deg B, midpoint distance):", [(A["cs"][k][3], B["cs"][j][3], round(float(np.linalg.norm(mid(A)[k] - mid(B)[j])), 3)) for k, j in enumerate(match)])

def raise_to(poly, d):
    while len(poly) - 1 < d:
        n = len(poly) - 1
        new = [poly[0]] + [(k / (n + 1)) * poly[k - 1] + (1 - k / (n + 1)) * poly[k] for k in range(1, n + 1)] + [poly[-1]]
        poly = np.array(new)
    return poly


def reduce_to_quadratic(C):
    return np.array([C[0], (3 * (C[1] + C[2]) - (C[0] + C[3])) / 4, C[3]])

def raise_q(Q):
    return np.array([Q[0], (Q[0] + 2 * Q[1]) / 3, (2 * Q[1] + Q[2]) / 3, Q[2]])

RA, TA, RB, TB = [], [], [], []
mixed = 0
for (pa_, sa, ra, da), j in zip(A["cs"], match):
    pb_, sb, rb, db = B["cs"][j]
    PA = A["c"][ra]
    flip = np.linalg.norm(PA[0] - B["c"][rb][-1]) < np.linalg.norm(PA[0] - B["c"][rb][0])
    rb = rb[::-1] if flip else rb
    PB = B["c"][rb]
    if da == db:
        T = (PA + PB) / 2
        TA.append(T); TB.append(T)
    else:
        mixed += 1
        QA = PA if da == 2 else reduce_to_quadratic(PA)
        QB = PB if db == 2 else reduce_to_quadratic(PB)
        Q = (QA + QB) / 2
        TA.append(Q if da == 2 else raise_q(Q)); TB.append(Q if db == 2 else raise_q(Q))
    RA.append(ra); RB.append(rb)
print("mixed-degree pieces:", mixed)

def solve(S, rows_list, T_list):
    K, x2 = S["K"], S["x2"]
    ghost = np.flatnonzero(~S["real"])
    R = np.concatenate(rows_list)
    Tm = np.concatenate(T_list)
    Kg = K[R][:, ghost].toarray()
    r = Tm - K[R] @ x2
    dx, res, rank, sv = np.linalg.lstsq(Kg, r, rcond=None)
    print("  rows", len(R), "ghost vars", len(ghost), "rank", rank, "residual", np.abs(Kg @ dx - r).max(), "|dx| max", np.abs(dx).max(), "sv min", sv[sv > 1e-12].min())
    x = x2.copy(); x[ghost] += dx
    return x

for name, S, R, T in (("A", A, RA, TA), ("B", B, RB, TB)):
    print(name)
    x = solve(S, R, T)
    c = S["K"] @ x
    S["new"] = c
    s = S["s"]
    nq = len(s.biquadratic)
    bq, bc = c[:9 * nq].reshape(-1, 3, 3, 3), c[9 * nq:].reshape(-1, 4, 4, 3)
    S["groups"] = [bq, bc]
    rep = measure_smoothness([bq, bc])
    rep0 = measure_smoothness([s.biquadratic, s.bicubic])
    print("  G1 within side: before %.1e after %.1e rad; boundary sides %d; moved real coefficients max %.3f" % (
        rep0.max_normal_jump, rep.max_normal_jump, rep.boundary_edges, np.abs(c - S["c"]).max()))

# gap across the crease: sample matched sides
from c1surf.evaluation.bezier import bernstein_basis
t = np.linspace(0, 1, 21)
gap = 0
for ra, rb in zip(RA, RB):
    ca, cb = A["new"][ra], B["new"][rb]
    ea = bernstein_basis(len(ca) - 1, t) @ ca
    eb = bernstein_basis(len(cb) - 1, t) @ cb
    gap = max(gap, np.abs(ea - eb).max())
print("crease gap (sampled):", gap)
both = measure_smoothness(A["groups"] + B["groups"])
print("A+B together: shared sides", both.shared_edges, "boundary", both.boundary_edges, "max gap", both.max_gap, "max jump (crease included) %.3f" % both.max_normal_jump)

print("=== joint solve")
def raise_rows(R, d):
    """(4, n) matrix mapping a degree-d polygon (d+1 points) to its cubic form."""
    if d == 3:
        return np.eye(4)
    return np.array([[1, 0, 0], [1 / 3, 2 / 3, 0], [0, 2 / 3, 1 / 3], [0, 0, 1]])

blocksA, blocksB = [], []
gA, gB = np.flatnonzero(~A["real"]), np.flatnonzero(~B["real"])
KA, KB = A["K"].tocsr(), B["K"].tocsr()
EA, EB, rhs = [], [], []
for (pa_, sa, ra, da), j in zip(A["cs"], match):
    pb_, sb, rb, db = B["cs"][j]
    PA = A["c"][ra]
    flip = np.linalg.norm(PA[0] - B["c"][rb][-1]) < np.linalg.norm(PA[0] - B["c"][rb][0])
    rb = rb[::-1] if flip else rb
    MA, MB = raise_rows(None, da), raise_rows(None, db)
    EA.append(MA @ KA[ra][:, gA].toarray()); EB.append(MB @ KB[rb][:, gB].toarray())
    rhs.append(MB @ (KB[rb] @ B["x2"]) - MA @ (KA[ra] @ A["x2"]))
M = np.hstack([np.vstack(EA), -np.vstack(EB)])
r = np.vstack(rhs)
sol, res, rank, sv = np.linalg.lstsq(M, r, rcond=None)
print("rows", M.shape[0], "vars", M.shape[1], "rank", rank, "residual", np.abs(M @ sol - r).max(), "|dx| max", np.abs(sol).max())
dxA, dxB = sol[: len(gA)], sol[len(gA):]
out = {}
for name, S, g, dx in (("A", A, gA, dxA), ("B", B, gB, dxB)):
    x = S["x2"].copy(); x[g] += dx
    c = S["K"] @ x
    s = S["s"]; nq = len(s.biquadratic)
    groups = [c[:9 * nq].reshape(-1, 3, 3, 3), c[9 * nq:].reshape(-1, 4, 4, 3)]
    out[name] = groups
    rep = measure_smoothness(groups)
    print(name, "G1 within side after joint correction: %.1e rad, moved coefficients max %.3f, boundary sides %d" % (rep.max_normal_jump, np.abs(c - S["c"]).max(), rep.boundary_edges))
both = measure_smoothness(out["A"] + out["B"])
print("A+B: shared sides", both.shared_edges, "boundary", both.boundary_edges, "max gap %.1e" % both.max_gap)
import c1surf.evaluation.smoothness as sm
for name in "AB":
    groups = out[name]
    rep = measure_smoothness(groups)
    pa, pb = rep.worst_pair
    allp = np.concatenate([sm.raise_degree(g, 3, 3) for g in groups])
    print(name, "worst pair", pa, pb, "centres", allp[pa].mean((0, 1)).round(2), allp[pb].mean((0, 1)).round(2))
    # distribution of jumps per side pair
print("dx norms A top:", np.sort(np.linalg.norm(dxA, axis=1))[-8:].round(3))
print("=== random refined points")
for name, S in (("A", A), ("B", B)):
    for scale in (1e-3, 0.1):
        x = S["x2"] + scale * np.random.default_rng(3).standard_normal(S["x2"].shape)
        c = S["K"] @ x
        nq = len(S["s"].biquadratic)
        rep = measure_smoothness([c[:9 * nq].reshape(-1, 3, 3, 3), c[9 * nq:].reshape(-1, 4, 4, 3)])
        print(name, scale, "%.1e" % rep.max_normal_jump)
print("=== smooth spread: minimize sum over refined edges |dx_u - dx_v|^2 on a band, subject to equal crease curves")
from scipy.sparse import coo_matrix
def band_and_laplacian(S, width):
    s = S["s"]; R = s.refined
    x = S["x2"]
    band = np.flatnonzero(np.abs(x[:, 1] + 0) < width)  # prototype: near the crease line y = 0 (centred coords!)
    return band, R

# the stages run on the input points as given here (no centring in my pipeline_after_refine), so y is y.
def laplacian_rows(R, band, n):
    o, d = np.asarray(R.origin), np.asarray(R.dest)
    keep = o < d
    o, d = o[keep], d[keep]
    inb = np.zeros(n, bool); inb[band] = True
    sel = inb[o] | inb[d]
    o, d = o[sel], d[sel]
    col = {v: k for k, v in enumerate(band)}
    rows, cols, vals = [], [], []
    for e, (a, b) in enumerate(zip(o, d)):
        if a in col: rows.append(e); cols.append(col[a]); vals.append(1.0)
        if b in col: rows.append(e); cols.append(col[b]); vals.append(-1.0)
    return coo_matrix((vals, (rows, cols)), shape=(len(o), len(band))).toarray()

for width in (0.6, 1.1, 1.6):
    parts = {}
    for name, S in (("A", A), ("B", B)):
        band, R = band_and_laplacian(S, width)
        D = laplacian_rows(R, band, len(S["x2"]))
        parts[name] = (band, D)
    bA, DA = parts["A"]; bB, DB = parts["B"]
    EA, EB, rhs = [], [], []
    for (pa_, sa, ra, da), j in zip(A["cs"], match):
        pb_, sb, rb, db = B["cs"][j]
        PA = A["c"][ra]
        flip = np.linalg.norm(PA[0] - B["c"][rb][-1]) < np.linalg.norm(PA[0] - B["c"][rb][0])
        rb = rb[::-1] if flip else rb
        MA, MB = raise_rows(None, da), raise_rows(None, db)
        EA.append(MA @ KA[ra][:, bA].toarray()); EB.append(MB @ KB[rb][:, bB].toarray())
        rhs.append(MB @ (KB[rb] @ B["x2"]) - MA @ (KA[ra] @ A["x2"]))
    M = np.hstack([np.vstack(EA), -np.vstack(EB)])
    r = np.vstack(rhs)
    nA, nB = len(bA), len(bB)
    Q = np.zeros((nA + nB, nA + nB))
    Q[:nA, :nA] = DA.T @ DA; Q[nA:, nA:] = DB.T @ DB
    Q += 1e-6 * np.eye(nA + nB)
    KKT = np.block([[Q, M.T], [M, np.zeros((M.shape[0], M.shape[0]))]])
    sol2 = np.linalg.lstsq(KKT, np.vstack([np.zeros((nA + nB, 3)), r]), rcond=None)[0][: nA + nB]
    print("width", width, "vars", nA + nB, "residual %.1e" % np.abs(M @ sol2 - r).max(), "|dx| max %.3f" % np.abs(sol2).max())
    for name, S, b, dx in (("A", A, bA, sol2[:nA]), ("B", B, bB, sol2[nA:])):
        x = S["x2"].copy(); x[b] += dx
        c = S["K"] @ x
        nq = len(S["s"].biquadratic)
        groups = [c[:9 * nq].reshape(-1, 3, 3, 3), c[9 * nq:].reshape(-1, 4, 4, 3)]
        out[name] = groups
        rep = measure_smoothness(groups)
        print("   ", name, "G1 %.1e rad, moved coefficients max %.3f" % (rep.max_normal_jump, np.abs(c - S["c"]).max()))
    both = measure_smoothness(out["A"] + out["B"])
    print("    A+B: shared", both.shared_edges, "boundary", both.boundary_edges, "max gap %.1e" % both.max_gap, "max jump (crease) %.2f" % both.max_normal_jump)
for name in "AB":
    groups = out[name]
    allp = np.concatenate([sm.raise_degree(g, 3, 3) for g in groups])
    from c1surf.evaluation.adjacency import match_patch_sides
    diag = np.linalg.norm(np.ptp(allp.reshape(-1, 3), 0))
    sides_ = match_patch_sides(groups, 1e-9 * diag)
    t = np.linspace(0, 1, 11)
    xa, na = sm.side_frames(allp, sides_.first, t)
    xb, nb = sm.side_frames(allp, sides_.second, t, sides_.reversed)
    ang = np.arctan2(np.linalg.norm(np.cross(na, nb), axis=1), np.einsum('ij,ij->i', na, nb)).reshape(-1, 11)
    bad = np.flatnonzero(ang.max(1) > 1e-8)
    print(name, "bad sides", len(bad), "of", len(ang))
    for k in bad[:6]:
        print("   ", sides_.first[k] // 4, sides_.second[k] // 4, "at", xa.reshape(-1, 11, 3)[k, 5].round(2), "jump profile", ang[k].round(3))
print("=== corner derivatives at the bad points (A)")
groups = out["A"]
allp = np.concatenate([sm.raise_degree(g, 3, 3) for g in groups])
for pa, pb in [(94, 298), (119, 299)]:
    for p in (pa, pb):
        P = allp[p]
        # find the corner nearest to the crease (smallest |y|)
        cs = {(0, 0): (P[1, 0] - P[0, 0], P[0, 1] - P[0, 0]), (3, 0): (P[3, 0] - P[2, 0], P[3, 1] - P[3, 0]),
              (3, 3): (P[3, 3] - P[2, 3], P[3, 3] - P[3, 2]), (0, 3): (P[1, 3] - P[0, 3], P[0, 3] - P[0, 2])}
        k = min(cs, key=lambda c: abs(P[c][1]))
        du, dv = cs[k]
        print(p, "corner", k, P[k].round(3), "|du| %.2e |dv| %.2e sin %.2e" % (np.linalg.norm(du), np.linalg.norm(dv), np.linalg.norm(np.cross(du, dv)) / (np.linalg.norm(du) * np.linalg.norm(dv) + 1e-300)))
print("=== A crease polygons after the last correction")
cA = np.concatenate([g.reshape(-1, 3) for g in out["A"]])
for (pa_, sa, ra, da), j in zip(A["cs"], match):
    poly = cA[ra]
    legs = np.linalg.norm(np.diff(poly, axis=0), axis=1)
    print(pa_, da, poly[:, :2].round(3).tolist(), "legs", legs.round(3))
print("=== natural (uncorrected) A and B crease polygons")
for S in (A, B):
    for (pa_, sa, ra, da) in S["cs"]:
        poly = S["c"][ra]
        legs = np.linalg.norm(np.diff(poly, axis=0), axis=1)
        print(pa_, da, poly[:, :2].round(3).tolist(), "legs", legs.round(3))
    print()
