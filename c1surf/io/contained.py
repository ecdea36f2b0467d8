"""Foreign code in a child process: a crash, a signal or a hang there becomes one line about the file (issue 42).

Open CASCADE's STEP reader crashes the process on some malformed entity graphs (a segmentation fault, nothing
printed). Its reading therefore runs in a child (``python -m c1surf.io.contained MODULE``) that is started on
first use and kept for the next reads of the same process (warm: Open CASCADE's libraries are loaded once).
The child answers each request with plain numpy arrays in NumPy's ``.npy`` format (``allow_pickle=False``
both ways: nothing the child sends is executed) and a JSON header; its standard output and error go nowhere,
so no library prints on c1surf's. A child that dies (a signal, an abort) or outlives its time limit is
replaced, and the read is refused with one ``MeshInputError`` line naming the file.

Protocol, one request at a time: the parent writes ``length (8 bytes, little-endian) + JSON [function,
args]`` to the child's stdin; the child answers ``length + JSON header + .npy arrays`` on its own copy of the
original stdout. The header is ``{"arrays": n, ...}`` or ``{"error": message, "line": line}`` (a
``C1SurfFileError`` raised in the child, re-raised here with the parent's path).
"""
from __future__ import annotations

import atexit
import importlib
import io
import json
import os
import select
import signal
import struct
import subprocess
import sys
import threading
import time

import numpy as np

from .errors import C1SurfFileError, MeshInputError

__all__ = ["ContainedCrash", "ContainedModule", "call_contained"]

_LENGTH = struct.Struct("<Q")


class ContainedCrash(MeshInputError):
    """The child died or ran out of time on a file: one line, the file refused."""


class ContainedModule:
    """A child process that imports ``module`` and runs its functions on request (one at a time, thread-safe).

    ``call(function, args, path=..., limit=seconds)`` runs ``module.function(*args)`` (JSON-able arguments) in
    the child, which returns ``(header: dict, arrays: list of ndarray)``; the parent gets the same back, or a
    one-line error about ``path``. ``what`` names the foreign code in messages ("Open CASCADE").
    """

    def __init__(self, module: str, what: str):
        self.module, self.what = module, what
        self._child = None
        self._owner = None  # the pid that started the child (a forked copy of this process starts its own)
        self._lock = threading.Lock()

    def call(self, function: str, args: list, *, path, limit: float):
        with self._lock:
            child = self._running()
            request = json.dumps([function, list(args)]).encode()
            try:
                child.stdin.write(_LENGTH.pack(len(request)) + request)
                child.stdin.flush()
                payload = _read_frame(child.stdout, time.monotonic() + limit)
            except (BrokenPipeError, EOFError, OSError) as error:
                raise self._failure(path, limit, timed_out=isinstance(error, TimeoutError)) from None
            except BaseException:  # Ctrl-C, SIGTERM, a caller's alarm: the child may be mid-answer, so it goes
                self._child.kill()
                self._forget()
                raise
        return _decode(path, payload)

    def _running(self):
        if self._child is not None and (self._owner != os.getpid() or self._child.poll() is not None):
            self._forget()
        if self._child is None:
            self._child = subprocess.Popen([sys.executable, "-m", __name__, self.module], stdin=subprocess.PIPE,
                                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, close_fds=True)
            self._owner = os.getpid()
        return self._child

    def _failure(self, path, limit: float, timed_out: bool) -> ContainedCrash:
        """The line for a child that timed out or died; the child is gone afterwards (the next call starts one)."""
        child = self._child
        if timed_out:
            child.kill()
        try:
            status = child.wait(timeout=10)
        except subprocess.TimeoutExpired:
            child.kill()
            status = child.wait()
        self._forget()
        if timed_out:
            return ContainedCrash(path, f"{self.what} took more than {limit:.0f} s reading the file and was stopped: "
                                        "the file is damaged or far larger than it looks; c1surf refuses it")
        ended = f"signal {signal.Signals(-status).name}" if status < 0 and -status in signal.valid_signals() \
            else f"exit status {status}"
        ended += ", out of memory?" if status == -signal.SIGKILL else ""
        return ContainedCrash(path, f"{self.what} crashed reading the file ({ended}): the file is damaged or holds "
                                    "what it cannot read; c1surf refuses it (nothing was written)")

    def _forget(self) -> None:
        child, self._child = self._child, None
        if child is not None and self._owner == os.getpid():
            _close(child)

    def close(self) -> None:
        with self._lock:
            self._forget()


