"""The one resource guard: refuse work that would not fit in memory or on the disk, before it starts.

Every command asks here (``check_memory``, ``check_disk_space``) with its own estimate; a refusal is a
``ResourceRefusal`` whose message says what to do, which the command line prints as its one error line.
The estimates of a tessellation live here too (``tessellation_bytes``); the bytes a file of each format takes are
facts of its format (``io.registry.Format``).
"""
from __future__ import annotations

import os
import shutil

from .errors import ResourceRefusal

__all__ = ["available_memory", "check_memory", "check_disk_space", "tessellation_bytes", "ResourceRefusal",
           "BYTES_PER_PATCH", "BYTES_PER_SAMPLE", "WRITER_HEADROOM", "STREAMED_BYTES_PER_SAMPLE",
           "MEMORY_SHARE", "MEMORY_LIMIT_VARIABLE"]

# Peak memory of a tessellation, traced with tracemalloc on spot_quadrangulated (46,848 patches):
# 465 bytes per patch at N = 2, 4,436 at N = 8, 40,950 at N = 24, i.e. about
# BYTES_PER_PATCH + BYTES_PER_SAMPLE * N^2, times WRITER_HEADROOM for the mesh writers.
BYTES_PER_PATCH = 220
BYTES_PER_SAMPLE = 72
WRITER_HEADROOM = 1.1
# A streamed conversion holds, besides the surface, the sample matrices of both patch degrees
# ((S d) x (N^2 d) and 2 (S x N^2) float64 for S = 9 and 16 control points, d = 3: 2,200 bytes per
# sample) and one block of at least one patch: counted from the array shapes, as 2,400 bytes per sample.
STREAMED_BYTES_PER_SAMPLE = 2400
MEMORY_SHARE = 0.8  # of the available memory, the most any estimate may take
MEMORY_LIMIT_VARIABLE = "C1SURF_MEMORY_LIMIT"  # bytes (suffix K, M or G) c1surf may take, instead of MemAvailable


def available_memory() -> int:
    """Bytes of memory c1surf may take: ``C1SURF_MEMORY_LIMIT`` (e.g. 500M, 2G) where set, else the system's
    MemAvailable, else 8 GiB."""
    limit = os.environ.get(MEMORY_LIMIT_VARIABLE, "").strip().upper()
    if limit:
        scale = {"K": 1 << 10, "M": 1 << 20, "G": 1 << 30}.get(limit[-1], 1)
        try:
            return int(float(limit.rstrip("KMG")) * scale)
        except ValueError:
            pass
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 8 << 30


def check_memory(needed: float, work: str, advice: str, force: bool | None = False, detail: str = "") -> None:
    """Refuse ``work`` whose ``needed`` bytes exceed ``MEMORY_SHARE`` of the available memory.

    The message: ``{work} would need about X GiB{detail} but about Y GiB is available: {advice}``, and
    ", or pass --force to try anyway" unless ``force`` is None (a command without --force).
    """
    available = available_memory()
    if needed > MEMORY_SHARE * available and not force:
        retry = "" if force is None else ", or pass --force to try anyway"
        raise ResourceRefusal(f"{work} would need about {needed / 2**30:.1f} GiB{detail} but about "
                              f"{available / 2**30:.1f} GiB is available: {advice}{retry}")


def check_disk_space(paths, sizes, force: bool) -> None:
    """Refuse, before writing, outputs whose estimated ``sizes`` [(suffix, bytes)] exceed the free space where
    ``paths`` go. Files on one file system add up; a folder that does not exist is left to the writer."""
    totals: dict = {}
    free: dict = {}
    for path, (_, size) in zip(paths, sizes):
        folder = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(folder):
            continue
        device = os.stat(folder).st_dev
        totals[device] = totals.get(device, 0) + size
        free.setdefault(device, shutil.disk_usage(folder).free)
    for device, total in totals.items():
        if total > free[device] and not force:
            raise ResourceRefusal(f"the output files would take about {total / 2**20:.1f} MiB but only "
                                  f"{free[device] / 2**20:.1f} MiB is free there: free some space, write elsewhere, "
                                  "or pass --force to try anyway")


def tessellation_bytes(n_patches: int, resolution: int) -> float:
    """Estimated peak memory (bytes) of tessellating and writing ``n_patches`` at ``resolution`` (see the constants)."""
    return n_patches * (BYTES_PER_PATCH + BYTES_PER_SAMPLE * resolution * resolution) * WRITER_HEADROOM
