"""Errors raised by the c1surf readers and writers.

Every error carries the file it is about and, where known, the 1-based
line, and prints as ``PATH:LINE: message`` (or ``PATH: message``) so the
CLI can show it as one line that editors and terminals can jump to.
Messages say what is wrong and what to do about it.
"""

from __future__ import annotations

import os

__all__ = ["C1SurfFileError", "MeshInputError", "OutputError"]


class C1SurfFileError(Exception):
    """Base class: a problem with a named file, optionally at a line.

    Parameters
    ----------
    path : str or os.PathLike
        The file the problem is about.
    message : str
        One line: what is wrong and what to do.
    line : int or None
        1-based line number in ``path``, or None when not applicable.

    Attributes
    ----------
    path : str
    message : str
    line : int or None
    """

    def __init__(self, path, message: str, line: int | None = None):
        path = os.fspath(path)
        line = None if line is None else int(line)
        # args mirror the signature so the exception pickles (multiprocessing).
        super().__init__(path, message, line)
        self.path = path
        self.message = message
        self.line = line

    def __str__(self) -> str:
        if self.line is None:
            return f"{self.path}: {self.message}"
        return f"{self.path}:{self.line}: {self.message}"


class MeshInputError(C1SurfFileError):
    """An input mesh file cannot be read or is not a valid polygon mesh."""


class OutputError(C1SurfFileError):
    """An output file cannot (or must not) be written."""

    def __init__(self, path, message: str):
        super().__init__(path, message, None)
        # Keep args equal to the constructor's so pickling round-trips.
        self.args = (self.path, message)
