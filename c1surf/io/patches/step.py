"""Patch files in STEP (``.step`` / ``.stp``, AP214) through Open CASCADE (optional extra ``c1surf[cad]``).

Every patch becomes a face on an exact Bezier surface (``Geom_BezierSurface``,
rational with the patch weights when the surface has them, written as a
B-spline surface); every merged piece (the default; ``--no-merge`` writes
patches) a face on its B-spline surface (``Geom_BSplineSurface``), in place
of the patches it stands for. The faces' shared edges, vertices and shells
come from c1surf's own adjacency (``brep.step_brep``), not from a sewing by
tolerance: each closed component of the surface is one solid, each open one
a shell. The header's time stamp is fixed, so the output is reproducible.
Every real is written with 17 significant digits (``_write_step_text``), so the
doubles come back.

Reading (``read_patch_set_step``, ``c1surf check`` / ``measure`` / ``diff`` /
``tessellate``) takes every face back: a Bezier span is a patch of its
degree, a merged B-spline piece a ``PatchSet.merged`` entry with its patches
cut out again (as the IGES reader does), a reversed face has u and v
swapped; other surfaces and trimmed faces are refused with one line.
"""
from __future__ import annotations

import importlib.util
import os
import re

import numpy as np

from ...console import quiet_stdout
from ...evaluation.merge import MergedPiece
from ...evaluation.patch_set import PatchSet
from ..contained import call_contained
from ..errors import MeshInputError
from ..finite import refuse_non_finite_patch_set
from .brep.step_brep import brep_shape, occ_classes
from .checks import check_net_range
from .merged import cad_patch_set, is_piece_knots, piece_patches
from .brep.step_faces import READ_HINT, face_nets, refuse_huge_reals, unpack_faces

_FACE_MODULE = "c1surf.io.patches.brep.step_faces"  # the Open CASCADE side of reading, run in a child (io.contained)
CONTAINED = True  # read in the child process (False: in this one, for tests that replace step_faces._read_shape)
_LIMIT_SECONDS = (60.0, 20.0)  # a read's time limit: base and per MB of file (torus2k's 10 MB read in ~6 s)


def write_patch_set_step(path, patch_set, *, file_name: str | None = None, strips: bool = True,
                         **_options) -> None:
    """Write ``patch_set`` as STEP AP214: one solid per closed component, one shell per open one.

    The B-rep comes from c1surf's own topology (``brep.step_brep.brep_shape``):
    shared patch sides are shared edges, nothing is sewn. Weights make rational
    faces; merged pieces are written as B-spline faces in place of their
    patches; ``strips``: cut into strips one span wide first (``merged.cad_patch_set``, ``convert
    --cad-pieces`` turns it off). Other formats' options (IGES units, ...) do not apply.
    """
    points = np.concatenate([np.asarray(g, dtype=np.float64)[..., :3].reshape(-1, 3) for g in patch_set.groups if len(g)]
                            + [np.zeros((0, 3))])
    _check_range(path, points)
    refuse_non_finite_patch_set(patch_set, path)
    if strips:  # Open CASCADE's default mass properties exact (io.patches.merged.cad_patch_set)
        patch_set = cad_patch_set(patch_set)
    write_step_shape(path, brep_shape(patch_set).shape, file_name or os.path.basename(os.fspath(path)))


def write_step_shape(path, shape, name: str) -> None:
    """Write an Open CASCADE shape as STEP AP214 with full precision and a reproducible header named ``name``."""
    occ_classes()  # or an OutputError saying what to install
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TCollection import TCollection_HAsciiString

    from ..errors import OutputError

    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    with quiet_stdout():  # Open CASCADE prints transfer statistics on stdout
        writer = STEPControl_Writer()
        if writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone:
            raise OutputError(path, "Open CASCADE could not translate the surface to STEP")
        del shape  # the caller's B-rep may go now: the STEP model holds what is written
        header = APIHeaderSection_MakeHeader(writer.Model())
        header.SetName(TCollection_HAsciiString(name))
        header.SetTimeStamp(TCollection_HAsciiString("1970-01-01T00:00:00"))
        header.SetOriginatingSystem(TCollection_HAsciiString("c1surf"))
        with open(path, "wb") as f:
            written = _write_step_text(writer, f)
        del writer, header
    if not written:
        raise OutputError(path, "Open CASCADE could not write the STEP file")
    _fix_header(path, name)


