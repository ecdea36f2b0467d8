"""Welded tessellation: every patch sampled on an N x N grid, shared points shared.

Patches are dual to the refined mesh (see ``patches``): patch corners are
centroids of refined faces and patch sides cross refined edges. So the welded
vertex numbering is index arithmetic on plain per-patch arrays (corner ids,
side edge ids and directions: ``adjacency.PatchAdjacency``): one vertex per corner, N-2 per
edge (in its own direction), (N-2)^2 per patch. No distance search. The arrays are stored in
patch files, so ``c1surf tessellate`` rebuilds exactly the mesh ``convert`` writes.

The output runs to gigabytes (N = 8 on a million patches: 49M points and
normals, 98M triangles), so speed is set by bytes written: every vertex is
evaluated once, straight into the output arrays, in blocks whose work arrays
stay in cache, on all cores (numpy and BLAS release the GIL); indices are
int32 while they fit.
"""
from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..parallel import run_tasks
from .adjacency import PatchAdjacency, adjacency_from_corner_labels, corner_labels, patch_adjacency, side_offsets
from .bezier import bernstein_basis, evaluate_grid, tensor_basis, unit_normals
from .rational import dehomogenize, evaluate_rational, homogeneous


@dataclass(frozen=True)
class Tessellation:
    """A triangle mesh sampled from the patches.

    points : (V, d) float; normals : (V, 3) float (exact, from patch derivatives)
    triangles : (T, 3) int, counter-clockwise from outside (int32 below 2^31 vertices, else int64)
    triangle_patch : (T,) int, patch index (biquadratic first, then bicubic), made on first use
    grid : (P, N, N) int (the dtype of triangles), vertex index of sample (i, j) = (u_i, v_j) of each patch
    """

    points: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    _triangle_patch: np.ndarray | None  # None: made from grid when asked (0.8 GB at N = 8 on 1M patches, rarely used)
    grid: np.ndarray

    @property
    def triangle_patch(self) -> np.ndarray:
        """(T,) int: patch index of each triangle."""
        if self._triangle_patch is None:
            per_patch = 2 * (self.resolution - 1) ** 2
            object.__setattr__(self, "_triangle_patch", np.repeat(np.arange(self.grid.shape[0]), per_patch))
        return self._triangle_patch

    @property
    def resolution(self) -> int:
        return int(self.grid.shape[1])


def grid_triangles(n: int) -> np.ndarray:
    """Triangles of one patch's n x n sample grid, samples numbered i * n + j (i along u).

    Returns
    -------
    (2 (n-1)^2, 3) int, counter-clockwise seen against the normal x_u x x_v
    """
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    b, c, d = a + n, a + n + 1, a + 1  # (i+1, j), (i+1, j+1), (i, j+1)
    # u x v points outward, so (i,j) -> (i+1,j) -> (i+1,j+1) is counter-clockwise.
    return np.stack([np.stack([a, b, c], 1), np.stack([a, c, d], 1)], axis=1).reshape(-1, 3)


def welded_grid_from_ids(adjacency: PatchAdjacency, n: int) -> np.ndarray:
    """Global vertex index of every grid sample, from plain adjacency arrays.

    Vertices are numbered corners first (by corner id), then the n-2 inner
    samples of every edge (by edge id, in the edge's own direction), then the
    (n-2)^2 inner samples of every patch (patch by patch, u slowest). Sample
    (i, j) of a patch is the point at (u_i, v_j). Ids that no patch uses are
    skipped (the numbering stays in order).

    Parameters
    ----------
    adjacency : PatchAdjacency, corner ids (P, 4), side edge ids (P, 4), reversed flags (P, 4)
    n : int >= 2, samples per side

    Returns
    -------
    (P, n, n) int (int32 below 2^31 vertices, else int64), a compact numbering 0..V-1
    """
    welding = _Welding.of(adjacency, n)
    grid = np.empty((welding.n_patches, n, n), dtype=welding.dtype)
    step = welding.patch_block
    run_tasks([partial(_grid_block, welding, a, min(a + step, welding.n_patches), grid) for a in range(0, welding.n_patches, step)])
    return grid


