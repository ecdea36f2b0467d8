"""Steps A1 (perturbation), A2 and A3 on the twice-refined mesh, as sparse stencils.

Names follow the paper and NOTES-ON-THE-SEED.md: an n-sided cell (a *hole*)
has corners C_1..C_n; B_{i,1} and B_{i,2} are the edge neighbours of C_i on the
C_{i-1} and C_{i+1} side, A_i is diagonal to C_i.

Every patch belongs to one vertex of the refined mesh and is described by that
vertex's four outgoing half-edges ``e0..e3`` in counter-clockwise order: its
corner [0,0] is the centroid of face(e2), [d,0] of face(e3), [d,d] of face(e0)
and [0,d] of face(e1). Its side u=1 crosses edge e0, v=1 crosses e1, u=0
crosses e2 and v=0 crosses e3. A biquadratic patch sits at every vertex whose
four faces are quads (A2); bicubic patch p_i sits at corner C_i of a hole with
``e0`` the hole's half-edge C_i -> C_{i+1} (A3).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix, identity
from scipy.sparse.csgraph import connected_components

from ...mesh.errors import TopologyError
from ...parallel import for_each_range
from ...mesh.halfedges import HalfEdgeMesh, first_outgoing
from .triangles import triangle_hole_coefficients


@dataclass(frozen=True)
class HoleGroup:
    """All n-sided holes of the refined mesh, for one n.

    Attributes
    ----------
    n : int
    cells : (k,) int, refined face index of each hole
    halfedges : (k, n) int, half-edge C_i -> C_{i+1} of each hole
    A, B1, B2, C : (k, n) int, refined vertex indices of A_i, B_{i,1}, B_{i,2}, C_i
    """

    n: int
    cells: np.ndarray
    halfedges: np.ndarray
    A: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    C: np.ndarray


def hole_neighbourhoods(mesh: HalfEdgeMesh, wanted_vertex=None) -> list[HoleGroup]:
    """Find the A, B, C points around every non-quadrilateral cell, grouped by n.

    Parameters
    ----------
    mesh : HalfEdgeMesh, the twice-refined mesh (every vertex used by a patch 4-valent)
    wanted_vertex : (V,) bool or None; if given, only holes with a wanted corner
        (open meshes: holes that reach into the real surface)
    """
    groups = []
    for n, cells, h in mesh.faces_by_size():
        if n == 4:
            continue
        if wanted_vertex is not None:
            keep = wanted_vertex[mesh.origin[h]].any(axis=1)
            cells, h = cells[keep], h[keep]
            if cells.size == 0:
                continue
        t = mesh.twin[h]  # C_{i+1} -> C_i in the quad beside edge i
        to_b2 = mesh.next[t]  # C_i -> B_{i,2}
        back = mesh.twin[to_b2]  # B_{i,2} -> C_i in the corner quad
        corner_quads = mesh.face[back]
        side_quads = mesh.face[t]
        if np.any(mesh.face_sizes[corner_quads] != 4) or np.any(mesh.face_sizes[side_quads] != 4):
            raise TopologyError("internal: a hole of the refined mesh is not surrounded by quads")
        groups.append(
            HoleGroup(
                n=n,
                cells=cells,
                halfedges=h,
                A=mesh.origin[mesh.prev[back]],
                B1=mesh.origin[mesh.next[mesh.next[back]]],
                B2=mesh.dest[to_b2],
                C=mesh.origin[h],
            )
        )
    return groups


def vertex_frames(mesh: HalfEdgeMesh, first: np.ndarray) -> np.ndarray:
    """Four outgoing half-edges e0..e3 counter-clockwise, starting at ``first``.

    Parameters
    ----------
    first : (k,) int, outgoing half-edges of 4-valent vertices

    Returns
    -------
    (k, 4) int
    """
    e = [first]
    for _ in range(3):
        e.append(mesh.rotate(e[-1]))
    frames = np.stack(e, axis=1)
    if np.any(frames < 0) or np.any(mesh.rotate(frames[:, 3]) != first):
        raise TopologyError("internal: a refined vertex is not 4-valent")
    return frames


def patch_frames(mesh: HalfEdgeMesh, holes: list[HoleGroup], wanted_vertex=None):
    """Frames (e0..e3) of all biquadratic and all bicubic patches.

    Parameters
    ----------
    wanted_vertex : (V,) bool or None, refined vertices that get a biquadratic patch if regular

    Returns
    -------
    quad_frames : (Nq, 4) int, one per regular (wanted) refined vertex, in vertex order
    cubic_frames : (Nc, 4) int, for the holes in ``holes`` order, corner by corner
    """
    first = first_outgoing(mesh)
    irregular = np.zeros(mesh.n_vertices, dtype=bool)
    for g in holes:
        irregular[g.C.ravel()] = True
    wanted = (first >= 0) if wanted_vertex is None else (first >= 0) & wanted_vertex
    regular = np.flatnonzero(wanted & ~irregular)
    # Every corner of a kept hole is irregular, so a regular vertex has four quads
    # around it as long as no vertex is a corner of two holes (R3):
    if irregular.sum() != sum(g.C.size for g in holes):
        raise TopologyError("internal: a refined vertex touches two holes")
    quad_frames = vertex_frames(mesh, first[regular])
    if holes:
        cubic_frames = vertex_frames(mesh, np.concatenate([g.halfedges.ravel() for g in holes]).astype(mesh.twin.dtype))
    else:
        cubic_frames = np.zeros((0, 4), dtype=quad_frames.dtype)
    return quad_frames, cubic_frames


def face_corner_vertices(mesh: HalfEdgeMesh, h: np.ndarray) -> np.ndarray:
    """(..., 4) int: the vertices of the quad containing half-edge(s) ``h``."""
    return np.stack([mesh.origin[h], mesh.dest[h], mesh.dest[mesh.next[h]], mesh.origin[mesh.prev[h]]], axis=-1)


def biquadratic_stencil(mesh: HalfEdgeMesh, frames: np.ndarray) -> csr_matrix:
    """Step A2: Bezier coefficients of the biquadratic patch at each regular vertex.

    Corners are centroids of the four quads, edge coefficients midpoints of the
    vertex and an edge neighbour, the centre the vertex itself.

    Parameters
    ----------
    frames : (Nq, 4) int, from ``patch_frames``

    Returns
    -------
    (Nq * 9, V) csr_matrix; row ``9 p + 3 i + j`` gives coefficient Q[i, j] of patch p.
    """
    n = frames.shape[0]
    centre = mesh.origin[frames[:, 0]]
    # Rows Q00 Q01 Q02 Q10 Q11 Q12 Q20 Q21 Q22 hold 4 2 4 2 1 2 4 2 4 entries: 25 per patch,
    # written straight into CSR arrays (a COO detour costs ~10 s and GBs at 1M patches).
    layout = [("quad", 2), ("pair", 2), ("quad", 1), ("pair", 3), ("centre", 0), ("pair", 1), ("quad", 3), ("pair", 0), ("quad", 0)]
    cols = np.empty((n, 25), dtype=np.int64)
    vals = np.empty(25)
    counts = []
    at = 0
    for kind, k in layout:
        if kind == "quad":
            cols[:, at : at + 4] = face_corner_vertices(mesh, frames[:, k])
            vals[at : at + 4] = 0.25
        elif kind == "pair":
            cols[:, at], cols[:, at + 1] = centre, mesh.dest[frames[:, k]]
            vals[at : at + 2] = 0.5
        else:
            cols[:, at], vals[at] = centre, 1.0
        width = {"quad": 4, "pair": 2, "centre": 1}[kind]
        counts.append(width)
        at += width
    index = np.int32 if max(mesh.n_vertices, 25 * n) < 2**31 else np.int64
    prefix = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(index)
    indptr = np.empty(9 * n + 1, dtype=index)
    indptr[:-1].reshape(n, 9)[:] = (25 * np.arange(n, dtype=index))[:, None] + prefix
    indptr[-1] = 25 * n
    return csr_matrix((np.tile(vals, n), cols.ravel().astype(index), indptr), shape=(9 * n, mesh.n_vertices))


# A2 on the 3 x 3 refined points G around a regular vertex: Q = M G M^T, that is
# corners are quad centroids, edge coefficients midpoints and the centre the vertex.
_AVERAGE = np.array([[0.5, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.5, 0.5]])
BIQUADRATIC_FROM_GRID = np.kron(_AVERAGE, _AVERAGE)  # (9, 9): Q.ravel() = this @ G.ravel()


@dataclass(frozen=True)
class BiquadraticLayout:
    """Step A2 as a gather of 3 x 3 refined points and one small dense product.

    The patch at refined vertex c with frame e0..e3 reads the grid

        G = [[diag(e2), dest(e2), diag(e1)],
             [dest(e3), c,        dest(e1)],
             [diag(e3), dest(e0), diag(e0)]]

    (diag(e): the vertex of face(e) opposite c) and has coefficients
    Q = M G M^T (``BIQUADRATIC_FROM_GRID``): Q00 is the centroid of face(e2),
    Q01 the midpoint of c and dest(e2), Q11 = c, and so on. Nine indices per
    patch replace a 25-entries-per-patch matrix, and nothing but the output
    is allocated at full size.

    Attributes
    ----------
    grid : (9, Nq) int, refined vertex of G.ravel()[k] of every patch (slot-major, so
        each slot gathers into a contiguous block)
    """

    grid: np.ndarray


def biquadratic_layout(mesh: HalfEdgeMesh, frames: np.ndarray) -> BiquadraticLayout:
    """Step A2 for the patches with ``frames`` (Nq, 4) (see ``BiquadraticLayout``)."""
    index_type = np.int32 if mesh.n_vertices < 2**31 else np.int64
    grid = np.empty((9, frames.shape[0]), dtype=index_type)
    origin, nxt = mesh.origin, mesh.next

    def fill(start: int, stop: int) -> None:  # random-access gathers: in threads, by blocks
        f = frames[start:stop]
        after = np.take(nxt, f, mode="clip")
        dest = np.take(origin, after, mode="clip")  # (k, 4)
        diagonal = np.take(origin, np.take(nxt, after, mode="clip"), mode="clip")
        g = grid[:, start:stop]
        g[0], g[1], g[2] = diagonal[:, 2], dest[:, 2], diagonal[:, 1]
        g[3], g[4], g[5] = dest[:, 3], np.take(origin, f[:, 0], mode="clip"), dest[:, 1]
        g[6], g[7], g[8] = diagonal[:, 3], dest[:, 0], diagonal[:, 0]

    for_each_range(frames.shape[0], lambda a, b: [fill(s, min(b, s + (1 << 16))) for s in range(a, b, 1 << 16)])
    return BiquadraticLayout(grid)


def gathered_products(points: np.ndarray, slots: np.ndarray, weights: np.ndarray, out: np.ndarray) -> np.ndarray:
    """out[p] = weights @ points[slots[:, p]] for every patch p: a small stencil applied to gathered rows.

    Blocks of patches that stay in cache, on the thread pool: gather slot by slot
    (each into a contiguous row of the block), one (r x m) @ (m x block d) product,
    one strided copy into the output. mode="clip": no bounds check, no buffering
    (the indices are valid by construction).

    Parameters
    ----------
    points : (V, d) float
    slots : (m, k) int, slots[j, p] is the row of points that is input j of patch p
    weights : (r, m) float
    out : (k, r, d) float, filled and returned
    """
    points = np.ascontiguousarray(points)
    m, k = slots.shape
    d = points.shape[1]
    step = max(1, (1 << 15) // m)

    def fill(first: int, last: int) -> None:
        gathered = np.empty((m, min(step, last - first), d))
        product = np.empty((weights.shape[0], gathered.shape[1] * d))
        for start in range(first, last, step):
            stop = min(last, start + step)
            g = gathered[:, : stop - start]
            for j in range(m):
                np.take(points, slots[j, start:stop], axis=0, out=g[j], mode="clip")
            q = np.matmul(weights, g.reshape(m, -1), out=product[:, : (stop - start) * d])
            out[start:stop] = q.reshape(weights.shape[0], -1, d).transpose(1, 0, 2)

    for_each_range(k, fill, minimum=max(1, (1 << 19) // m), uses_blas=True)
    return out


def biquadratic_patches(layout: BiquadraticLayout, points: np.ndarray) -> np.ndarray:
    """Step A2: (Nq, 3, 3, d) Bezier coefficients from refined ``points`` (V, d)."""
    n, d = layout.grid.shape[1], points.shape[1]
    return gathered_products(points, layout.grid, BIQUADRATIC_FROM_GRID, np.empty((n, 9, d))).reshape(n, 3, 3, d)


def bicubic_hole_coefficients(A, B1, B2, C, alpha: float = 1.0, beta: float = 0.0, tangent_rule: str = "symmetric"):
    """Step A3: the n bicubic patches covering one n-sided hole.

    Implements the paper's formulas with the corrections of
    NOTES-ON-THE-SEED.md (P_12 is the mirror of P_21; P_22 uses E_{i+j-1}).

    Parameters
    ----------
    A, B1, B2, C : (..., n, d) float, the (perturbed) refined points around the hole
    alpha : float, the shape parameter of P_32 (default 1)
    beta : float, S = S_C + beta (S_P - S_C) (section 1.3.3; 0 gives the centroid of the C_i)
    tangent_rule : "symmetric" (A3) or "corners" (A3a: P_32 from the C_i only)

    Returns
    -------
    (..., n, 4, 4, d) float: P[..., i, k, l] is coefficient P_{kl,i} of patch p_i.
    """
    n = C.shape[-2]
    c = np.cos(2 * np.pi / n)
    a = c / (1 - c)

    def shift(x, s):  # x_{i+s}
        return np.roll(x, -s, axis=-2)

    C_next, C_prev = shift(C, 1), shift(C, -1)
    B1_next = shift(B1, 1)  # B_{i+1,1}
    B2_prev = shift(B2, -1)  # B_{i-1,2}
    P = np.zeros(C.shape[:-1] + (4, 4) + C.shape[-1:])
    P[..., 0, 0, :] = (B2 + B1 + C + A) / 4
    P[..., 1, 0, :] = (5 * B2 + B1 + 5 * C + A) / 12
    P[..., 2, 0, :] = (5 * B2 + B1_next + 5 * C + C_next) / 12
    P[..., 3, 0, :] = (B2 + B1_next + C + C_next) / 4
    P[..., 0, 1, :] = (5 * B1 + B2 + 5 * C + A) / 12
    P[..., 0, 2, :] = (5 * B1 + B2_prev + 5 * C + C_prev) / 12
    P[..., 0, 3, :] = (B1 + B2_prev + C + C_prev) / 4
    P[..., 1, 1, :] = (5 * B2 + 5 * B1 + A + 25 * C) / 36 + a / 9 * (C - A)
    P[..., 2, 1, :] = (5 * B2 + 5 * C_next + B1_next + 25 * C) / 36 + a / 18 * (-5 * B2 + B1_next + C_next + 3 * C)
    P[..., 1, 2, :] = (5 * B1 + 5 * C_prev + B2_prev + 25 * C) / 36 + a / 18 * (-5 * B1 + B2_prev + C_prev + 3 * C)
    P31 = (B2 + B1_next + 5 * C_next + 5 * C) / 12 + a / 6 * (C_next + C - B2 - B1_next)
    P[..., 3, 1, :] = P31
    P[..., 1, 3, :] = shift(P31, -1)  # P_{13,i} = P_{31,i-1}

    S_C = C.mean(axis=-2, keepdims=True)
    S = S_C + beta * (P31.mean(axis=-2, keepdims=True) - S_C)
    i = np.arange(n)
    cosines = np.cos(2 * np.pi * ((i[None, :] - i[:, None]) % n) / n)  # [i, m] = cos(2 pi (m - i) / n)
    tangent_source = P31 if tangent_rule == "symmetric" else (C + C_next) / 2
    P32 = S + 4 * alpha / (3 * n) * np.einsum("im,...md->...id", cosines, tangent_source)
    E = (1 - 2 * c / 3) * P32 + (2 * c / 3) * P31
    # P_22,i = sum_m Z[i, m] E_m with m = i + j - 1 (the notes' index correction).
    j = (i[None, :] - i[:, None]) % n + 1
    sign = np.where(j % 2 == 0, 1.0, -1.0)
    Z = -sign if n % 2 else -2.0 / n * (n - j) * sign
    P[..., 3, 3, :] = S
    P[..., 3, 2, :] = P32
    P[..., 2, 3, :] = shift(P32, -1)  # P_{23,i} = P_{32,i-1}
    P[..., 2, 2, :] = np.einsum("im,...md->...id", Z, E)
    return P


@lru_cache(maxsize=64)
def _local_bicubic_weights(n: int, alpha: float, beta: float, tangent_rule: str, triangles: str = "g1"):
    """Weights of ``bicubic_hole_coefficients`` on the 4n local points [A, B1, B2, C].

    ``triangles="parametric"`` takes section 1.3.4's patches for n = 3 (``core.triangles``).

    Returns (patch, coefficient, local point, weight) arrays of the non-zeros.
    """
    eye = np.eye(4 * n)
    if n == 3 and triangles == "parametric":
        W = triangle_hole_coefficients(eye[:n], eye[n : 2 * n], eye[2 * n : 3 * n], eye[3 * n :])
    else:
        W = bicubic_hole_coefficients(eye[:n], eye[n : 2 * n], eye[2 * n : 3 * n], eye[3 * n :], alpha, beta, tangent_rule)
    W = W.reshape(n, 16, 4 * n)
    W[np.abs(W) < 1e-15] = 0.0  # exact cancellations (e.g. a = 0 terms) left as round-off
    i, r, c = np.nonzero(W)
    return i, r, c, W[i, r, c]


@lru_cache(maxsize=64)
def _dense_bicubic_weights(n: int, alpha: float, beta: float, tangent_rule: str, triangles: str = "g1") -> np.ndarray:
    """(16 n, 4 n) float: row 16 i + 4 k + l is coefficient P_{kl} of patch p_i, columns [A, B1, B2, C]."""
    i, r, c, w = _local_bicubic_weights(n, alpha, beta, tangent_rule, triangles)
    weights = np.zeros((16 * n, 4 * n))
    weights[16 * i + r, c] = w
    return weights


@dataclass(frozen=True)
class BicubicLayout:
    """Step A3 as gathers of each hole's 4n points and one dense product per hole size.

    Attributes
    ----------
    groups : tuple of (local, weights): local (k, 4n) int, the refined points [A, B1, B2, C]
        of every n-sided hole; weights (16 n, 4 n) float (``_dense_bicubic_weights``)
    keep : (Nc,) bool or None, the patches kept (open meshes: those at real corners)
    """

    groups: tuple
    keep: np.ndarray | None


def bicubic_layout(holes: list[HoleGroup], alpha: float = 1.0, beta: float = 0.0, tangent_rule: str = "symmetric",
                   triangles: str = "g1", keep=None) -> BicubicLayout:
    """Step A3 for all holes, patches numbered hole by hole (``holes`` order), corner i within a hole."""
    groups = tuple((np.concatenate([g.A, g.B1, g.B2, g.C], axis=1),
                    _dense_bicubic_weights(g.n, float(alpha), float(beta), tangent_rule, triangles)) for g in holes)
    return BicubicLayout(groups, None if keep is None or np.all(keep) else np.asarray(keep, dtype=bool))


def bicubic_patches(layout: BicubicLayout, points: np.ndarray) -> np.ndarray:
    """Step A3: (Nc, 4, 4, d) Bezier coefficients from refined ``points`` (V, d)."""
    d = points.shape[1]
    parts = [gathered_products(points, local.T, weights, np.empty((local.shape[0], weights.shape[0], d))).reshape(-1, 4, 4, d)
             for local, weights in layout.groups]  # per hole size n: 4n points in, 16n coefficients out
    patches = np.concatenate(parts) if parts else np.zeros((0, 4, 4, d))
    return patches if layout.keep is None else patches[layout.keep]


def bicubic_stencil(mesh: HalfEdgeMesh, holes: list[HoleGroup], alpha: float = 1.0, beta: float = 0.0, tangent_rule: str = "symmetric",
                    triangles: str = "g1") -> csr_matrix:
    """Step A3 for all holes: (Nc * 16, V) matrix, row ``16 p + 4 k + l`` = P_{kl} of patch p.

    Patches are numbered hole by hole in ``holes`` order, corner i within a hole.
    """
    rows, cols, vals = [], [], []
    base = 0
    for g in holes:
        i, r, c, w = _local_bicubic_weights(g.n, float(alpha), float(beta), tangent_rule, triangles)
        local = np.concatenate([g.A, g.B1, g.B2, g.C], axis=1)  # (k, 4n)
        patch = base + np.arange(g.cells.size)[:, None] * g.n + i[None, :]
        rows.append((patch * 16 + r[None, :]).ravel())
        cols.append(local[:, c].ravel())
        vals.append(np.broadcast_to(w, (g.cells.size, w.size)).ravel())
        base += g.cells.size * g.n
    if not rows:
        return csr_matrix((0, mesh.n_vertices))
    matrix = csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(base * 16, mesh.n_vertices))
    matrix.sum_duplicates()
    return matrix


def perturbation_matrix(mesh: HalfEdgeMesh, holes: list[HoleGroup]):
    """Step A1's perturbation of the B points of even holes with n > 4.

    Each such hole needs the alternating sum r . B = sum_ij (-1)^(i+j) B_ij to
    vanish. The paper corrects each hole alone; holes can share B points
    (NOTES, item 4), so this takes the least-norm joint correction
    dB = -A^+ (A B), which is the paper's rule for an isolated hole.

    Returns
    -------
    (V, V) csr_matrix ``I - A^T (A A^T)^-1 A``, or None when no hole needs it.
    """
    rows, cols, vals = [], [], []
    count = 0
    for g in holes:
        if g.n % 2 or g.n <= 4:
            continue
        k = g.cells.size
        sign = np.where(np.arange(g.n) % 2 == 0, 1.0, -1.0)
        hole = count + np.arange(k)[:, None]
        rows += [np.broadcast_to(hole, (k, g.n)).ravel()] * 2
        cols += [g.B1.ravel(), g.B2.ravel()]
        vals += [np.broadcast_to(sign, (k, g.n)).ravel(), np.broadcast_to(-sign, (k, g.n)).ravel()]
        count += k
    if count == 0:
        return None
    constraints = coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(count, mesh.n_vertices)
    ).tocsr()
    constraints.sum_duplicates()
    inverse_gram = block_diagonal_inverse((constraints @ constraints.T).tocoo())
    return (identity(mesh.n_vertices, format="csr") - constraints.T @ (inverse_gram @ constraints)).tocsr()


def block_diagonal_inverse(matrix: coo_matrix) -> csr_matrix:
    """Inverse of a sparse symmetric matrix made of small diagonal blocks.

    Even holes couple only where they share B points, so A A^T splits into
    tiny blocks (almost all 1 x 1). Blocks of one size are inverted together.

    Parameters
    ----------
    matrix : (m, m) coo_matrix

    Returns
    -------
    (m, m) csr_matrix
    """
    m = matrix.shape[0]
    _, label = connected_components(matrix, directed=False)
    order = np.argsort(label, kind="stable")
    sizes = np.bincount(label)
    start = np.concatenate([[0], np.cumsum(sizes)])
    position = np.empty(m, dtype=np.int64)
    position[order] = np.arange(m) - start[label[order]]
    rows, cols, vals = [], [], []
    for size in np.unique(sizes):
        components = np.flatnonzero(sizes == size)
        slot = np.full(sizes.size, -1)
        slot[components] = np.arange(components.size)
        blocks = np.zeros((components.size, size, size))
        keep = sizes[label[matrix.row]] == size
        r, c = matrix.row[keep], matrix.col[keep]
        np.add.at(blocks, (slot[label[r]], position[r], position[c]), matrix.data[keep])
        inverse = np.linalg.inv(blocks)
        members = order[start[components][:, None] + np.arange(size)]  # (k, size) global indices
        rows.append(np.repeat(members, size, axis=1).ravel())
        cols.append(np.tile(members, (1, size)).ravel())
        vals.append(inverse.ravel())
    return csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, m))
