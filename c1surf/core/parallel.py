"""Threads over blocks of rows, for the loops whose numpy calls release the GIL.

Gathers (``np.take``), BLAS products and elementwise arithmetic on large
arrays run without the GIL, so the blocked loops of the construction and the
tessellation split their blocks between a few threads. Each thread gets one
contiguous range of blocks and its own scratch buffers; results go to
disjoint slices of a preallocated output, so no locking is needed.

``C1SURF_THREADS`` sets the number of threads (default: the CPUs this process
may use, at most 8; 1 turns threading off).
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

_pool: ThreadPoolExecutor | None = None


def thread_count() -> int:
    """Threads to use: ``C1SURF_THREADS`` or the usable CPUs (at most 8)."""
    value = os.environ.get("C1SURF_THREADS", "")
    if value.strip().isdigit() and int(value) > 0:
        return int(value)
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cpus = os.cpu_count() or 1
    return max(1, min(cpus, 8))


def for_each_range(n: int, work, minimum: int = 1 << 16) -> None:
    """Call ``work(start, stop)`` on consecutive ranges covering 0..n, in threads.

    Parameters
    ----------
    n : int, rows to cover
    work : callable(start, stop), fills rows start:stop of some output (and only those)
    minimum : int, fewer rows than this per thread are not worth a thread
    """
    global _pool
    threads = min(thread_count(), max(1, n // minimum))
    if threads == 1:
        work(0, n)
        return
    if _pool is None or _pool._max_workers < threads:
        _pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="c1surf")
    bounds = [n * k // threads for k in range(threads + 1)]
    # the blocks' matrix products are small: BLAS threads would only spin against ours
    with _single_threaded_blas(_blas_threads()):
        futures = [_pool.submit(work, bounds[k], bounds[k + 1]) for k in range(threads)]
        for future in futures:
            future.result()  # re-raises a worker's exception here
_blas_lock = threading.Lock()
_blas_users = [0, None]  # calls inside _single_threaded_blas, BLAS threads before the first of them


@contextmanager
def _single_threaded_blas(blas):
    """BLAS on one thread inside; the count before is restored when the last concurrent user leaves."""
    if blas is None:
        yield
        return
    with _blas_lock:
        if _blas_users[0] == 0:
            _blas_users[1] = blas[0]()
            blas[1](1)
        _blas_users[0] += 1
    try:
        yield
    finally:
        with _blas_lock:
            _blas_users[0] -= 1
            if _blas_users[0] == 0:
                blas[1](_blas_users[1])


_BLAS_SYMBOLS = [("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
                 ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
                 ("openblas_get_num_threads64_", "openblas_set_num_threads64_"),
                 ("openblas_get_num_threads", "openblas_set_num_threads")]
_blas_cache: list = []


def _blas_threads():
    """(get, set) of the number of threads of the OpenBLAS numpy has loaded, or None (other BLAS, not Linux)."""
    if not _blas_cache:
        _blas_cache.append(None)
        try:
            import ctypes

            with open("/proc/self/maps", encoding="utf-8", errors="replace") as maps:
                paths = sorted({line.split()[-1] for line in maps if "openblas" in line.lower() and "/" in line})
            for path in paths:
                lib = ctypes.CDLL(path)  # the loaded library again (dlopen of a loaded path does not reload it)
                for get_name, set_name in _BLAS_SYMBOLS:
                    if hasattr(lib, get_name) and hasattr(lib, set_name):
                        get, set_ = getattr(lib, get_name), getattr(lib, set_name)
                        get.restype, set_.argtypes = ctypes.c_int, [ctypes.c_int]
                        _blas_cache[0] = (get, set_)
                        return _blas_cache[0]
        except (OSError, AttributeError):
            pass
    return _blas_cache[0]