def tessellate(patch_groups, refined, frames: np.ndarray, resolution: int = 8, weights=None) -> Tessellation:
    """Sample patches on a welded grid.

    Parameters
    ----------
    patch_groups : list of (p_k, d_k+1, d_k+1, dim) float, in the order of ``frames``
    refined : HalfEdgeMesh, the twice-refined mesh the frames refer to
    frames : (sum p_k, 4) int
    resolution : int >= 2, samples per patch side
    weights : None or list of (p_k, d_k+1, d_k+1) float: rational patches (A2a)

    Returns
    -------
    Tessellation (the same as ``tessellate_patches(patch_groups, patch_adjacency(refined, frames), resolution)``;
    at resolution 2 the samples are the corners, so only corners are numbered, half the work, as streamed)
    """
    adjacency = (adjacency_from_corner_labels(corner_labels(refined.face, frames)) if resolution == 2
                 else patch_adjacency(refined, frames))
    return tessellate_patches(patch_groups, adjacency, resolution, weights)


def tessellate_patches(patch_groups, adjacency: PatchAdjacency, resolution: int = 8, weights=None) -> Tessellation:
    """Sample patches on a welded grid given by plain adjacency arrays (``convert`` and ``tessellate``
    both call this with the same arrays, from the construction or a patch file: identical outputs).

    Parameters
    ----------
    patch_groups : list of (p_k, d_k+1, d_k+1, dim) float, patches in adjacency order
    adjacency : PatchAdjacency of the sum p_k patches
    resolution : int >= 2, samples per patch side
    weights : None or list of (p_k, d_k+1, d_k+1) float: rational patches (A2a), points
        divided by w and normals by the quotient rule (``evaluation.rational``)

    Returns
    -------
    Tessellation
    """
    if resolution < 2:
        raise ValueError("resolution must be at least 2")
    if weights is not None:
        return _tessellate_rational(patch_groups, weights, adjacency, int(resolution))
    n = int(resolution)
    groups = [np.ascontiguousarray(g, dtype=np.float64) for g in patch_groups]
    welding = _Welding.of(adjacency, n)
    dim = groups[0].shape[-1]
    points = np.empty((welding.n_vertices, dim))
    normals = np.empty((welding.n_vertices, 3))
    grid = np.empty((welding.n_patches, n, n), dtype=welding.dtype)
    local = grid_triangles(n)
    triangles = np.empty((welding.n_patches * local.shape[0], 3), dtype=welding.dtype)
    # dense ids (always, for adjacency from the construction or a patch file): each vertex evaluated once
    _evaluate_welded(groups, welding, points, normals, grid, local.ravel(), triangles)
    if not welding.dense:  # ids with gaps were closed: every sample of every patch, the last patch winning
        t = np.linspace(0.0, 1.0, n)
        for ids, group, _ in _group_grids(grid, groups):
            b, db = bernstein_basis(group.shape[1] - 1, t), bernstein_basis(group.shape[1] - 1, t, 1)
            points[ids] = evaluate_grid(group, b, b)
            normals[ids] = unit_normals(evaluate_grid(group[..., :3], db, b), evaluate_grid(group[..., :3], b, db))
    return Tessellation(points, defined_normals(points, normals, triangles), triangles, None, grid)


def _group_grids(grid: np.ndarray, groups, weights=None):
    """(rows of ``grid``, group, its weights or None) for every non-empty group, in order."""
    start = 0
    for k, group in enumerate(groups):
        if len(group):
            yield grid[start : start + len(group)], group, None if weights is None else weights[k]
            start += len(group)


