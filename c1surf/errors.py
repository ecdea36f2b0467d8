"""Errors every layer raises about a named input (a file, at a line where known), and resource refusals.

Every ``C1SurfFileError`` carries the file it is about and, where known, the 1-based
line, and prints as ``PATH:LINE: message`` (or ``PATH: message``) so the
CLI can show it as one line that editors and terminals can jump to.
Messages say what is wrong and what to do about it. They live here, below the
layers, because the input preparation (``c1surf.prepare``) refuses meshes too.
"""

from __future__ import annotations

import os

__all__ = ["C1SurfFileError", "MeshInputError", "ResourceRefusal", "OptionError"]


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


class ResourceRefusal(Exception):
    """Work refused before it starts because it would not fit (memory, disk): ``message`` says what to do."""

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message


class OptionError(ValueError):
    """An option value or combination the construction or the preparation cannot take (``SurfaceOptions.check``,
    ``InputOptions.check``): a usage error on the command line."""