def _close(child) -> None:
    for stream in (child.stdin, child.stdout):
        try:
            stream.close()
        except OSError:
            pass
    try:
        child.wait(timeout=2)
    except subprocess.TimeoutExpired:
        child.kill()
        child.wait()


def _read_frame(stream, deadline: float) -> bytes:
    """One length-prefixed frame from ``stream`` (a pipe), or TimeoutError past ``deadline``, EOFError at its end."""
    fd = stream.fileno()
    head = _read_exactly(fd, _LENGTH.size, deadline)
    return _read_exactly(fd, _LENGTH.unpack(head)[0], deadline)


def _read_exactly(fd: int, n: int, deadline: float) -> bytes:
    parts, got = [], 0
    while got < n:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            raise TimeoutError
        part = os.read(fd, min(n - got, 1 << 20))
        if not part:
            raise EOFError
        parts.append(part)
        got += len(part)
    return b"".join(parts)


def _decode(path, payload: bytes):
    """(header, arrays) of a child's answer; its error re-raised as the parent's ``MeshInputError``."""
    stream = io.BytesIO(payload)
    header = json.loads(stream.readline())
    if "error" in header:
        raise MeshInputError(path, header["error"], header.get("line"))
    arrays = [np.lib.format.read_array(stream, allow_pickle=False).copy() for _ in range(int(header["arrays"]))]
    return header, arrays


def _answer(module, request: bytes) -> bytes:
    """The child's answer to one request: header and arrays, or the error line of a refused file."""
    function, args = json.loads(request)
    try:
        header, arrays = getattr(module, function)(*args)
        header = {**header, "arrays": len(arrays)}
    except C1SurfFileError as error:
        header, arrays = {"error": error.message, "line": error.line}, []
    except MemoryError:
        header, arrays = {"error": "out of memory reading the file", "line": None}, []
    except Exception as error:  # a bug in c1surf's own code around the foreign reader: still one line
        said = " ".join(str(error).split())[:300]  # one line, whatever the foreign code's message holds
        header, arrays = {"error": f"could not be read ({type(error).__name__}: {said}); please report it",
                          "line": None}, []
    out = io.BytesIO()
    out.write(json.dumps(header).encode() + b"\n")
    for array in arrays:
        np.lib.format.write_array(out, np.ascontiguousarray(array), allow_pickle=False)
    return out.getvalue()


def serve(module_name: str) -> None:
    """The child's loop: requests on stdin, answers on the original stdout; anything printed goes nowhere."""
    answers = os.fdopen(os.dup(1), "wb")
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.dup2(null, 2)
    requests = sys.stdin.buffer
    module = importlib.import_module(module_name)
    while True:
        head = requests.read(_LENGTH.size)
        if len(head) < _LENGTH.size:
            return
        payload = _answer(module, requests.read(_LENGTH.unpack(head)[0]))
        answers.write(_LENGTH.pack(len(payload)) + payload)
        answers.flush()


_MODULES: dict = {}


def call_contained(module: str, what: str, function: str, path, *args, limit: float):
    """``module.function(path, *args)`` in this process's child for ``module`` (started on first use):
    ``(header, arrays)``, or a one-line ``MeshInputError`` on ``path`` (the child's refusal, crash or timeout)."""
    if module not in _MODULES:
        _MODULES[module] = ContainedModule(module, what)
    return _MODULES[module].call(function, [os.fspath(path), *args], path=path, limit=limit)


@atexit.register
def _close_all() -> None:
    for contained in _MODULES.values():
        contained.close()


if __name__ == "__main__":
    serve(sys.argv[1])