def _tessellate_rational(groups, weights, adjacency: PatchAdjacency, n: int) -> Tessellation:
    """Welded tessellation of rational patches (A2a).

    The homogeneous patches (w x, w) are tessellated as polynomial ones (the
    welding is the same), then points are divided by w and normals come from
    the quotient rule (``rational.evaluate_rational``).
    """
    tess = tessellate_patches([homogeneous(g, w) for g, w in zip(groups, weights)], adjacency, n)
    points, _ = dehomogenize(tess.points)
    normals = np.empty((points.shape[0], 3))
    t = np.linspace(0.0, 1.0, n)
    for ids, group, w in _group_grids(tess.grid, groups, weights):
        normals[ids] = evaluate_rational(group, w, t, t)[1]
    return Tessellation(points, defined_normals(points, normals, tess.triangles), tess.triangles, None, tess.grid)


def fill_from_neighbours(values: np.ndarray, defined: np.ndarray, triangles: np.ndarray, rings: int = 64,
                         nonzero: bool = False) -> np.ndarray:
    """``values`` with undefined rows set to the mean of their defined neighbours, ring by ring.

    Parameters
    ----------
    values : (V, k) or (V,) float; defined : (V,) bool; triangles : (T, 3) int, the vertex neighbourhoods
    rings : int, how far to reach; rows still without a defined neighbour then are 0
    nonzero : bool, a mean of zero (normals that cancel) does not count as defined

    Returns
    -------
    values (a new array), every row finite
    """
    out = np.array(values, dtype=np.float64)
    flat = out.reshape(out.shape[0], -1)
    known = np.asarray(defined, dtype=bool).copy()
    flat[~known] = 0.0
    near = triangles[(~known)[triangles].any(axis=1)]
    edges = np.concatenate([near[:, [0, 1]], near[:, [1, 2]], near[:, [2, 0]]])
    edges = np.concatenate([edges, edges[:, ::-1]])
    for _ in range(rings):
        if known.all():
            break
        step = edges[~known[edges[:, 0]] & known[edges[:, 1]]]
        if step.size == 0:
            break
        total = np.zeros_like(flat)
        np.add.at(total, step[:, 0], flat[step[:, 1]])
        count = np.bincount(step[:, 0], minlength=flat.shape[0])
        fill = count > 0
        flat[fill] = total[fill] / count[fill, None]
        if nonzero:
            fill &= np.any(flat != 0, axis=1)
        known |= fill
    return out


