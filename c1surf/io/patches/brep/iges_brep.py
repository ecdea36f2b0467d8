"""IGES 5.3 B-rep of a patch set: one solid per closed component (an open shell per open one), from c1surf's own topology.

A reader needs no sewing: the faces share their edges and vertices by
reference, as ``topology.brep_topology`` found them from the patch adjacency
(its patch-side edges joined into chains by ``edge_chains``, as in STEP). The entities are those of IGES 5.3's boundary-representation solid
model (section 4, "BREP"), written after the surfaces (one type 128 per face, in
the writer's order: merged pieces, then the uncovered patches), in this
Directory order:

- 126 rational B-spline curve, one per edge (form 0, status 00010000). The
  edges are those of the STEP B-rep (``edge_chains``): the patch sides
  between the same two faces where nothing else meets them, k of them one
  edge over [0, k], whose curve (``iges_edges``) is the C1 quadratic B-spline
  of those sides (knots 0 0 0 1 .. k k k) along a merged piece, one side's
  Bezier polygon (degree 2 or 3, knots ``0..0 1..1``) otherwise. Weights of a
  rational surface, PROP3 = 1 where they are all equal; grouped by layout;
- 126, the pcurves (status 00010500: use flag 05, parameter space): an edge
  use's straight degree-1 curve in its face's (u, v) domain ([0, m] x [0, n]
  for a piece of knots 0 .. m, [0, 1]^2 for a patch), planar (normal 0 0 1),
  from the use's start to its end *in loop direction*, over [0, k]. It runs
  with the 3D curve where the loop uses the edge forwards; where backwards,
  the reader reverses it (Open CASCADE's IGESToBRep does) and it runs with the
  curve again, parameter for parameter. Uses with the same segment share one
  entity (IGES lets several entities reference a physically dependent one):
  every patch face's loop names the same four;
- 502 vertex list and 504 edge list (form 1), in blocks of ``LIST_BLOCK``
  entries (an edge names its curve, start and end vertex as (list, index));
- 508 loop (form 1), one per face: its outer boundary, each entry an edge use
  (type 0, the edge list and index, orientation 1 = with the edge's curve,
  one isoparametric pcurve);
- 510 face (form 1): its surface, one loop, outer-loop flag 1;
- 514 shell, one per connected component of faces: form 1 (closed) or 2
  (open, IGES 5.3; Open CASCADE accepts forms 1 and 2 only), every face with
  orientation flag 1 (the patch normals are consistently oriented);
- 186 manifold solid B-rep object (form 0), one per closed component, no void
  shells; its shell orientation flag is 1 where the patch normals point out
  of the solid (positive signed volume), 0 where they point in, so the solid
  is outward either way;
- 402 form 7 group of the roots (solids and open shells) when there are
  several and ``group`` is on, so CAD still shows one object.

Subordinate entities are physically dependent (status ``00010000``), the
roots independent. Pointers are Directory Entry sequence numbers (2 k + 1 for
entity k). Entities are formatted from integer and real arrays, many at a time
(``iges_records.ParameterWriter``), never one string per entity.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ....evaluation.patch_set import PatchSet
from ..iges_numbers import SLOT, SPACE, format_ints, format_reals
from ..iges_records import ParameterWriter
from .iges_edges import IgesEdges, iges_edges
from .solids import closed_components, face_components, signed_volumes
from .topology import BRepTopology, brep_topology, edge_polygons

__all__ = ["IgesBRep", "iges_brep", "edge_polygons", "LIST_BLOCK"]

LIST_BLOCK = 512  # vertices per 502 entity, edges per 504 entity
_BUDGET = 1 << 18  # tokens formatted per chunk (with padding): bounds the memory

_STATUS = [b"00000000", b"00010000", b"00010500", b"00020000"]  # root, dependent, parameter space, group member
_ROOT, _DEPENDENT, _PARAMETRIC, _MEMBER = range(4)
_LABELS = [b"EDGE", b"PCURVE", b"VERTICES", b"EDGES", b"LOOP", b"FACE", b"SHELL", b"C1SURF"]
_CURVE, _PCURVE, _VERTICES, _EDGES, _LOOP, _FACE, _SHELL, _SOLID = range(8)


@dataclass(frozen=True)
class IgesBRep:
    """The B-rep entities of one file, numbered after its ``first`` surfaces, ready for ``iges_writer.write_iges``.

    topology : BRepTopology of the file: edges are chains (``iges_edges``), faces in the order of its surfaces
    first : int, number of surfaces before the B-rep entities (entity k has the DE pointer 2 k + 1)
    etype, form, status, label : (N,) int64, per B-rep entity in Directory order (status and label
        index ``STATUS`` and ``LABELS``)
    subscript : (N,) int64, 1-based number of the entity within its kind
    closed : (C,) bool, per connected component (shell)
    outward : (C,) bool, per component: the patch normals point out of the solid (closed ones)
    """

    topology: BRepTopology
    first: int
    etype: np.ndarray
    form: np.ndarray
    status: np.ndarray
    label: np.ndarray
    subscript: np.ndarray
    closed: np.ndarray
    outward: np.ndarray
    _parts: tuple  # (first entity, rows) of each run of entities in Directory order; rows() gives (ints, floats)

    STATUS = _STATUS
    LABELS = _LABELS

    @property
    def n_entities(self) -> int:
        return int(self.etype.size)

    @property
    def n_solids(self) -> int:
        return int(self.closed.sum())

    def emit(self, pdw: ParameterWriter) -> None:
        """Write the Parameter Data records of every B-rep entity, in Directory order."""
        for first, rows in self._parts:
            _emit_rows(pdw, first, *rows())  # tables made when written, one kind at a time: bounded memory


# ----------------------------------------------------------------------------
# parameter rows


def _ragged(etype: int, row: np.ndarray, items: np.ndarray, n_rows: int):
    """Integer parameter lists ``etype, count, items of the row ...``, one per row, concatenated.

    Parameters
    ----------
    row : (n,) int64, non-decreasing: the row (entity) of each item
    items : (n, k) int64, each item's k parameters

    Returns
    -------
    values : (sum of 2 + k count,) int64; starts : (n_rows + 1,) int64, row r is values[starts[r]:starts[r + 1]]
    """
    k = items.shape[1]
    count = np.bincount(row, minlength=n_rows)
    starts = np.r_[0, np.cumsum(2 + k * count)].astype(np.int64)
    values = np.empty(int(starts[-1]), np.int64)
    values[starts[:-1]] = etype
    values[starts[:-1] + 1] = count
    within = np.arange(row.size) - np.r_[0, np.cumsum(count)][row]
    values[(starts[row] + 2 + k * within)[:, None] + np.arange(k)] = items
    return values, starts


def _curve_rows(points: np.ndarray, weights: np.ndarray | None, d: int, spans: int, multiplicity: int):
    """Entity 126 parameters of clamped B-spline curves of ``spans`` unit spans: ints (n, 7), reals (n, ...).

    points : (n, c, 3) float; weights : (n, c) float or None (unit weights, polynomial). Degree d,
    knots ``0`` and ``spans`` d + 1 times, 1 .. spans - 1 ``multiplicity`` times each; range [0, spans],
    not flagged planar (normal 0 0 0); PROP2 (closed) where the end points and their weights are
    equal, PROP3 (polynomial) where all weights are.
    """
    n, count = points.shape[:2]
    w = np.ones(points.shape[:2]) if weights is None else weights
    closed = np.all(points[:, 0] == points[:, -1], axis=1) & (w[:, 0] == w[:, -1])
    polynomial = np.all(w == w[:, :1], axis=1)
    ints = np.zeros((n, 7), np.int64)
    ints[:, 0], ints[:, 1], ints[:, 2], ints[:, 4], ints[:, 5] = 126, count - 1, d, closed, polynomial
    knots = np.r_[np.zeros(d + 1), np.repeat(np.arange(1.0, spans), multiplicity), np.full(d + 1, float(spans))]
    floats = np.concatenate([np.broadcast_to(knots, (n, knots.size)), w, points.reshape(n, -1),
                             np.broadcast_to([0.0, float(spans), 0.0, 0.0, 0.0], (n, 5))], axis=1)
    return ints, floats


def _pcurve_rows(uv: np.ndarray):
    """Entity 126 parameters of straight parameter-space segments: ints (L, 7), reals (L, 17).

    uv : (L, 2, 2) float, start and end (u, v) of axis-parallel segments of whole spans. Degree 1,
    knots 0 0 k k and range [0, k] for a segment k spans long (so it runs with its edge's curve),
    unit weights, points (u, v, 0), planar with the normal 0 0 1.
    """
    n = uv.shape[0]
    spans = np.abs(uv[:, 1] - uv[:, 0]).sum(axis=1)
    ints = np.tile(np.array([126, 1, 1, 1, 0, 1, 0], np.int64), (n, 1))
    floats = np.zeros((n, 17))
    floats[:, [4, 5, 16]] = 1.0  # weights 1 1, normal 0 0 1
    floats[:, [2, 3, 13]] = spans[:, None]  # knots 0 0 k k, range 0 k
    floats[:, [6, 7]] = uv[:, 0]
    floats[:, [9, 10]] = uv[:, 1]
    return ints, floats


def _real_tokens(floats: np.ndarray):
    """``format_reals`` of a (g, nf) table, each column equal in all rows formatted once: (g, nf, SLOT), off, lens."""
    g, nf = floats.shape
    chars = np.empty((g, nf, SLOT), np.uint8)
    off = np.empty((g, nf), np.int64)
    lens = np.empty((g, nf), np.int64)
    const = np.all(floats == floats[:1], axis=0)
    for columns, rows in ((np.flatnonzero(const), 1), (np.flatnonzero(~const), g)):
        if columns.size:
            c, o, ln = format_reals(floats[:rows, columns])
            chars[:, columns] = c.reshape(rows, columns.size, SLOT)
            off[:, columns] = o.reshape(rows, columns.size)
            lens[:, columns] = ln.reshape(rows, columns.size)
    return chars, off, lens


def _chunk_end(lengths: np.ndarray, start: int) -> int:
    """End of the chunk of rows from ``start``: as many as fit the budget, padded to their longest (one at least)."""
    window = lengths[start : start + _BUDGET // 4]
    fits = np.arange(1, window.size + 1) * np.maximum.accumulate(window) <= _BUDGET
    return start + max(1, window.size if fits.all() else int(np.argmin(fits)))


def _emit_rows(pdw: ParameterWriter, first: int, ints, floats: np.ndarray | None) -> None:
    """Emit entities ``first, first + 1, ...``: integer columns, then real columns.

    ints : (g, ni) int64 (every row full), or ``(values, starts)`` of ``_ragged`` (integer rows of
        any lengths; then ``floats`` is None)
    floats : (g, nf) float or None
    """
    if isinstance(ints, tuple):
        values, starts = ints
        lengths = np.diff(starts)
    else:
        lengths = np.full(ints.shape[0], ints.shape[1] + (0 if floats is None else floats.shape[1]), np.int64)
    start = 0
    while start < lengths.size:
        end = _chunk_end(lengths, start)
        width = int(lengths[start:end].max())
        n = end - start
        if isinstance(ints, tuple):
            column = np.arange(width)[None, :]
            padding = column >= lengths[start:end, None]
            block = values[np.where(padding, 0, starts[start:end, None] + column)]
        else:
            block, padding = ints[start:end], None
        ni = block.shape[1]
        chars = np.empty((n, width, SLOT), np.uint8)
        off = np.empty((n, width), np.int64)
        lens = np.empty((n, width), np.int64)
        c, o, ln = format_ints(block)
        chars[:, :ni], off[:, :ni], lens[:, :ni] = c.reshape(n, ni, SLOT), o.reshape(n, ni), ln.reshape(n, ni)
        if floats is not None:
            chars[:, ni:], off[:, ni:], lens[:, ni:] = _real_tokens(floats[start:end])
        if padding is not None:
            lens[padding] = 0
            chars[padding] = SPACE
        pdw.emit(np.arange(first + start, first + end), chars, off, lens)
        start = end


# ----------------------------------------------------------------------------
# the entities


def _distinct_segments(uv: np.ndarray):
    """The distinct parameter-space segments of the loop entries: ((S, 2, 2) float, (L,) int64 segment of each entry).

    Domain corners are integers (0 .. m, 0 .. n), so a segment is one integer
    key; anything else falls back to a row-wise ``np.unique``.
    """
    flat = uv.reshape(-1, 4)
    base = int(flat.max()) + 1 if flat.size else 1
    if flat.size and np.all(flat == np.round(flat)) and flat.min() >= 0 and base ** 4 < 2**62:
        key = ((flat[:, 0] * base + flat[:, 1]) * base + flat[:, 2]) * base + flat[:, 3]
        keys, first, inverse = np.unique(key.astype(np.int64), return_index=True, return_inverse=True)
        return flat[first].reshape(-1, 2, 2), inverse.ravel()
    segments, inverse = np.unique(flat, axis=0, return_inverse=True)
    return segments.reshape(-1, 2, 2), inverse.ravel()


def _pointer(entity) -> np.ndarray:
    """Directory Entry pointer (sequence number of its first DE record) of 0-based entity numbers."""
    return 2 * np.asarray(entity, dtype=np.int64) + 1


@dataclass(frozen=True)
class _Numbers:
    """The first entity number of each kind, in Directory order (``end``: one past the last)."""

    curve: int
    pcurve: int
    vertex_list: int
    edge_list: int
    loop: int
    face: int
    shell: int
    solid: int
    group: int
    end: int


def _blocks(n: int) -> int:
    return -(-n // LIST_BLOCK)


def iges_brep(patch_set: PatchSet, first: int, group: bool = True, topology: BRepTopology | None = None) -> IgesBRep:
    """The B-rep entities of ``patch_set`` whose faces are the file's surfaces 0 .. ``first`` - 1.

    Parameters
    ----------
    patch_set : PatchSet, written by ``iges.write_patch_set_iges`` as ``first`` surfaces (merged
        pieces, then the uncovered patches: the order of ``topology.brep_topology``'s faces)
    first : int, number of surfaces (checked against the topology's faces)
    group : collect several roots (solids, open shells) in one 402 group
    topology : its ``brep_topology``, when already computed

    Returns
    -------
    IgesBRep
    """
    topology = brep_topology(patch_set) if topology is None else topology
    if topology.n_faces != first:
        raise ValueError(f"the B-rep has {topology.n_faces} faces but the file {first} surfaces")
    runs = iges_edges(topology, edge_polygons(patch_set, topology))
    topology = runs.topology  # edges: chains of patch sides (edge_chains), as in the STEP B-rep
    f, e, v = topology.n_faces, topology.n_edges, len(topology.vertex_points)
    component = face_components(topology)
    n_comp = int(component.max(initial=-1)) + 1
    face_of_use = np.repeat(np.arange(f), np.diff(topology.loop_start))
    closed = closed_components(topology, component)
    outward = signed_volumes(patch_set, topology, component) >= 0
    grouped = bool(group) and n_comp > 1
    segments, segment_of_use = _distinct_segments(topology.loop_uv)
    counts = [e, len(segments), _blocks(v), _blocks(e), f, f, n_comp, int(closed.sum()), int(grouped)]
    at = _Numbers(*(first + np.r_[0, np.cumsum(counts)]).tolist())
    parts, curve_of = _curve_parts(runs, at, segments)
    parts += _list_parts(topology, at, curve_of)
    loop_parts, loop_rank = _loop_and_face_parts(topology, at, segment_of_use, face_of_use)
    parts += loop_parts + _shell_parts(at, component, closed, outward, grouped)
    etype, form, status, label, subscript = _directory_fields(counts, closed, grouped)
    subscript[etype == 508] = np.argsort(loop_rank) + 1  # a loop is numbered by its face
    assert etype.size == at.end - first
    return IgesBRep(topology, first, etype, form, status, label, subscript, closed, outward, tuple(parts))


def _curve_parts(runs: IgesEdges, at: _Numbers, segments: np.ndarray):
    """Rows of the 126 edge curves (by layout) and pcurves, and the curve entity of each edge ((E,) int64)."""
    curve_of = np.empty(runs.topology.n_edges, np.int64)
    parts, first = [], at.curve
    for edges, degree, spans, multiplicity, points, weights in runs.curves:
        curve_of[edges] = first + np.arange(edges.size)
        parts.append((first, lambda p=points, w=weights, d=degree, k=spans, m=multiplicity: _curve_rows(p, w, d, k, m)))
        first += edges.size
    parts.append((at.pcurve, lambda: _pcurve_rows(segments)))
    return parts, curve_of


def _list_parts(topology: BRepTopology, at: _Numbers, curve_of: np.ndarray) -> list:
    """Rows of the 502 vertex lists (full blocks, then the last) and of the 504 edge lists."""
    v, parts = len(topology.vertex_points), []
    full = v // LIST_BLOCK * LIST_BLOCK
    for a, b in ((0, full), (full, v)):
        if b > a:
            rows = (b - a) // LIST_BLOCK if b == full else 1
            ints = np.tile(np.array([[502, min(LIST_BLOCK, b - a)]], np.int64), (rows, 1))
            points = topology.vertex_points[a:b].reshape(rows, -1)
            parts.append((at.vertex_list + a // LIST_BLOCK, lambda i=ints, x=points: (i, x)))
    def edge_lists():
        start, end = topology.edge_vertices[:, 0], topology.edge_vertices[:, 1]
        items = np.stack([_pointer(curve_of), _pointer(at.vertex_list + start // LIST_BLOCK), start % LIST_BLOCK + 1,
                          _pointer(at.vertex_list + end // LIST_BLOCK), end % LIST_BLOCK + 1], axis=1)
        e = topology.n_edges
        return _ragged(504, np.arange(e) // LIST_BLOCK, items, _blocks(e)), None

    return parts + [(at.edge_list, edge_lists)]


def _loop_and_face_parts(topology: BRepTopology, at: _Numbers, segment_of_use: np.ndarray, face_of_use: np.ndarray):
    """Rows of the 508 loops (longest first: fewer, tighter chunks) and 510 faces; the loop rank of each face."""
    f = topology.n_faces
    loop_rank = np.empty(f, np.int64)
    loop_rank[np.argsort(-np.diff(topology.loop_start), kind="stable")] = np.arange(f)

    def loops():
        uses = np.argsort(loop_rank[face_of_use], kind="stable")  # loop entries in the loops' Directory order
        edge = topology.loop_edge[uses]
        ones = np.ones_like(edge)
        items = np.stack([0 * ones, _pointer(at.edge_list + edge // LIST_BLOCK), edge % LIST_BLOCK + 1,
                          topology.loop_forward[uses].astype(np.int64), ones, ones,
                          _pointer(at.pcurve + segment_of_use[uses])], axis=1)
        return _ragged(508, loop_rank[face_of_use[uses]], items, f), None

    def faces():
        return np.stack([np.full(f, 510), _pointer(np.arange(f)), np.ones(f, np.int64), np.ones(f, np.int64),
                         _pointer(at.loop + loop_rank)], axis=1), None

    return [(at.loop, loops), (at.face, faces)], loop_rank


def _shell_parts(at: _Numbers, component: np.ndarray, closed: np.ndarray, outward: np.ndarray, grouped: bool) -> list:
    """Rows of the 514 shells (one per component), the 186 solids of the closed ones and the 402 group."""
    by_component = np.argsort(component, kind="stable")
    items = np.stack([_pointer(at.face + by_component), np.ones(component.size, np.int64)], axis=1)
    shells_rows = _ragged(514, component[by_component], items, closed.size)
    parts = [(at.shell, lambda: (shells_rows, None))]
    shells = np.flatnonzero(closed)
    if shells.size:
        solids = np.stack([np.full(shells.size, 186), _pointer(at.shell + shells), outward[shells].astype(np.int64),
                           np.zeros(shells.size, np.int64)], axis=1)
        parts.append((at.solid, lambda: (solids, None)))
    if grouped:
        roots = np.where(closed, _pointer(at.solid + np.cumsum(closed) - 1), _pointer(at.shell + np.arange(closed.size)))
        group = np.r_[402, closed.size, roots][None, :].astype(np.int64)
        parts.append((at.group, lambda: (group, None)))
    return parts


def _directory_fields(counts: list, closed: np.ndarray, grouped: bool):
    """Type, form, status, label and subscript (each (N,) int64) of the B-rep entities, in Directory order."""
    n_curves, n_pcurves, n_vlists, n_elists, f, _, _, n_solids, _ = counts
    loose = _MEMBER if grouped else _ROOT  # the roots (solids, open shells): in the group, or on their own
    runs = [(126, 0, _DEPENDENT, _CURVE, n_curves), (126, 0, _PARAMETRIC, _PCURVE, n_pcurves),
            (502, 1, _DEPENDENT, _VERTICES, n_vlists), (504, 1, _DEPENDENT, _EDGES, n_elists),
            (508, 1, _DEPENDENT, _LOOP, f), (510, 1, _DEPENDENT, _FACE, f)]
    runs += [(514, 1, _DEPENDENT, _SHELL, 1) if c else (514, 2, loose, _SHELL, 1) for c in closed.tolist()]
    runs += [(186, 0, loose, _SOLID, n_solids)] + ([(402, 7, _ROOT, _SOLID, 1)] if grouped else [])
    sizes = [r[4] for r in runs]
    etype, form, status, label = (np.repeat(np.array([r[i] for r in runs], np.int64), sizes) for i in range(4))
    subscript = np.concatenate([np.arange(1, n + 1) for n in sizes]).astype(np.int64)  # numbered within each kind
    subscript[etype == 514] = np.arange(1, closed.size + 1)
    subscript[etype == 402] = 0
    return etype, form, status, label, subscript
