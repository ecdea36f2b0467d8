"""What native code prints on the process's standard output, kept off it (Open CASCADE's transfer statistics,
Instant Meshes' progress): c1surf's standard output carries only its reports and files (``-o -``)."""
from __future__ import annotations

import contextlib
import os
import sys

__all__ = ["quiet_stdout"]


@contextlib.contextmanager
def quiet_stdout():
    """Send file descriptor 1 to /dev/null for the block, C++ output included; Python's buffered output is
    flushed first. Nothing is silenced where the process has no file descriptor 1."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError, AttributeError):
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