def defined_normals(points: np.ndarray, normals: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``normals`` with every undefined row (a degenerate patch point: zero derivative, e.g. at a
    zero blend ratio, Lemma 1.3.12) replaced by the unit sum of its triangles' area vectors; where
    those vanish too (a collapsed region), by the mean of the neighbours' normals; zero only where
    nothing around has one. So no output carries NaN.

    Parameters
    ----------
    points : (V, dim) float, normals : (V, 3) float (changed in place and returned), triangles : (T, 3) int
    """
    if np.isfinite(normals.sum()):  # every entry finite (a sum of finite unit normals does not overflow): 30x faster
        return normals
    if not (bad := ~np.isfinite(normals).all(axis=1)).any():  # (overflowed sums of finite rows)
        return normals
    touching = bad[triangles].any(axis=1)
    tri = triangles[touching]
    p = points[:, :3]
    area = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    total = np.zeros((points.shape[0], 3))
    for corner in range(3):
        np.add.at(total, tri[:, corner], area)
    length = np.linalg.norm(total[bad], axis=1, keepdims=True)
    normals[bad] = np.divide(total[bad], length, out=np.zeros_like(total[bad]), where=length > 0)
    # where a whole region collapsed (zero-area triangles), take the mean normal of the defined
    # neighbours, ring by ring: at an edge a zero blend ratio makes sharp, the two sides' mean
    empty = np.linalg.norm(normals, axis=1) == 0
    if empty.any():
        normals[:] = fill_from_neighbours(normals, ~empty, tri, nonzero=True)
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        np.divide(normals, length, out=normals, where=length > 0)
    return normals


# -- the welded numbering --------------------------------------------------------------

_BLOCK_SAMPLES = 1 << 15  # samples evaluated per block: its ~20 float work arrays stay in a core's cache
_GRID_BLOCK_SAMPLES = 1 << 18  # grid samples per block of patches (int32 ids and their triangles)


@dataclass(frozen=True)
class _Welding:
    """The numbering of ``welded_grid_from_ids`` with its gaps closed, and who evaluates each vertex.

    corners, edges : (P, 4) int compact ids (the adjacency's arrays, int32 from the construction: not copied);
        reversed : (P, 4) bool
    corner_owner, edge_owner : (n_corners,), (n_edges,) int (int32 below 2^31 sides), the last flat position (patch * 4 + slot)
        holding each id: writing all patches in order would leave that patch's value (edge_owner is None
        when there are no edge samples)
    dense : bool, no id was unused (then each vertex is evaluated once, from its owner)
    """

    n: int
    corners: np.ndarray
    edges: np.ndarray
    reversed: np.ndarray
    corner_owner: np.ndarray
    edge_owner: np.ndarray | None
    dense: bool

    @staticmethod
    def of(adjacency: PatchAdjacency, n: int) -> "_Welding":
        corners, edges = np.asarray(adjacency.corners), np.asarray(adjacency.edges)
        corner_owner = _last_owner(corners, adjacency.n_corners)
        corners, corner_owner, dense = _close_gaps(corners, corner_owner)
        edge_owner = None
        if n > 2:  # edge ids only number edge samples
            edge_owner = _last_owner(edges, adjacency.n_edges)
            edges, edge_owner, dense_edges = _close_gaps(edges, edge_owner)
            dense = dense and dense_edges
        reversed_ = adjacency.reversed  # read through flat views; None in a corners-only adjacency (n = 2)
        reversed_ = None if reversed_ is None else np.ascontiguousarray(reversed_, dtype=bool)
        return _Welding(n, corners, edges, reversed_, corner_owner, edge_owner, dense)

    @property
    def n_patches(self) -> int:
        return int(self.corners.shape[0])

    @property
    def inner(self) -> int:
        return self.n - 2

    @property
    def n_corners(self) -> int:
        return int(self.corner_owner.size)

    @property
    def n_edges(self) -> int:
        return 0 if self.edge_owner is None else int(self.edge_owner.size)

    @property
    def patch_base(self) -> int:
        """First id of the patch interiors."""
        return self.n_corners + self.n_edges * self.inner

    @property
    def n_vertices(self) -> int:
        return self.patch_base + self.n_patches * self.inner**2

    @property
    def dtype(self):
        return np.int32 if self.n_vertices < 2**31 else np.int64

    @property
    def patch_block(self) -> int:
        """Patches per block of grid rows (int ids: a few per sample)."""
        return max(1, _GRID_BLOCK_SAMPLES // (self.n * self.n))


def _last_owner(ids: np.ndarray, count: int) -> np.ndarray:
    """(count,) int (int32 below 2^31 positions): the last position in the flat ``ids`` holding each id 0..count-1;
    -1 if none."""
    flat, index = ids.reshape(-1), np.int32 if ids.size < 2**31 else np.int64
    owner = np.full(count, -1, dtype=index)
    for a in range(0, flat.size, _GRID_BLOCK_SAMPLES):  # in order, so the last patch writing an id wins
        owner[flat[a : a + _GRID_BLOCK_SAMPLES]] = np.arange(a, min(a + _GRID_BLOCK_SAMPLES, flat.size), dtype=index)
    return owner


def _close_gaps(ids: np.ndarray, owner: np.ndarray):
    """(ids, owner, dense): ids renumbered 0, 1, ... in order without the unused ones (rare: no copy when dense)."""
    used = owner >= 0
    if used.all():
        return ids, owner, True
    rank = np.cumsum(used) - 1
    return rank[ids], owner[used], False


def _grid_block(welding: _Welding, a: int, z: int, grid: np.ndarray, alone: bool = False) -> None:
    """Fill ``grid[a:z]`` ((z-a, n, n) ids; ``alone``: ``grid`` is that block): corners, edge samples, interiors."""
    out = grid if alone else grid[a:z]
    corners = welding.corners[a:z]
    out[:, 0, 0] = corners[:, 0]
    out[:, -1, 0] = corners[:, 1]
    out[:, -1, -1] = corners[:, 2]
    out[:, 0, -1] = corners[:, 3]
    inner = welding.inner
    if inner <= 0:
        return
    # sample k of side s is sample k of its edge, or inner-1-k when the side runs against the edge
    first = welding.edges[a:z].astype(grid.dtype) * inner + welding.n_corners  # (z-a, 4), in the ids' type
    k = np.arange(inner)
    pattern, back = np.stack([k, inner - 1 - k]), welding.reversed[a:z].view(np.uint8)
    # sides: v = 0 and v = 1 with u increasing, u = 1 and u = 0 with v increasing
    for s, side in enumerate((out[:, 1:-1, 0], out[:, -1, 1:-1], out[:, 1:-1, -1], out[:, 0, 1:-1])):
        np.add(first[:, s, None], np.take(pattern, back[:, s], axis=0), out=side)
    interior = np.arange(a * inner * inner, z * inner * inner, dtype=grid.dtype).reshape(z - a, inner, inner)
    np.add(interior, welding.patch_base, out=out[:, 1:-1, 1:-1])


_local = threading.local()


def _work(name: str, shape, dtype=np.float64) -> np.ndarray:
    """A work array of ``shape``, kept per thread and reused by its next block (no fresh pages, warm in cache)."""
    arrays = _local.__dict__.setdefault("arrays", {})
    size = math.prod(shape)
    flat = arrays.get((name, dtype))
    if flat is None or flat.size < size:
        flat = arrays[name, dtype] = np.empty(size, dtype=dtype)
    return flat[:size].reshape(shape)


# -- evaluation straight into the welded arrays ------------------------------------------


def _normals_into(out: np.ndarray, xu, xv, sign=None) -> None:
    """out (..., 3) = sign (xu x xv) / |xu x xv|, NaN where it is zero, from coordinate planes.

    xu, xv : 3 arrays each (the x, y, z planes) of the shape of out[..., 0]
    sign : None or +-1 float broadcasting to that shape
    Computed as n = xu x xv, n_k * (sign / sqrt((n_0^2 + n_1^2) + n_2^2)), every step one
    pass over planes into per-thread work arrays (no temporaries).
    """
    shape = out.shape[:-1]
    n, t = _work("cross", (3,) + shape), _work("product", shape)
    for k in range(3):  # n_k = xu_{k+1} xv_{k+2} - xu_{k+2} xv_{k+1}
        np.multiply(xu[(k + 1) % 3], xv[(k + 2) % 3], out=n[k])
        np.multiply(xu[(k + 2) % 3], xv[(k + 1) % 3], out=t)
        np.subtract(n[k], t, out=n[k])
    square = _work("square", (3,) + shape)
    np.multiply(n, n, out=square)
    np.add(square[0], square[1], out=t)
    np.add(t, square[2], out=t)
    np.sqrt(t, out=t)
    if not t.all():
        t[t == 0] = np.nan  # a singular point has no normal (and 1 / NaN stays NaN)
    np.divide(1.0 if sign is None else sign, t, out=t)  # +-1 / length is exactly +-(1 / length)
    for k in range(3):
        np.multiply(n[k], t, out=out[..., k])


@dataclass(frozen=True)
class _Bases:
    """Sample matrices of one degree d at the n-2 inner parameters t (S = (d+1)^2 control points, m = (n-2)^2).

    position : (S dim, m dim), patch interiors from flat control points (rows (i, j, coordinate))
    du, dv : (S, m), interior derivatives from one coordinate's control points
    side_position : ((d+1) dim, (n-2) dim), side samples from the side's control polygon
    along, across : (n-2, 2 (d+1)), side derivatives from [control polygon, next row inwards]
    side_index : (4, 2, 2 (d+1)) int, control point offsets (i (d+1) + j) of [polygon, next row]
        of side s, in increasing parameter (flip 0) or in the opposite direction (flip 1)
    side_sign : (4, 2) float, +1 where x_u x x_v = along x across, -1 where it is across x along
    corner_index : (4, 3) int, offsets of corner c, its neighbour in u and in v
    corner_sign : (4,) float, s_u s_v: x_u = s_u (u neighbour - corner), x_v = s_v (v neighbour - corner)
    """

    d: int
    position: np.ndarray
    du: np.ndarray
    dv: np.ndarray
    side_position: np.ndarray
    along: np.ndarray
    across: np.ndarray
    side_index: np.ndarray
    side_sign: np.ndarray
    corner_index: np.ndarray
    corner_sign: np.ndarray

    @staticmethod
    def of(d: int, n: int, dim: int) -> "_Bases":
        t = np.linspace(0.0, 1.0, n)[1:-1]
        b, db = bernstein_basis(d, t), bernstein_basis(d, t, 1)
        position = np.kron(tensor_basis(b, b), np.eye(dim)).T
        du = np.ascontiguousarray(tensor_basis(db, b).T)
        dv = np.ascontiguousarray(tensor_basis(b, db).T)
        side_position = np.kron(b, np.eye(dim)).T
        zero = np.zeros_like(db)
        along, across = np.concatenate([db, zero], axis=1), np.concatenate([-b, b], axis=1)
        side_index = np.array([[np.concatenate([row, nxt]), np.concatenate([row[::-1], nxt[::-1]])]
                               for row, nxt in side_offsets(d)])
        # across points inwards: +x_v on side 0, -x_u on side 1, -x_v on side 2, +x_u on side 3, so
        # x_u x x_v is along x across on sides 0 and 1; a flipped polygon turns along around
        side_sign = np.array([[1.0, -1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, 1.0]])
        ci = np.array([0, d, d, 0])  # corner c at (u, v) = (0,0), (1,0), (1,1), (0,1)
        cj = np.array([0, 0, d, d])
        ni, nj = np.where(ci == 0, 1, d - 1), np.where(cj == 0, 1, d - 1)
        corner_index = np.stack([ci * (d + 1) + cj, ni * (d + 1) + cj, ci * (d + 1) + nj], axis=1)
        corner_sign = np.where(ci == 0, 1.0, -1.0) * np.where(cj == 0, 1.0, -1.0)
        return _Bases(d, position, du, dv, side_position, along, across, side_index, side_sign,
                      corner_index, corner_sign)


def _interior_block(flat: np.ndarray, bases: _Bases, points: np.ndarray, normals: np.ndarray) -> None:
    """Interior samples of a block of C patches of one degree.

    flat : (C, S dim) control points; points : (C, m dim) and normals : (C m, 3), output rows
    """
    c, dim = flat.shape[0], points.shape[1] // bases.du.shape[1]
    np.matmul(flat, bases.position, out=points)
    planes = _work("planes", (3, c, bases.du.shape[0]))  # one coordinate's control points per plane
    np.copyto(planes, flat.reshape(c, -1, dim)[:, :, :3].transpose(2, 0, 1))
    xu, xv = _work("xu", (3, c * bases.du.shape[1])), _work("xv", (3, c * bases.du.shape[1]))
    np.matmul(planes.reshape(3 * c, -1), bases.du, out=xu.reshape(3 * c, -1))
    np.matmul(planes.reshape(3 * c, -1), bases.dv, out=xv.reshape(3 * c, -1))
    _normals_into(normals, xu, xv)


def _side_block(control: np.ndarray, bases: _Bases, patch, side, flip, points: np.ndarray, normals: np.ndarray) -> None:
    """Inner samples of C edges, each from one side of one patch of one degree, in the edge's direction.

    control : (P_k (d+1)^2, dim) control points of the group; patch, side, flip : (C,) int
    points : (C, (n-2) dim) and normals : (C (n-2), 3), output rows
    """
    c, dim, k = patch.size, control.shape[1], bases.side_index.shape[-1]
    kind = side * 2 + flip  # take: much faster than fancy indexing on small tables
    index = patch[:, None] * (bases.d + 1) ** 2 + np.take(bases.side_index.reshape(8, k), kind, axis=0)  # (C, 2 (d+1))
    rows = _work("rows", (c * k, dim))
    np.take(control, index.reshape(-1), axis=0, out=rows, mode="clip")
    rows = rows.reshape(c, k * dim)
    np.matmul(rows[:, : (bases.d + 1) * dim], bases.side_position, out=points)
    # derivatives as (samples x control points) @ (control points x (coordinate, edge)): long rows,
    # where (edge, coordinate) rows would give products of only n-2 columns
    planes = _work("side planes", (k, 3, c))
    np.copyto(planes, rows.reshape(c, k, dim)[:, :, :3].transpose(1, 2, 0))
    inner = bases.along.shape[0]
    along, across = _work("along", (inner, 3, c)), _work("across", (inner, 3, c))
    np.matmul(bases.along, planes.reshape(k, 3 * c), out=along.reshape(inner, 3 * c))
    np.matmul(bases.across, planes.reshape(k, 3 * c), out=across.reshape(inner, 3 * c))
    _normals_into(normals.reshape(c, inner, 3).transpose(1, 0, 2), along.transpose(1, 0, 2), across.transpose(1, 0, 2),
                  np.take(bases.side_sign.reshape(8), kind))


def _corner_block(control, bases: _Bases, patch, slot, points: np.ndarray, normals: np.ndarray) -> None:
    """C corners, each from one corner of one patch: the control point, normals from first differences.

    control : (P_k (d+1)^2, dim), or a callable giving the rows (3, C, dim) at (3, C) offsets into such an array
    patch, slot : (C,) int; points : (C, dim), normals : (C, 3)
    """
    c = patch.size
    index = _work("corner index", (3, c), np.int64)  # rows of the corner and of its neighbours in u and v
    np.add(patch * (bases.d + 1) ** 2, np.take(bases.corner_index.T, slot, axis=1), out=index)  # take: fast on small tables
    rows = control(index) if callable(control) else np.take(control, index, axis=0, mode="clip",
                                                            out=_work("corner rows", (3, c, control.shape[1])))
    points[:] = rows[0]
    planes = _work("corner planes", (3, 3, c))  # (corner / u / v, coordinate, C)
    np.copyto(planes, rows[:, :, :3].transpose(0, 2, 1))
    np.subtract(planes[1:], planes[0], out=planes[1:])
    # x_u = s_u (u neighbour - corner), x_v alike, and (s_u a) x (s_v b) = s_u s_v (a x b) exactly
    _normals_into(normals, planes[1], planes[2], np.take(bases.corner_sign, slot))


def _owned_block(evaluate, groups, starts, owner: np.ndarray, width: int, points: np.ndarray, normals: np.ndarray) -> None:
    """Evaluate a block of corners or edges, each from the patch (and slot) ``owner`` names.

    evaluate(k, patch, slot, points, normals) does group k (patch: index in the group); points
    (C, width dim) and normals (C width, 3) are the output rows, written directly when one group
    owns the whole block.
    """
    patch, slot = owner >> 2, owner & 3  # divmod by 4 (owners are >= 0), several times faster
    for k, g in enumerate(groups):
        if g.shape[0] == 0:
            continue
        if starts[k] <= patch.min() and patch.max() < starts[k + 1]:
            evaluate(k, patch - starts[k], slot, points, normals)
            return
        mine = np.flatnonzero((patch >= starts[k]) & (patch < starts[k + 1]))
        if mine.size:
            p, q = _work("owned points", (mine.size, points.shape[1])), _work("owned normals", (mine.size * width, 3))
            evaluate(k, patch[mine] - starts[k], slot[mine], p, q)
            points[mine] = p
            normals.reshape(-1, width, 3)[mine] = q.reshape(-1, width, 3)


def _evaluate_welded(groups, welding: _Welding, points, normals, grid, local, triangles) -> None:
    """Fill ``grid``, ``triangles`` and (dense ids) the welded ``points`` and ``normals``.

    Every welded vertex is evaluated once, from the last patch that has it (as
    writing all patches in order would leave it): corners are control points
    with normals from first differences, edge samples come from the side's
    boundary curve and the next row of control points, and patch interiors are
    dense basis matrices (samples x coefficients) applied with matrix products
    written into the output rows. Blocks of patches also fill their grid rows
    and take their triangles from them while those are in cache.
    """
    n, inner, dim = welding.n, welding.inner, points.shape[1]
    m = inner * inner
    starts = np.cumsum([0] + [g.shape[0] for g in groups])
    bases = [_Bases.of(g.shape[1] - 1, n, dim) for g in groups]
    control = [g.reshape(-1, dim) for g in groups]
    per_patch = local.size // 3  # triangles

    def patches(k, a, z):  # patches a..z-1 (global) of group k
        _grid_block(welding, a, z, grid)
        block = triangles[a * per_patch : z * per_patch].reshape(z - a, -1)
        np.take(grid[a:z].reshape(z - a, -1), local, axis=1, out=block, mode="clip")  # clip: no bounds-check buffer
        if m and welding.dense:
            flat = groups[k].reshape(groups[k].shape[0], -1)
            step = max(1, _BLOCK_SAMPLES // m)  # interiors in smaller blocks: ~20 work arrays per sample
            for lo in range(a, z, step):
                hi = min(lo + step, z)
                rows = slice(welding.patch_base + lo * m, welding.patch_base + hi * m)
                _interior_block(flat[lo - starts[k] : hi - starts[k]], bases[k], points[rows].reshape(hi - lo, m * dim),
                                normals[rows])

    def corner(k, patch, slot, p, q):
        _corner_block(control[k], bases[k], patch, slot, p, q)

    def side(k, patch, slot, p, q):
        flip = np.take(welding.reversed.reshape(-1), (patch + starts[k]) * 4 + slot)
        _side_block(control[k], bases[k], patch, slot, flip.view(np.uint8), p, q)

    tasks = []
    step = welding.patch_block
    for k in range(len(groups)):
        for a in range(starts[k], starts[k + 1], step):
            tasks.append(partial(patches, k, a, min(a + step, starts[k + 1])))
    if welding.dense:
        step = _BLOCK_SAMPLES
        for a in range(0, welding.n_corners, step):
            z = min(a + step, welding.n_corners)
            tasks.append(partial(_owned_block, corner, groups, starts, welding.corner_owner[a:z], 1, points[a:z], normals[a:z]))
        step = max(1, _BLOCK_SAMPLES // max(inner, 1))
        for a in range(0, welding.n_edges, step):
            z = min(a + step, welding.n_edges)
            rows = slice(welding.n_corners + a * inner, welding.n_corners + z * inner)
            tasks.append(partial(_owned_block, side, groups, starts, welding.edge_owner[a:z], inner,
                                 points[rows].reshape(z - a, inner * dim), normals[rows]))
    run_tasks(tasks, uses_blas=True)
