"""Memory the process keeps after freeing it (glibc), given back where a large conversion needs it to be."""
from __future__ import annotations

import ctypes

__all__ = ["return_freed_memory"]


def return_freed_memory() -> None:
    """Give the pages of freed memory back to the system (glibc's ``malloc_trim``; nothing where there is none).

    The command line has glibc keep freed memory for reuse (``cli.runtime.tune_allocator``: every array from
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
