"""The writers' last line of defence: no NaN or infinity ever reaches an output file.

Every mesh, patch and image writer calls ``refuse_non_finite`` on the numbers it is about
to write (streamed writers on each block) before the bytes go out; ``atomic_output`` then
removes the temporary file and names the final output, so a bug upstream becomes a
one-line refusal instead of a file of NaN.
"""
from __future__ import annotations

import numpy as np

from .errors import OutputError

__all__ = ["NonFiniteOutput", "refuse_non_finite", "refuse_non_finite_mesh", "refuse_non_finite_patch_set", "refuse_non_finite_vertices"]

_CHUNK = 1 << 20  # elements tested at a time: the mask of a 10 M-point array is never whole in memory


class NonFiniteOutput(OutputError):
    """A writer was given NaN or infinite numbers (or numbers its file's float type cannot hold)."""


def refuse_non_finite(values, what: str, path="output", dtype=None, allow_positive_infinity: bool = False) -> None:
    """Raise ``NonFiniteOutput`` unless every number of ``values`` is finite (and fits ``dtype``).

    Parameters
    ----------
    values : array_like of any shape (None and integer arrays pass: they cannot hold NaN)
    what : str, what the numbers are, plural ("vertex positions", "control points")
    path : the file being written (``atomic_output`` replaces a temporary name by the output's)
    dtype : the float type written (np.float32 for --float32): values beyond its range would become infinite
    allow_positive_infinity : +inf is a value of the format (an EXR depth channel's background)
    """
    if values is None:
        return
    array = np.asarray(values)
    if array.dtype.kind not in "fc" or array.size == 0:
        return
    limit = np.finfo(dtype).max if dtype is not None and np.dtype(dtype).kind == "f" else np.inf
    flat = array.reshape(-1)
    not_finite = beyond = 0
    for start in range(0, flat.size, _CHUNK):
        part = flat[start:start + _CHUNK]
        if array.dtype.kind == "c":
            part = np.concatenate([part.real, part.imag])
        finite = np.isfinite(part)
        if allow_positive_infinity:
            finite |= part == np.inf
        not_finite += int(part.size - np.count_nonzero(finite))
        if np.isfinite(limit) and not not_finite and (part.max() > limit or part.min() < -limit):  # two fast passes
            beyond += int(np.count_nonzero(np.abs(part) > limit))
    if not_finite:
        raise NonFiniteOutput(path, f"{not_finite} of the {flat.size} {what} to be written are NaN or infinite: "
                                    "nothing was written (this is a bug in c1surf unless the input holds such "
                                    "numbers; please report it)")
    if beyond:
        name = np.dtype(dtype).name
        raise NonFiniteOutput(path, f"{beyond} of the {flat.size} {what} to be written exceed the largest {name} "
                                    f"({limit:.3g}), the number type of this output (--float32, STL, GLB): write "
                                    "doubles (.ply or .obj without --float32) or scale the mesh down; nothing was "
                                    "written")


def refuse_non_finite_mesh(mesh, path, float32: bool = False) -> None:
    """``refuse_non_finite`` on every number of a ``io.meshes.write.TriangleMesh``: positions, normals,
    texture coordinates, colours and named properties (``float32``: the positions must fit a float32)."""
    refuse_non_finite_vertices(mesh.points, mesh.normals, path, np.float32 if float32 else None)
    refuse_non_finite(mesh.uv, "texture coordinates", path, np.float32)
    refuse_non_finite(mesh.colours, "colour values", path)
    for name, values in (mesh.properties or {}).items():
        refuse_non_finite(values, f"'{name}' values", path, np.float32)


def refuse_non_finite_vertices(points, normals, path, dtype=None) -> None:
    """``refuse_non_finite`` on a block of vertex positions and normals (the streamed writers, per block)."""
    refuse_non_finite(points, "vertex coordinates", path, dtype)
    refuse_non_finite(normals, "normal components", path, dtype)


def refuse_non_finite_patch_set(patch_set, path) -> None:
    """``refuse_non_finite`` on a ``evaluation.patch_set.PatchSet``: control points, weights, merged pieces."""
    for group in patch_set.groups:
        refuse_non_finite(group, "control point coordinates", path)
    for weights in patch_set.weights or ():
        refuse_non_finite(weights, "weights", path)
    for piece in patch_set.merged or ():
        refuse_non_finite(piece.points, "control point coordinates of merged pieces", path)
        refuse_non_finite(piece.weights, "weights of merged pieces", path)
        refuse_non_finite(piece.knots_u, "knots of merged pieces", path)
        refuse_non_finite(piece.knots_v, "knots of merged pieces", path)
