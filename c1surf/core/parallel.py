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
from concurrent.futures import ThreadPoolExecutor

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
    futures = [_pool.submit(work, bounds[k], bounds[k + 1]) for k in range(threads)]
    for future in futures:
        future.result()  # re-raises a worker's exception here
