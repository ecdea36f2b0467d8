"""Area, volume, centroid and inertia tensor of a patch surface, by Gauss-Legendre quadrature.

Everything is an integral over the patches' parameter squares of a function of
``x``, ``x_u`` and ``x_v``; ``N = x_u x x_v`` is the (unnormalized) outward normal:

- area: ``|N|``, not a polynomial (a square root). Integrated with ``k x k``
  Gauss points per patch on ``s x s`` sub-squares, ``s`` doubled patch by patch
  until two levels agree to ``AREA_RTOL`` (adaptive; the integrand is analytic
  where the patch is regular, so the rule converges exponentially and the
  difference of two levels bounds the error of the finer one by far).
- volume, first and second moments, by the divergence theorem on the solid
  bounded by a closed surface, with ``y = x - origin``:
  ``V = 1/3 int y.N``, ``int_V y_i = 1/4 int y_i (y.N)``,
  ``int_V y_i y_j = 1/5 int y_i y_j (y.N)`` (div(y_i y_j y) = 5 y_i y_j).
  For a polynomial patch of degree ``d`` in u, ``y.N`` has degree ``3d - 1`` in u
  and ``y_i y_j (y.N)`` degree ``5d - 1``: ``ceil(5d / 2)`` Gauss points (exact to
  degree ``2k - 1``) integrate all three exactly, up to rounding. Rational patches
  (``x = H / w``) give rational integrands (``y.N = det(H, H_u, H_v) / w^3`` for
  the origin at 0): they take the adaptive path of the area, to ``MOMENT_RTOL``.

The origin of ``y`` is the centre of the control points' bounding box, so that
the centroid and the central second moments lose no digits to a far-away
solid. The inertia tensor is that of the solid of unit density about its
centroid, ``I = int_V (|r|^2 Id - r r^T)`` with ``r = x - centroid``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bezier import bernstein_basis, evaluate_grid
from .rational import euclidean_derivatives, homogeneous
from .stream.patches import BLOCK, ArrayPatches, patch_blocks
from ..parallel import for_each_range

AREA_RTOL = 1e-13  # two levels of the area quadrature agree to this, relative, patch by patch
MOMENT_RTOL = 1e-13  # the same for the moments of rational patches
MAX_SUBDIVISIONS = 64  # sub-squares per side at most (a singular patch stops there)
COMPILED_FROM = 20_000  # polynomial patches from which the integrals run compiled (``compiled_loops``)
CHUNK_SAMPLES = 1 << 19  # samples evaluated at once (bounds the memory, not a per-patch loop)


@dataclass(frozen=True)
class MassProperties:
    """Result of ``mass_properties``.

    area : float
    area_error : float, estimated absolute error of ``area`` (sum over patches of the
        difference of the last two quadrature levels)
    closed : bool, every patch side shared by two consistently oriented patches
    reason : str or None, why volume, centroid and inertia are None (open surface)
    volume : float or None
    centroid : (3,) float or None
    inertia : (3, 3) float or None, about the centroid, unit density
    note : str or None, e.g. the orientation was inwards and was turned
    """

    area: float
    area_error: float
    closed: bool
    reason: str | None = None
    volume: float | None = None
    centroid: np.ndarray | None = None
    inertia: np.ndarray | None = None
    note: str | None = None


def gauss_rule(points: int, subdivisions: int = 1):
    """Composite Gauss-Legendre rule on [0, 1].

    Parameters
    ----------
    points : int, Gauss points per sub-interval (exact for polynomials of degree 2 points - 1)
    subdivisions : int, equal sub-intervals

    Returns
    -------
    nodes, weights : (points * subdivisions,) float, the weights summing to 1
    """
    x, w = np.polynomial.legendre.leggauss(points)
    left = np.arange(subdivisions, dtype=np.float64)[:, None]
    nodes = (left + 0.5 * (x[None, :] + 1.0)) / subdivisions
    return nodes.ravel(), np.tile(0.5 * w / subdivisions, subdivisions)


def area_points(degree: int) -> tuple:
    """(coarse, fine): the Gauss points per direction of the area's screen (``_screened_area``) in a variable
    of degree ``degree``: the moment rule's ``moment_points`` plus 2 and plus 4. Measured on the patches of
    the 100,000-triangle torus and of ogre.obj at -r 2: 7 points leave biquadratic patches' areas within
    4e-14 relative of a 48-point composite rule (the rounding floor), 10 points bicubic ones within 4e-14
    (torus) and 3e-13 on 99% of ogre's; 5 and 8, 1e-13 to 3e-13 (torus) and far worse where a patch's
    parametrization nearly degenerates (those fail the screen and are subdivided)."""
    return moment_points(degree) + 2, moment_points(degree) + 4


def moment_points(degree: int) -> int:
    """Gauss points integrating ``y_i y_j (y . x_u x x_v)`` exactly in a variable of degree ``degree``."""
    return max(1, (5 * degree + 1) // 2)


def patch_frames(points: np.ndarray, weights, u: np.ndarray, v: np.ndarray):
    """Points and first derivatives of patches of one degree on a tensor grid.

    Parameters
    ----------
    points : (p, du+1, dv+1, 3) float
    weights : None or (p, du+1, dv+1) float (rational patches)
    u, v : (mu,), (mv,) float

    Returns
    -------
    x, x_u, x_v : (p, mu, mv, 3) float
    """
    coefficients = points if weights is None else homogeneous(points, weights)
    du, dv = coefficients.shape[1] - 1, coefficients.shape[2] - 1
    bu, bv = bernstein_basis(du, u), bernstein_basis(dv, v)
    h = {(0, 0): evaluate_grid(coefficients, bu, bv),
         (1, 0): evaluate_grid(coefficients, bernstein_basis(du, u, 1), bv),
         (0, 1): evaluate_grid(coefficients, bu, bernstein_basis(dv, v, 1))}
    if weights is not None:
        h = euclidean_derivatives(h)
    return h[(0, 0)], h[(1, 0)], h[(0, 1)]


def area_integrand(x: np.ndarray, xu: np.ndarray, xv: np.ndarray, origin=None) -> np.ndarray:
    """``|x_u x x_v|`` as one column: (..., 3) float arrays -> (..., 1) float."""
    n = np.cross(xu, xv)
    return np.sqrt(np.einsum("...i,...i->...", n, n))[..., None]


def moment_integrand(x: np.ndarray, xu: np.ndarray, xv: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Volume, first and second moment densities of the divergence theorem.

    Parameters
    ----------
    x, xu, xv : (..., 3) float
    origin : (3,) float

    Returns
    -------
    (..., 13) float: ``y.N / 3``, ``y_i (y.N) / 4`` (3), ``y_i y_j (y.N) / 5`` (9, row-major)
    """
    y = x - origin
    flux = np.einsum("...i,...i->...", y, np.cross(xu, xv))[..., None]
    second = (y[..., :, None] * y[..., None, :]).reshape(y.shape[:-1] + (9,))
    return np.concatenate([flux / 3.0, y * flux / 4.0, second * flux / 5.0], axis=-1)


