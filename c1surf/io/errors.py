"""Errors raised by the c1surf readers and writers.

Every error carries the file it is about and, where known, the 1-based
line, and prints as ``PATH:LINE: message`` (or ``PATH: message``) so the
CLI can show it as one line that editors and terminals can jump to.
Messages say what is wrong and what to do about it.
"""

from __future__ import annotations

from ..errors import C1SurfFileError, MeshInputError

__all__ = ["C1SurfFileError", "MeshInputError", "OutputError"]


class OutputError(C1SurfFileError):
    """An output file cannot (or must not) be written."""

    def __init__(self, path, message: str):
        super().__init__(path, message, None)
        # Keep args equal to the constructor's so pickling round-trips.
        self.args = (self.path, message)