def _check_range(path, points: np.ndarray) -> None:
    """Refuse coordinates that are not finite or of magnitude 1e100 and more (a 3-digit exponent overflows Open CASCADE's number buffer)."""
    if points.size and not np.abs(points).max() < 1e100:  # also catches nan
        from ..errors import OutputError

        raise OutputError(path, "STEP output needs finite coordinates below 1e100 in magnitude")


def _write_step_text(writer, stream) -> bool:
    """Write the STEP file of ``writer``'s model to the binary ``stream``, every real with 17 significant digits.

    ``STEPControl_Writer.Write`` prints reals with 12 digits; this does what it
    does (``StepSelect_WorkLibrary::WriteFile``: a ``StepData_StepWriter`` on the
    model, ``SendModel``, ``Print``) with the float format ``%.16E``, so every
    double reads back to the same bits. Magnitudes below 1e-99 take ``%.15E``:
    their 3-digit exponent would not fit Open CASCADE's 24-character buffer.
    Printed straight into the file (not into memory first): spot's 150 MB of text is never held.
    """
    from OCP.StepData import StepData_StepWriter

    step_writer = StepData_StepWriter(writer.Model())
    floats = step_writer.FloatWriter()
    floats.SetFormat("%.16E")  # resets the range format and the zero suppression (which cuts long numbers)
    floats.SetFormatForRange("%.15E", 0.0, 1e-99)
    step_writer.SendModel(writer.WS().Protocol())
    return bool(step_writer.Print(stream))


# ----------------------------------------------------------------------------
# reading


def read_patch_set_step(path) -> PatchSet:
    """Read the faces of a STEP file as a PatchSet (``c1surf check``, ``measure``, ``diff``, ``tessellate``).

    Every face must be untrimmed (its parameter bounds those of its surface,
    one wire) on a Bezier surface or a B-spline surface that is one Bezier
    span (a patch of its degree) or a c1surf merged piece (degree (2, 2),
    knots 0 0 0 1 ... m m m: a ``PatchSet.merged`` entry, its patches cut out
    again into the biquadratic group, as the IGES reader does). A reversed
    face (``TopAbs_REVERSED``) has its u and v swapped, so every normal
    ``x_u x x_v`` points as the face's. Unequal weights make ``PatchSet.weights``.

    Returns
    -------
    PatchSet with groups ordered by degree: biquadratic (3, 3, 3), then
    bicubic (4, 4, 3), then any other degree; no adjacency or sources
    (``PatchSet.welding()`` finds the adjacency from the geometry)

    Raises
    ------
    MeshInputError
        one line: no Open CASCADE, no such file, not STEP, no faces, or a face
        c1surf does not read (other surface types, trimmed faces, other B-splines)
    """
    by_shape: dict = {(3, 3): ([], [])}  # (du + 1, dv + 1) -> (patches, weights), in face order
    pieces = []
    faces = _read_faces(path)
    check_net_range(path, *_nets_by_size(faces))  # before any evaluation: Open CASCADE reads a real of 3e38 as inf
    for number, (knots_u, knots_v, weights, points) in enumerate(_outward_nets(faces), 1):
        if _single_span(knots_u, points.shape[0]) and _single_span(knots_v, points.shape[1]):
            patches, patch_weights = by_shape.setdefault(points.shape[:2], ([], []))
            patches.append(points)
            patch_weights.append(weights)
            continue
        if not _is_piece(knots_u, knots_v, points):
            raise MeshInputError(str(path), f"face {number}: the B-spline surface has interior knots and is not a merged "
                                 "c1surf surface (degree (2, 2), knots 0 0 0 1 ... m m m): c1surf reads only such "
                                 "surfaces and single Bezier patches")
        quad, quad_weights = by_shape[(3, 3)]
        m, n = points.shape[0] - 2, points.shape[1] - 2
        piece = MergedPiece(points, weights, knots_u, knots_v, len(quad) + np.arange(m * n).reshape(m, n),
                            np.zeros((m, n), dtype=np.int64))
        cut, cut_weights = piece_patches(piece)
        pieces.append(piece)
        quad.extend(cut)
        quad_weights.extend(cut_weights)
    return _patch_set(path, by_shape, pieces)


