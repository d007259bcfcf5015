"""A piece of work done beside the main process, on the machine's second core.

numpy runs one operation at a time on one core, and two threads gain little
here (measured on the 2-core CI machine: the two nodes' passes in two
threads took 0.85 to 0.9 of the time in one, as their many short numpy calls
queue for the interpreter's lock), while two processes each run at full
speed.  :class:`Beside` forks the process, computes ``fn(*args)`` in the
child (which shares every array of the parent without a copy) and hands the
value back through a pipe, pickled.  The child leaves by ``os._exit``: it
never flushes the parent's buffered output, runs no ``atexit`` hook and
writes no file.

Only where it is safe and pays (:func:`can_fork`): Linux (where ``fork`` of a
process running numpy is safe; macOS's frameworks are not), two cores or
more, and no other Python thread in the process (a thread holding a lock at
the fork would leave the child stuck on it: the station and live sessions
measure serially).  ``STAND_SERIAL=1`` turns it off.  If
the child dies or its answer cannot be read, the parent does the work
itself: the answer never depends on how it was computed.

A large answer (a run's streams: 23 MB at 600 s) goes back without a pipe's
copies when the caller reserves ``shared_bytes``: the child pickles it with
its arrays out of band (pickle protocol 5) and copies their bytes once into
an anonymous mapping that both processes share (made before the fork); the
pipe carries the rest, and the parent's arrays are views of the mapping.
An answer that does not fit goes through the pipe as ever.
"""

from __future__ import annotations

import mmap
import os
import pickle
import sys
import threading
from collections.abc import Callable
from typing import Any

from stand.process.allocator import release_free_memory


def can_fork() -> bool:
    """Whether work may be forked beside this process now (see the module's notes)."""
    return (
        sys.platform.startswith("linux")  # macOS: fork is unsafe once its frameworks load
        and len(os.sched_getaffinity(0)) >= 2  # the cores this process may run on
        and threading.active_count() == 1
        and os.environ.get("STAND_SERIAL", "") in ("", "0")
    )


class Beside:
    """``fn(*args)`` computed in a forked child while the caller goes on.

    :meth:`result` returns its value or raises the exception it raised (the
    project's exceptions pickle); :meth:`cancel` ends the child unread.  Use
    only where :func:`can_fork` is true.
    """

    def __init__(self, fn: Callable[..., Any], *args: Any, shared_bytes: int = 0) -> None:
        self._fn, self._args = fn, args
        self._pid, self._read = 0, -1
        self._shared = _mapping(shared_bytes)
        release_free_memory()  # not shared with the child: fewer pages copied
        read, write = os.pipe()
        try:
            pid = os.fork()
        except OSError:  # no process to be had (memory, limits): the work is done here
            os.close(read)
            os.close(write)
            return
        if pid == 0:  # the child: compute, answer, leave without any clean-up of the parent's
            try:
                os.close(read)
                _answer(write, fn, args, self._shared)
            finally:
                os._exit(0)
        os.close(write)
        self._pid, self._read = pid, read

    def result(self) -> Any:
        """The child's value (or its exception, raised here); computed here if the child
        could not answer (or none could be forked)."""
        if self._read < 0:
            return self._fn(*self._args)
        try:
            with os.fdopen(self._read, "rb") as f:
                data = f.read()
        finally:
            self._reap()
        shared, self._shared = self._shared, None  # kept alive by the arrays that view it
        try:
            spans, body = pickle.loads(data)
            whole = memoryview(shared) if shared is not None else None
            views = [whole[a : a + n] for a, n in spans or ()] if whole is not None else []
            kind, value = pickle.loads(body, buffers=views)
        except Exception:  # a dead child, an answer cut short: do the work here
            return self._fn(*self._args)
        if kind == "error":
            raise value
        return value

    def cancel(self) -> None:
        """End the child without reading its answer (idempotent)."""
        if self._pid:
            import signal

            try:
                os.kill(self._pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            os.close(self._read)
            self._reap()

    def _reap(self) -> None:
        if self._pid:
            pid, self._pid = self._pid, 0
            os.waitpid(pid, 0)


def _mapping(size: int) -> mmap.mmap | None:
    """An anonymous mapping of ``size`` bytes shared with a child forked after it (None:
    none asked for, or none to be had: the answer then goes through the pipe)."""
    if size <= 0:
        return None
    try:
        return mmap.mmap(-1, size)
    except (OSError, ValueError, OverflowError):
        return None


def _answer(
    fd: int, fn: Callable[..., Any], args: tuple[Any, ...], shared: mmap.mmap | None
) -> None:
    """Compute ``fn(*args)`` and write ``("value", v)`` or ``("error", exc)``, pickled, to
    ``fd`` (its arrays' bytes into ``shared`` where they fit); nothing is written if even
    that cannot be pickled (the parent then computes)."""
    try:
        answer: tuple[str, Any] = ("value", fn(*args))
    except BaseException as exc:  # handed to the parent, which raises it
        answer = ("error", exc)
    try:
        body, spans = _out_of_band(answer, shared)
        data = pickle.dumps((spans, body), protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:
        return
    with os.fdopen(fd, "wb") as f:
        f.write(data)


def _out_of_band(
    answer: tuple[str, Any], shared: mmap.mmap | None
) -> tuple[bytes, list[tuple[int, int]] | None]:
    """``answer`` pickled with its large buffers copied into ``shared`` (their offsets and
    sizes, each at a multiple of 64 bytes), or all in the pickle (None) if they do not fit."""
    if shared is None:
        return pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL), None
    buffers: list[pickle.PickleBuffer] = []
    body = pickle.dumps(answer, protocol=5, buffer_callback=buffers.append)
    spans, at = [], 0
    for buffer in buffers:
        raw = buffer.raw()
        if at + raw.nbytes > len(shared):
            return pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL), None
        shared[at : at + raw.nbytes] = raw
        spans.append((at, raw.nbytes))
        at = -(-(at + raw.nbytes) // 64) * 64
    return body, spans
