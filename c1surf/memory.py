"""Memory the process keeps after freeing it (glibc): kept for reuse by the command line (``tune_allocator``),
given back where a large conversion needs it to be (``return_freed_memory``).

``tune_allocator`` is a process-wide setting the command line applies first (never on import of the library):

c1surf allocates and frees arrays of hundreds of megabytes in turn. glibc gives
each of them fresh pages from the kernel (mmap) and returns them on free, so
every phase pays the first-touch page faults again; on virtual machines whose
memory is backed lazily by the host this costs more than the arithmetic
(measured here: 0.25-2.3 s per GB fresh against 0.13 s per GB reused). Keeping
freed memory in the process lets later arrays reuse pages that are already
mapped. The peak resident memory is not raised by this: it is still set by the
largest set of arrays alive at once.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import sys

__all__ = ["return_freed_memory", "tune_allocator"]


def return_freed_memory() -> None:
    """Give the pages of freed memory back to the system (glibc's ``malloc_trim``; nothing where there is none).

    The command line has glibc keep freed memory for reuse (``tune_allocator``: every array from
    the heap, given back only above 1 GiB free at its top), and the library's arrays below glibc's mmap
    threshold live in its heaps anyway. Once the build is let go, what comes next is much smaller, so
    those pages are given back here. Measured on the 180k-quad torus: 812 MB after its Surface was
    dropped, 657 MB after the call, 340 MB once the topology went; on the 4,000,000-quad torus
    16.2 -> 12.9 -> 6.7 GB (0.02 to 0.7 s a call). The build of a large mesh calls it too, between
    its largest steps (``construction.topology.build_topology``): what one step freed is not resident beside the next one's
    arrays, which do not fit in its holes.
    """
    try:
        trim = ctypes.CDLL(None).malloc_trim
    except (OSError, AttributeError, TypeError):  # not glibc (TypeError: no CDLL(None) on Windows)
        return
    trim(0)


_M_TRIM_THRESHOLD = -1
_M_MMAP_MAX = -4
_M_ARENA_MAX = -8
_tuned = False


def tune_allocator() -> bool:
    """Make glibc keep freed memory for reuse (no-op elsewhere). Returns True if applied."""
    global _tuned
    if _tuned:
        return True
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False  # not glibc (e.g. musl)
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    # large blocks from the heap, not mmap; give memory back only when > 1 GiB is free at its top
    _tuned = bool(mallopt(_M_MMAP_MAX, 0)) and bool(mallopt(_M_TRIM_THRESHOLD, 1 << 30))
    # and one heap for every thread: glibc's per-thread arenas ignore M_MMAP_MAX for blocks larger than their
    # 64 MB heaps (mmap, then munmap on free) and unmap their emptied heaps, so the arrays the thread pool
    # allocates were fresh pages every time (strace: 2.4 GB unmapped while converting the 180,000-quad torus)
    _tuned = _tuned and bool(mallopt(_M_ARENA_MAX, 1))
    _no_huge_pages()
    return _tuned


def _no_huge_pages() -> None:
    """Stop numpy from asking for transparent huge pages on its large arrays.

    With the kernel's THP defrag set to "madvise" (a common default) every
    madvised fault may compact memory synchronously: measured here 2.0 s per
    fresh GB with huge pages against 0.35 s without, and no gain afterwards.
    """
    import numpy as np

    setter = getattr(getattr(np, "_core", np.core).multiarray, "_set_madvise_hugepage", None)
    if setter is not None:
        setter(False)