def _read_faces(path) -> list:
    """(knots_u, knots_v, weights (nu, nv), points (nu, nv, 3), solid) of every face (``step_faces.face_nets``),
    read by Open CASCADE in a child process: its crash, signal or time limit is one ``MeshInputError`` line."""
    if not os.path.exists(path):
        raise MeshInputError(str(path), "no such file")
    if os.path.isdir(path):
        raise MeshInputError(str(path), "is a directory, not a patch file")
    if not CONTAINED:
        return face_nets(path)
    if not _has_open_cascade():  # said here: importing Open CASCADE to find out takes seconds
        raise MeshInputError(str(path), READ_HINT)
    refuse_huge_reals(path)  # before Open CASCADE sees them: a real of 1e100 keeps it busy for minutes
    base, per_mb = _LIMIT_SECONDS
    limit = base + per_mb * os.path.getsize(path) / 1e6
    _, arrays = call_contained(_FACE_MODULE, "Open CASCADE", "face_arrays", path, limit=limit)
    return unpack_faces(*arrays)


def _nets_by_size(faces: list):
    """The faces' control points and weights stacked by net size: lists of (P, n, 3) and (P, n) arrays."""
    sizes: dict = {}
    for _, _, weights, points, _ in faces:
        entry = sizes.setdefault(weights.size, ([], []))
        entry[0].append(points.reshape(-1, 3))
        entry[1].append(weights.ravel())
    return [np.stack(p) for p, _ in sizes.values()], [np.stack(w) for _, w in sizes.values()]


def _has_open_cascade() -> bool:
    try:
        return importlib.util.find_spec("OCP") is not None
    except (ImportError, ValueError):
        return False


def _is_piece(knots_u: np.ndarray, knots_v: np.ndarray, points: np.ndarray) -> bool:
    """Whether knots and net (nu, nv, 3) are those of a c1surf merged piece (degree (2, 2), knots 0 0 0 1 ... m m m)."""
    return (points.shape[0] >= 3 and is_piece_knots(knots_u) and is_piece_knots(knots_v)
            and knots_u.size == points.shape[0] + 3 and knots_v.size == points.shape[1] + 3)


def _outward_nets(faces: list) -> list:
    """The faces' (knots_u, knots_v, weights, points) with every solid turned outwards by c1surf's own volume.

    ``faces``: (knots_u, knots_v, weights (nu, nv), points (nu, nv, 3), solid) per face, ``solid`` the index of
    the solid it bounds (-1: none). Open CASCADE's STEP reader heals every solid
    (``ShapeFix_Solid::SolidFromShell``) and reverses its shell where its ray
    classifier (``BRepClass3d_SolidClassifier::PerformInfinitePoint``) finds the
    point at infinity inside; that classifier errs on some closed B-reps (boot
    fitted at 300 faces, written in strips: every face came back transposed).
    Here a solid whose faces, as read, enclose a negative volume (Gauss rules
    exact for polynomial nets, :func:`_face_volumes`) has every face's u and v
    swapped back, so each solid's normals point out as the file's shell says.
    """
    solid = np.array([f[4] for f in faces], dtype=np.int64)
    if not np.any(solid >= 0):
        return [f[:4] for f in faces]
    volume = np.bincount(solid[solid >= 0], _face_volumes(faces)[solid >= 0])
    flipped = np.r_[volume < 0, False][solid].tolist()  # solid -1 is the appended False
    return [(kv, ku, w.T.copy(), p.transpose(1, 0, 2).copy()) if flip else (ku, kv, w, p)
            for (ku, kv, w, p, _), flip in zip(faces, flipped)]


