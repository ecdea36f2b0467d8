"""QuadriFlow's quad remesh (Huang, Zhou, Niessner, Shewchuk, Guibas 2018) through ``pyquadriflow``'s library.

QuadriFlow solves for a cross field and a position field as Instant Meshes does, then repairs the singularities of
the integer position field by a minimum-cost flow, so its quads have far fewer irregular vertices at the same size
(issue 43's survey: an animal at about 3,000 faces, 110 against Instant Meshes' 182-249). Each irregular vertex of
valence n costs n CAD faces (A3's bicubic patches join the biquadratic complex G1, not C1), so that is the lever on
the STEP face count. It does not resolve parts thinner than its edge and may not keep every rim: ``control_mesh``
takes its layout only where the scan's topology and coverage checks pass.

``pyquadriflow``'s own wrapper copies the arrays through Python lists (15 s for a 12,000-face remesh); here its
library is called on the numpy buffers directly (``remesh_quadriflow`` and ``free_mem``, the wrapper's ``MESH_DATA``
layout). Its wheel carries the library for Linux x86-64 and Windows only: ``available()`` says whether it loads.
"""
from __future__ import annotations

import ctypes
import functools
import time

import numpy as np

from ...console import quiet_stdout

__all__ = ["available", "quadriflow_remesh"]

SEED = 0  # QuadriFlow's random seed: the same remesh every run


class _MeshData(ctypes.Structure):
    """``pyquadriflow``'s ``MESH_DATA``: the remesh the library returns (freed by ``free_mem``)."""

    _fields_ = [("nn_verts", ctypes.c_int), ("nn_faces", ctypes.c_int),
                ("vertices", ctypes.POINTER(ctypes.c_float * 3)), ("faces", ctypes.POINTER(ctypes.c_int * 4)),
                ("has_error", ctypes.c_bool), ("str_error", ctypes.c_char_p)]


@functools.lru_cache(maxsize=1)
def _library():
    """The loaded library with its two functions typed, or None where it does not load (no wheel library for the
    platform, or pyquadriflow not installed)."""
    try:
        from pyQuadriFlow.clib.load_library import load_library

        library = load_library()
    except Exception:  # ImportError, or the wrapper's unbound name on platforms without a library
        return None
    remesh = library.remesh_quadriflow
    remesh.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.POINTER(ctypes.c_float * 3),
                       ctypes.POINTER(ctypes.c_int * 3)] + [ctypes.c_bool] * 5
    remesh.restype = ctypes.POINTER(_MeshData)
    library.free_mem.argtypes = [ctypes.POINTER(_MeshData)]
    return library


def available() -> bool:
    """Whether QuadriFlow's library loads here."""
    return _library() is not None


def quadriflow_remesh(points: np.ndarray, triangles: np.ndarray, faces: int, sharp: bool = False):
    """QuadriFlow's pure-quad remesh of a triangle mesh, about ``faces`` quads, rims kept as rims.

    Parameters
    ----------
    points : (m, 3) float; triangles : (t, 3) int, a manifold
    faces : int > 0, the quads asked for (QuadriFlow returns 70-95 % of it, measured on the shared scans)

    Returns
    -------
    quad_points : (V, 3) float64; quads : (F, 4) int64; seconds : float

    Raises RuntimeError when the library is not available or reports an error.
    """
    library = _library()
    if library is None:
        raise RuntimeError("QuadriFlow's library does not load here (pyquadriflow: Linux x86-64 and Windows only)")
    start = time.perf_counter()
    vertices = np.ascontiguousarray(points, dtype=np.float32)
    corners = np.ascontiguousarray(triangles, dtype=np.int32)
    with quiet_stdout():
        result = library.remesh_quadriflow(
            int(faces), SEED, vertices.shape[0], corners.shape[0],
            vertices.ctypes.data_as(ctypes.POINTER(ctypes.c_float * 3)),
            corners.ctypes.data_as(ctypes.POINTER(ctypes.c_int * 3)),
            bool(sharp), True, False, False, False)  # sharp features, boundaries, adaptive scale, aggressive SAT, min-cost flow
    data = result.contents
    try:
        if data.has_error:
            raise RuntimeError(f"QuadriFlow failed: {(data.str_error or b'').decode('ascii', 'replace')}")
        n, f = data.nn_verts, data.nn_faces
        if n == 0 or f == 0:
            return np.zeros((0, 3)), np.zeros((0, 4), dtype=np.int64), time.perf_counter() - start
        quad_points = np.ctypeslib.as_array(ctypes.cast(data.vertices, ctypes.POINTER(ctypes.c_float)), (n * 3,))
        quads = np.ctypeslib.as_array(ctypes.cast(data.faces, ctypes.POINTER(ctypes.c_int)), (f * 4,))
        quad_points = quad_points.reshape(n, 3).astype(np.float64)
        quads = quads.reshape(f, 4).astype(np.int64)
    finally:
        library.free_mem(result)
    return quad_points, quads, time.perf_counter() - start
