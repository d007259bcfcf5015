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
"""

from __future__ import annotations

import os
import pickle
import signal
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

    def __init__(self, fn: Callable[..., Any], *args: Any) -> None:
        self._fn, self._args = fn, args
        self._pid, self._read = 0, -1
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
                _answer(write, fn, args)
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
        try:
            kind, value = pickle.loads(data)
        except Exception:  # a dead child, an answer cut short: do the work here
            return self._fn(*self._args)
        if kind == "error":
            raise value
        return value

    def cancel(self) -> None:
        """End the child without reading its answer (idempotent)."""
        if self._pid:
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


def _answer(fd: int, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
    """Compute ``fn(*args)`` and write ``("value", v)`` or ``("error", exc)``, pickled, to
    ``fd``; nothing is written if it cannot be pickled (the parent then computes)."""
    try:
        answer: tuple[str, Any] = ("value", fn(*args))
    except BaseException as exc:  # handed to the parent, which raises it
        answer = ("error", exc)
    try:
        data = pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:
        return
    with os.fdopen(fd, "wb") as f:
        f.write(data)