def _face_volumes(faces: list) -> np.ndarray:
    """(F,) float: each face's share of its solid's signed volume, 1/3 of the integral of (x - o) . (x_u x x_v)
    over its Bezier spans (a B-spline face cut at its knots), o the centre of the nets' bounding box."""
    from ...evaluation.measure import gauss_rule, patch_frames

    nets = {}  # (nu, nv) -> (face numbers, nets, weights)
    for k, (knots_u, knots_v, weights, points, _) in enumerate(faces):
        if _single_span(knots_u, points.shape[0]) and _single_span(knots_v, points.shape[1]):
            cut, cut_weights = [points], [weights]
        elif _is_piece(knots_u, knots_v, points):
            m, n = points.shape[0] - 2, points.shape[1] - 2
            numbers, turns = np.arange(m * n).reshape(m, n), np.zeros((m, n), dtype=np.int64)
            cut, cut_weights = piece_patches(MergedPiece(points, weights, knots_u, knots_v, numbers, turns))
        else:
            continue  # refused with its own line afterwards
        entry = nets.setdefault(np.shape(cut[0])[:2], ([], [], []))
        entry[0].extend([k] * len(cut))
        entry[1].extend(cut)
        entry[2].extend(cut_weights)
    flat = np.concatenate([np.reshape(f[3], (-1, 3)) for f in faces])
    origin = 0.5 * (flat.min(axis=0) + flat.max(axis=0))
    volume = np.zeros(len(faces))
    for (nu, nv), (owner, points, weights) in nets.items():
        u, w = gauss_rule((3 * (max(nu, nv) - 1) + 1) // 2)
        for a in range(0, len(owner), _VOLUME_CHUNK):  # chunks of patches: bounded memory
            chunk = slice(a, a + _VOLUME_CHUNK)
            x, xu, xv = patch_frames(np.stack(points[chunk]), np.stack(weights[chunk]), u, u)
            flux = np.einsum("pabi,pabi->pab", x - origin, np.cross(xu, xv))
            volume += np.bincount(owner[chunk], np.einsum("pab,a,b->p", flux, w, w) / 3.0,
                                  minlength=len(faces))
    return volume


_VOLUME_CHUNK = 1 << 14  # patches per Gauss evaluation in _face_volumes


def _single_span(knots: np.ndarray, n_poles: int) -> bool:
    """Clamped knots of one Bezier span over ``n_poles`` poles: n_poles equal values, then n_poles equal values."""
    return knots.size == 2 * n_poles and np.all(knots[:n_poles] == knots[0]) and np.all(knots[n_poles:] == knots[-1])


def _patch_set(path, by_shape: dict, pieces: list) -> PatchSet:
    """The PatchSet of the patches by shape (biquadratic first, then by degree) and the merged pieces."""
    shapes = [(3, 3)] + sorted(k for k in by_shape if k != (3, 3) and by_shape[k][0])
    groups = [np.stack(by_shape[k][0]) for k in shapes if by_shape[k][0]]
    weights = [np.stack(by_shape[k][1]) for k in shapes if by_shape[k][0]]
    if not groups:
        raise MeshInputError(str(path), "the STEP file holds no faces: c1surf reads B-spline and Bezier faces")
    rational = any(not np.all(w == w.flat[0]) for w in weights)
    if not rational:
        pieces = [MergedPiece(p.points, None, p.knots_u, p.knots_v, p.patches, p.rotation) for p in pieces]
    header = {"format": "step", "input": {"path": str(path)}, "counts": {"patches": int(sum(len(g) for g in groups))},
              "ordered": False}  # faces come in shell order, not in patch order: diff pairs them by their centres
    return PatchSet(groups, None, None, None, header, weights if rational else None, pieces)


_HEAD_BYTES = 1 << 16  # the header and the first entities (the PRODUCT) of a STEP file


def _fix_header(path, name: str) -> None:
    """Pin FILE_NAME's name and time stamp and the product name.

    Open CASCADE may put the clock and the temporary file name in the header,
    and numbers product names with a per-process counter; neither belongs in
    a reproducible file. Both are near the top: the first 64 KiB are fixed
    and the rest copied after them by blocks (never the whole file in memory).
    """
    import shutil

    with open(path, "rb") as f:
        head = f.read(_HEAD_BYTES)
    text = head.decode("latin-1")
    quoted = _step_string(name)
    fixed = re.sub(r"FILE_NAME\('(?:[^']|'')*','[^']*'", lambda m: f"FILE_NAME({quoted},'1970-01-01T00:00:00'", text, count=1)
    product = _step_string(os.path.splitext(name)[0] or "c1surf")
    fixed = re.sub(r"= PRODUCT\('(?:[^']|'')*',\s*'(?:[^']|'')*'", lambda m: f"= PRODUCT({product},{product}", fixed, count=1)
    if fixed == text:
        return
    fixed_path = os.fspath(path) + ".h"
    try:
        with open(path, "rb") as source, open(fixed_path, "wb") as target:
            target.write(fixed.encode("latin-1"))
            source.seek(len(head))
            shutil.copyfileobj(source, target, 1 << 20)
        os.replace(fixed_path, path)
    finally:
        if os.path.exists(fixed_path):
            os.remove(fixed_path)


def _step_string(text: str) -> str:
    """A STEP string literal (ASCII, apostrophes doubled)."""
    text = text.encode("ascii", "replace").decode("ascii").replace("'", "''")
    return f"'{text}'"


__all__ = ["write_patch_set_step", "read_patch_set_step", "write_step_shape"]