def _integrate_fixed(points, weights, integrand, origin, rule_u, rule_v, compiled: bool = False) -> np.ndarray:
    """Integrals of ``integrand`` over every patch with one tensor rule: (p, c), in chunks of patches. With
    ``compiled``, polynomial patches' area and moments go through the compiled loops (``_compiled_fixed``)."""
    if not len(points):
        return np.zeros((0, 1))
    if compiled and weights is None and integrand in (area_integrand, moment_integrand):
        return _compiled_fixed(points, integrand is moment_integrand, origin, rule_u, rule_v)
    return _numpy_fixed(points, weights, integrand, origin, rule_u, rule_v)


def _numpy_fixed(points, weights, integrand, origin, rule_u, rule_v) -> np.ndarray:
    """``_integrate_fixed`` in numpy, any integrand and rational patches: (p, c), in chunks of patches."""
    (u, wu), (v, wv) = rule_u, rule_v
    w = wu[:, None] * wv[None, :]
    chunk = max(1, CHUNK_SAMPLES // w.size)
    out = []
    for start in range(0, len(points), chunk):
        part = slice(start, start + chunk)
        frames = patch_frames(points[part], None if weights is None else weights[part], u, v)
        out.append(_weighted_sums(integrand(*frames, origin), w))
    return np.concatenate(out) if out else np.zeros((0, 1))


def _compiled_fixed(points: np.ndarray, moments: bool, origin, rule_u, rule_v) -> np.ndarray:
    """``_integrate_fixed`` of polynomial patches by ``kernels.area_sums`` (moments False: (p, 1)) or
    ``kernels.moment_sums`` ((p, 13)), on ``parallel``'s threads over ranges of patches (each patch's value is
    computed from its own coefficients alone: the same bits on any thread and in any range).

    points : (p, du+1, dv+1, 3) float; origin : (3,) float; rule_u, rule_v : (nodes, weights) of ``gauss_rule``
    """
    from .compiled import kernels  # numba: imported by the commands that integrate, and only on their first block

    points = np.ascontiguousarray(points, dtype=np.float64)
    (u, wu), (v, wv) = rule_u, rule_v
    du, dv = points.shape[1] - 1, points.shape[2] - 1
    bases = tuple(np.ascontiguousarray(b) for b in (bernstein_basis(du, u), bernstein_basis(du, u, 1),
                                               bernstein_basis(dv, v), bernstein_basis(dv, v, 1), wu, wv))
    out = np.empty((len(points), 13 if moments else 1))
    if moments:
        origin = np.ascontiguousarray(origin, dtype=np.float64)
        work = lambda a, z: kernels.moment_sums(points[a:z], bases, origin, out[a:z])
    else:
        work = lambda a, z: kernels.area_sums(points[a:z], bases, out[a:z, 0])
    for_each_range(len(points), work, minimum=1 << 11)
    return out


def _weighted_sums(values: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(p, c) float: ``sum_ab values[p, a, b, c] w[a, b]``, each patch's sum over one contiguous row of its
    products (numpy's pairwise sum of a row), so that a patch's integral does not depend on how many patches
    are integrated with it (``einsum`` sums a single patch in another order)."""
    p, c = values.shape[0], values.shape[-1]
    rows = np.ascontiguousarray(np.moveaxis(values, -1, 1)).reshape(p, c, -1)
    rows *= w.reshape(-1)
    return rows.sum(axis=-1)


def integrate_patches(points, weights, integrand, origin, rtol: float | None = None):
    """Integrals of ``integrand(x, x_u, x_v, origin)`` over every patch of one degree.

    With ``rtol`` None: one rule of ``moment_points`` Gauss points per direction
    (exact for the polynomial moments). Otherwise adaptive: the sub-squares per
    side double on the patches whose last two levels differ by more than
    ``rtol`` (relative to the patch's value, or to the mean over the patches where
    that is smaller), up to ``MAX_SUBDIVISIONS``.

    Parameters
    ----------
    points : (p, du+1, dv+1, 3) float
    weights : None or (p, du+1, dv+1) float
    integrand : callable (..., 3) x 3, (3,) -> (..., c)
    origin : (3,) float
    rtol : float or None

    Returns
    -------
    values : (p, c) float; error : (p,) float, the last difference of two levels (0 without rtol)
    """
    patches = ArrayPatches([points], None if weights is None else [weights])
    if not patches.counts:
        return _integrate_fixed(points, weights, integrand, origin, None, None), np.zeros(0)
    return _integrate_group(patches, 0, (integrand, origin, compiled_loops(patches)), rtol, len(points))


def compiled_loops(patches) -> bool:
    """Whether the integrals of a ``stream.patches`` reader run in the compiled loops (``kernels``): polynomial
    patches, ``COMPILED_FROM`` or more of them (fewer: numpy, without numba's import and loading, 0.5 s).
    Decided for the whole reader, so that a patch's value never depends on the block it is read in."""
    return not patches.rational and sum(patches.counts) >= COMPILED_FROM


def _integrate_group(patches, k: int, integral: tuple, rtol, block: int, progress=None, label: str = ""):
    """``integrate_patches`` of group ``k`` of a ``stream.patches`` reader, ``block`` patches at a time, for the
    ``integral`` (integrand, origin, compiled: ``compiled_loops``).

    Every patch's value is computed patch by patch (the fixed rule, then the levels of the adaptive one, whose
    test reads the mean over the whole group: taken from the fixed values of all patches, held as (p, c)), so
    the values do not depend on ``block``. The area of polynomial patches: ``_screened_area``.
    """
    integrand, origin, compiled = integral
    if rtol is not None and integrand is area_integrand and not patches.rational:
        return _screened_area(patches, k, rtol, block, compiled, (progress, label))
    count, (du, dv) = patches.counts[k], patches.degrees[k]
    ku, kv = moment_points(du), moment_points(dv)
    values, error = None, np.zeros(count)
    for a in range(0, count, block):
        z = min(a + block, count)
        part = _integrate_fixed(*patches.block(k, a, z), integrand, origin, gauss_rule(ku), gauss_rule(kv), compiled)
        if values is None:
            values = np.empty((count, part.shape[1]))
        values[a:z] = part
        patches.release()
        if progress is not None and rtol is None:
            progress(label, z - a, sum(patches.counts))
    if rtol is None:
        return values, error
    scale = np.maximum(np.abs(values), np.abs(values).mean(axis=0))
    for a in range(0, count, block):
        z = min(a + block, count)
        _refine(patches.block(k, a, z), integral, rtol, (ku, kv), (values[a:z], error[a:z], scale[a:z]))
        patches.release()
        if progress is not None:
            progress(label, z - a, sum(patches.counts))
    return values, error


def _screened_area(patches, k: int, rtol: float, block: int, compiled: bool, progress=(None, "")):
    """``_integrate_group`` of the area of polynomial patches: the two rules of ``area_points`` on every patch,
    the finer one kept where the two agree to ``rtol`` (relative to the patch's area, or to the group's mean
    area where that is larger); the other patches go through the levels of ``_refine`` from the moment rule
    (sub-squares doubled up to ``MAX_SUBDIVISIONS``), as every patch did before the screen (issue 36: on the
    100,000-triangle torus's 1.2 M patches those levels evaluated 613 M points, the screen 156 M).

    The integrand is analytic on a regular patch, so Gauss-Legendre's error falls geometrically with the points:
    the difference of the two rules bounds the coarse one's error, and the finer one's is smaller still. Per
    patch, the same values whatever ``block`` (the screen's test reads the mean of the whole group, held (p,)).

    Returns
    -------
    values : (p, 1) float; error : (p,) float, the last difference of two rules or levels
    """
    count, (du, dv) = patches.counts[k], patches.degrees[k]
    (cu, fu), (cv, fv) = area_points(du), area_points(dv)
    area = (area_integrand, np.zeros(3), compiled)
    coarse, values = np.empty(count), np.empty(count)
    for a in range(0, count, block):
        z = min(a + block, count)
        points = patches.block(k, a, z)[0]
        coarse[a:z] = _integrate_fixed(points, None, *area[:2], gauss_rule(cu), gauss_rule(cv), compiled)[:, 0]
        values[a:z] = _integrate_fixed(points, None, *area[:2], gauss_rule(fu), gauss_rule(fv), compiled)[:, 0]
        patches.release()
        if progress[0] is not None:
            progress[0](progress[1], z - a, sum(patches.counts))
    error = np.abs(values - coarse)
    scale = np.maximum(np.abs(values), np.abs(values).mean())
    hard = np.flatnonzero(error > rtol * scale)
    rule = (moment_points(du), moment_points(dv))
    for a in range(0, hard.size, block):
        ids = hard[a:a + block]
        points = patches.take(k, ids)[0]
        state = (_integrate_fixed(points, None, *area[:2], gauss_rule(rule[0]), gauss_rule(rule[1]), compiled),
                 np.zeros(ids.size), scale[ids, None])
        _refine((points, None), area, rtol, rule, state)
        values[ids], error[ids] = state[0][:, 0], state[1]
        patches.release()
    return values[:, None], error


def _refine(block: tuple, integral: tuple, rtol: float, rule: tuple, state: tuple) -> None:
    """The adaptive levels of ``integrate_patches`` on a ``block`` (points, weights) of patches, for the
    ``integral`` (integrand, origin, compiled): ``state`` (values (b, c), error (b,), scale (b, c)) updated in
    place (views into the group's); ``scale``, the test's relative scale of each patch."""
    (points, weights), (integrand, origin, compiled), (values, error, scale) = block, integral, state
    (ku, kv), active, s = rule, np.arange(len(points)), 1
    while active.size and s < MAX_SUBDIVISIONS:
        s *= 2
        finer = _integrate_fixed(points[active], None if weights is None else weights[active], integrand, origin,
                                 gauss_rule(ku, s), gauss_rule(kv, s), compiled)
        change = np.abs(finer - values[active])
        values[active], error[active] = finer, change.max(axis=1)
        active = active[np.any(change > rtol * scale[active], axis=1)]


def closed_surface(edges: np.ndarray, reversed_: np.ndarray):
    """Whether patch sides close up into a consistently oriented surface.

    Parameters
    ----------
    edges : (P, 4) int, edge id of every side (``adjacency.PatchAdjacency.edges``)
    reversed_ : (P, 4) bool, side runs against its edge

    Returns
    -------
    closed : bool; reason : str or None, why not
    """
    if edges.size == 0:
        return False, "there are no patches"
    flat = edges.ravel()
    count = np.bincount(flat)
    if np.any(count == 1):
        return False, f"the surface is open: {int(np.sum(count == 1))} patch sides lie on its boundary"
    if np.any(count > 2):
        return False, f"{int(np.sum(count > 2))} patch edges are shared by more than two patches"
    # Run counter-clockwise around a patch, sides 2 and 3 go against increasing parameter.
    ccw = (reversed_ ^ (np.arange(4) >= 2)[None, :]).ravel()
    order = np.argsort(flat, kind="stable")
    if np.any(ccw[order[0::2]] == ccw[order[1::2]]):
        return False, "the patches are not consistently oriented (a non-orientable surface bounds no solid)"
    return True, None


def _bbox_centre(patches, block: int = BLOCK) -> np.ndarray:
    """(3,) float: the centre of the bounding box of the control points (x, y, z), read by blocks."""
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    for _, k, a, z in patch_blocks(patches, block):
        flat = patches.block(k, a, z)[0].reshape(-1, 3)
        low, high = np.minimum(low, flat.min(axis=0)), np.maximum(high, flat.max(axis=0))
    return 0.5 * (low + high)


def _reader(groups, weights):
    """A ``stream.patches`` reader of ``groups`` (lists of arrays, or a reader already)."""
    if hasattr(groups, "take"):
        return groups
    return ArrayPatches([np.asarray(g)[..., :3] for g in groups], weights)


def surface_area(groups, weights=None, rtol: float = AREA_RTOL, block: int = BLOCK, progress=None):
    """Area of the patches and its estimated absolute error.

    Parameters
    ----------
    groups : list of (p_k, du+1, dv+1, 3) float, or a ``stream.patches`` reader (``weights`` None)
    weights : None or a list parallel to ``groups`` of (p_k, du+1, dv+1) float
    block : int, patches integrated at a time (the result does not depend on it)
    progress : callable(label, advance, total) or None

    Returns
    -------
    area, error : float
    """
    patches = _reader(groups, weights)
    area = error = 0.0
    for k in range(len(patches.counts)):
        values, err = _integrate_group(patches, k, (area_integrand, np.zeros(3), compiled_loops(patches)), rtol,
                                       block, progress, "measuring the area")
        area, error = area + float(values.sum()), error + float(err.sum())
    return area, error


def solid_moments(groups, weights=None, rtol: float = MOMENT_RTOL, block: int = BLOCK, progress=None):
    """Volume, centroid and central inertia tensor of the solid the closed patches bound.

    Parameters
    ----------
    groups : list of (p_k, du+1, dv+1, 3) float, a closed, consistently oriented surface; or a
        ``stream.patches`` reader (``weights`` None)
    weights : None or a list parallel to ``groups`` of (p_k, du+1, dv+1) float (rational
        patches: adaptive quadrature to ``rtol``; polynomial ones are exact)
    block, progress : as ``surface_area``'s

    Returns
    -------
    volume : float (negative when the normals point inwards); centroid : (3,) float;
    inertia : (3, 3) float, about the centroid, of the density sign(volume)
    """
    patches = _reader(groups, weights)
    origin = _bbox_centre(patches, block)
    total = np.zeros(13)
    for k in range(len(patches.counts)):
        values, _ = _integrate_group(patches, k, (moment_integrand, origin, compiled_loops(patches)),
                                     rtol if patches.rational else None, block, progress, "measuring the volume")
        total += values.sum(axis=0)
    volume, first, second = total[0], total[1:4], total[4:].reshape(3, 3)
    shift = first / volume
    central = second - volume * np.outer(shift, shift)
    inertia = np.trace(central) * np.eye(3) - central
    return float(volume), origin + shift, 0.5 * (inertia + inertia.T)


def mass_properties(groups, edges: np.ndarray, reversed_: np.ndarray, weights=None, block: int = BLOCK,
                    progress=None) -> MassProperties:
    """Area; for a closed surface also volume, centroid and inertia tensor (about the centroid).

    Parameters
    ----------
    groups : list of (p_k, du+1, dv+1, 3) float, patches in file order (memory-mapped ones are read by
        blocks); or a ``stream.patches`` reader (``SourcePatches``: a streamed Surface), ``weights`` None
    edges, reversed_ : (P, 4) int, (P, 4) bool, the patch adjacency (decides closedness)
    weights : None or a list parallel to ``groups`` of (p_k, du+1, dv+1) float
    block : int, patches integrated at a time: the result does not depend on it (every patch's integral is
        computed patch by patch, and the sums are taken over the (P, c) values of each group, held whole)
    progress : callable(label, advance, total) or None

    Returns
    -------
    MassProperties; a solid whose normals point inwards is measured turned outwards (with a note)
    """
    patches = _reader(groups, weights)
    area, area_error = surface_area(patches, block=block, progress=progress)
    closed, reason = closed_surface(np.asarray(edges), np.asarray(reversed_, dtype=bool))
    if not closed:
        return MassProperties(area, area_error, False, reason)
    volume, centroid, inertia = solid_moments(patches, block=block, progress=progress)
    note = None
    if volume < 0:
        volume, inertia = -volume, -inertia
        note = "the patch normals point into the solid; measured as if they pointed out"
    return MassProperties(area, area_error, True, None, volume, centroid, inertia, note)


__all__ = ["MassProperties", "mass_properties", "surface_area", "solid_moments", "closed_surface", "gauss_rule",
           "integrate_patches", "patch_frames", "AREA_RTOL", "MOMENT_RTOL"]
