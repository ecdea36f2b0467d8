"""Threads over blocks of rows, for the loops whose numpy calls release the GIL.

Gathers (``np.take``), BLAS products and elementwise arithmetic on large
arrays run without the GIL, so the blocked loops of the construction, the
adjacency and the tessellation share one pool of threads: ``run_tasks`` for
independent tasks, ``for_each_range`` for one contiguous range of rows per
thread. Tasks write disjoint slices of preallocated outputs, so no locking is
needed.

``C1SURF_THREADS`` sets the number of threads (default: the CPUs this process
may use, at most 8; 1 turns threading off).
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from functools import partial

_PREFIX = "c1surf"


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


def run_tasks(tasks, uses_blas: bool = False) -> list:
    """Call independent ``tasks`` (each writes only its own rows) on the shared pool.

    Parameters
    ----------
    tasks : list of callables without arguments
    uses_blas : bool, the tasks make (small) matrix products: BLAS is held to one
        thread meanwhile, since its threads would only spin against ours (measured
        5x slower when the other core is busy); where that cannot be done (not
        OpenBLAS) the tasks run one after another

    Returns
    -------
    list, the tasks' results in order
    """
    blas = _blas_threads() if uses_blas else None
    workers = min(thread_count(), len(tasks))
    if (uses_blas and blas is None) or threading.current_thread().name.startswith(_PREFIX):
        workers = 1  # no BLAS control, or already on one of our threads (no oversubscription)
    if workers <= 1:
        return [task() for task in tasks]
    # a pool per call: its threads, and the work arrays they keep (tessellate._work), end with it
    pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix=_PREFIX)
    try:
        with _single_threaded_blas(blas):
            return [future.result() for future in [pool.submit(task) for task in tasks]]  # re-raises errors
    finally:
        pool.shutdown(wait=True, cancel_futures=True)  # after an error or an interrupt, skip the tasks not started


def for_each_range(n: int, work, minimum: int = 1 << 16, uses_blas: bool = False) -> None:
    """Call ``work(start, stop)`` on consecutive ranges covering 0..n, one per thread.

    Parameters
    ----------
    n : int, rows to cover
    work : callable(start, stop), fills rows start:stop of some output (and only those)
    minimum : int, fewer rows than this per thread are not worth a thread
    uses_blas : bool, as for ``run_tasks``
    """
    bounds = ranges_of(n, minimum)
    run_tasks([partial(work, bounds[k], bounds[k + 1]) for k in range(len(bounds) - 1)], uses_blas)


def ranges_of(n: int, minimum: int = 1 << 16) -> list:
    """The bounds of ``for_each_range``'s ranges: [0, ..., n], one range per thread."""
    threads = min(thread_count(), max(1, n // minimum))
    return [n * k // threads for k in range(threads + 1)]


@contextmanager
def blas_on_one_thread(hold: bool = True):
    """Hold BLAS to one thread inside (when ``hold`` and the BLAS can be told), as ``run_tasks`` does for its
    tasks: a product computed alone then gives the bits it gives inside those tasks."""
    with _single_threaded_blas(_blas_threads() if hold else None):
        yield


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
    if not _blas_cache:  # only a found library is remembered: numpy may load OpenBLAS after a first call
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
                        _blas_cache.append((get, set_))
                        return _blas_cache[0]
        except (OSError, AttributeError):
            pass
        return None
    return _blas_cache[0]
