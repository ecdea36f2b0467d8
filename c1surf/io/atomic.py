"""Write output files atomically, and never over an input file."""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from pathlib import Path

from .errors import OutputError

__all__ = ["atomic_output"]

_PREFIX = ".tmp-c1surf-"


@contextlib.contextmanager
def atomic_output(path, inputs=()):
    """Give a temporary path to write; move it onto ``path`` on success.

    The temporary file lives in the same directory as ``path`` (so the
    final rename is atomic) and ends with ``path``'s name, suffix
    included, so writers that pick a format from the suffix still work:
    ``out/mesh.ply`` is written as ``out/.tmp-c1surf-1a2b3c4d.mesh.ply``.
    If the block raises (KeyboardInterrupt included) the temporary file
    is deleted and ``path`` is left as it was.

    Parameters
    ----------
    path : str or os.PathLike
        The final output file.
    inputs : iterable of str or os.PathLike
        Files being read; refusing to overwrite any of them (also through
        symlinks or hard links).

    Yields
    ------
    str
        The temporary path to write to (already created, empty).

    Raises
    ------
    OutputError
        ``path`` is one of ``inputs``, is a directory, or its directory
        does not exist or is not writable; or the block did not leave a
        file at the temporary path.
    """
    path_str = os.fspath(path) if isinstance(os.fspath(path), str) else os.fsdecode(path)
    target = _file_behind(Path(os.fspath(path)), path_str)
    _check_target(target, path_str, inputs)
    # ``made`` holds the temporary file's name from just before it is created, so an
    # interrupt (Ctrl-C, SIGTERM) at any point after that removes it as well.
    made = []
    try:
        tmp = _create_temporary(target, path_str, made)
        yield tmp
        _move_into_place(tmp, target, path_str)
    except BaseException as error:
        for name in made:
            with contextlib.suppress(OSError):
                os.unlink(name)
        if isinstance(error, OutputError) and error.path in made:  # a writer's refusal names the output, not the temporary
            raise type(error)(path_str, error.message) from None
        raise


def _file_behind(target: Path, path_str: str) -> Path:
    """The file ``target`` names: a symlink's final target (replaced in place, so the link stays a link), which
    must be a regular file or not exist yet; devices, pipes and sockets are refused (never replaced by a file)."""
    real = Path(os.path.realpath(target)) if target.is_symlink() else target
    try:
        mode = os.stat(real).st_mode
    except OSError:  # does not exist yet (or unreachable: _check_target says why)
        return real
    kinds = {stat.S_ISCHR: "a character device", stat.S_ISBLK: "a block device", stat.S_ISFIFO: "a named pipe",
             stat.S_ISSOCK: "a socket"}
    for test, kind in kinds.items():
        if test(mode):
            via = f" (through the symlink to {str(real)!r})" if real != target else ""
            raise OutputError(path_str, f"is {kind}{via}, not a regular file: c1surf writes regular files only; "
                                        "choose another output path")
    return real


def _temporary_name(directory: Path, name: str) -> Path:
    """``.tmp-c1surf-<random>.<name>`` in ``directory``, the start of ``name`` dropped as far as needed for the
    name to fit the file system's limit (NAME_MAX, 255 bytes) with the suffix kept."""
    head = f"{_PREFIX}{secrets.token_hex(4)}."
    try:
        limit = os.pathconf(directory, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        limit = 255
    while name and len(os.fsencode(head + name)) > limit:
        name = name[1:]
    return directory / (head + name)


def _create_temporary(target: Path, path_str: str, made: list) -> str:
    """Create an empty file named ``.tmp-c1surf-<random>.<name>`` beside ``target``; return its path.

    ``made`` gets the name before the file is created (and loses it again if the name is taken).
    """
    directory = target.parent
    for _ in range(100):  # name clashes are astronomically unlikely
        candidate = _temporary_name(directory, target.name)
        made.append(str(candidate))
        try:
            # 0o666 & ~umask, like any newly written file (mkstemp would
            # give 0o600).
            fd = os.open(candidate, os.O_WRONLY | os.O_CREAT | os.O_EXCL,
                         0o666)
        except FileExistsError:
            made.pop()  # somebody else's file
            continue
        except OSError as exc:
            made.pop()
            raise OutputError(
                path_str, f"cannot create a file in {str(directory)!r} "
                f"({exc.strerror or exc}): choose another output folder"
                ) from None
        os.close(fd)
        return str(candidate)
    raise OutputError(path_str, "cannot pick a temporary file name: "
                      f"clean up {_PREFIX}* files in the output folder")


def _move_into_place(tmp: str, target: Path, path_str: str) -> None:
    """Flush the finished temporary file and rename it onto ``target`` (keeping the permissions of a file replaced)."""
    if not os.path.isfile(tmp):
        raise OutputError(
            path_str, "the writer did not produce the temporary file: "
            "this is a bug in c1surf; please report it")
    if target.exists():
        os.chmod(tmp, stat.S_IMODE(os.stat(target).st_mode))
    _fsync(tmp)
    try:
        os.replace(tmp, target)
    except OSError as exc:
        raise OutputError(
            path_str, f"cannot move the finished file into place "
            f"({exc.strerror or exc}): check the output path") from None


def _check_target(target: Path, path_str: str, inputs) -> None:
    """Refuse outputs that would clobber an input or cannot be written."""
    resolved = target.resolve()
    for inp in inputs:
        inp_path = Path(os.fspath(inp))
        same = inp_path.resolve() == resolved
        if not same and target.exists() and inp_path.exists():
            with contextlib.suppress(OSError):
                same = os.path.samefile(inp_path, target)  # hard links
        if same:
            raise OutputError(
                path_str, f"the output would overwrite the input "
                f"{os.fspath(inp)!r}: choose a different output path")
    directory = target.parent
    if not directory.exists():
        raise OutputError(
            path_str, f"the output folder {str(directory)!r} does not "
            "exist: create it first or choose another output path")
    if not directory.is_dir():
        raise OutputError(
            path_str, f"{str(directory)!r} is not a folder: choose another "
            "output path")
    if target.is_dir():
        raise OutputError(
            path_str, "is a directory: give an output file name")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise OutputError(
            path_str, f"the output folder {str(directory)!r} is not "
            "writable: choose another output path")


def _fsync(path: str) -> None:
    """Flush the file to disk so the rename never exposes a partial file."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
