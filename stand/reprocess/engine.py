"""Where the runs are solved: in processes on this machine, or on a Dask cluster.

Both take the runs in tasks of a few dozen (:func:`tasks`) and give back each task's
outcomes as it finishes; neither writes anything: the client alone writes the archive.
The local pool spawns fresh interpreters with one BLAS thread each; a Dask scheduler's
workers run :func:`stand.reprocess.work.rejudge_chunk` wherever they are (each must have
this software installed, at this version: checked before the first task).  A worker lost
mid-way costs only its tasks, which the scheduler gives to another.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import queue
import socket
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

from stand import __version__
from stand.errors import ClusterError, UsageError
from stand.process import keep_freed_memory, one_blas_thread
from stand.reprocess.selection import Item
from stand.reprocess.work import rejudge_chunk
from stand.solve import ConfigText

TASK_RUNS = 25
"""Runs per task at most: few enough for an even spread, enough to keep overhead low."""
CONNECT_TIMEOUT_S = 10.0
"""How long a scheduler has to answer before the command gives up [s]."""
POLL_S = 5.0
"""How often a wait for the next task looks whether the scheduler is still there [s]."""
INSTALL = "pip install -e '.[cluster]' (or pip install 'distributed')"


def tasks(todo: list[Item], workers: int) -> list[list[Item]]:
    """The runs in tasks: at most :data:`TASK_RUNS` each, at least four per worker."""
    if not todo:
        return []
    size = max(1, min(TASK_RUNS, math.ceil(len(todo) / (4 * max(1, workers)))))
    return [todo[k : k + size] for k in range(0, len(todo), size)]


def default_jobs() -> int:
    """All of this machine's cores (those this process may use)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


class LocalEngine:
    """``jobs`` processes on this machine (1: in this process).  ``keep_memory``: each
    solving process keeps freed memory for the next run
    (:func:`stand.process.keep_freed_memory`)."""

    dashboard: str | None = None

    def __init__(self, jobs: int, *, keep_memory: bool = True):
        if jobs < 1:
            raise UsageError(f"--jobs {jobs}: at least 1")
        self.workers = jobs
        self.keep_memory = keep_memory

    def run(self, work: list[list[Item]], config: ConfigText | None) -> Iterator[list[Any]]:
        """Each task's outcomes, as it finishes."""
        if not work:  # everything in the revision already: no process to start
            return
        if self.workers == 1:
            if self.keep_memory:
                keep_freed_memory()
            for chunk in work:
                yield rejudge_chunk(chunk, config)
            return
        one_blas_thread()  # the spawned interpreters inherit it: N processes, not N x cores
        context = multiprocessing.get_context("spawn")
        start = keep_freed_memory if self.keep_memory else None
        processes = min(self.workers, len(work))  # none idle from its start
        with ProcessPoolExecutor(processes, context, initializer=start) as pool:
            futures = [pool.submit(rejudge_chunk, chunk, config) for chunk in work]
            try:
                for f in as_completed(futures):
                    yield f.result()
            finally:
                for f in futures:
                    f.cancel()

    def close(self) -> None:
        pass


def _software() -> str:
    return __version__


def keep_memory_plugin() -> Any:
    """A Dask worker plugin: :func:`stand.process.keep_freed_memory` in every worker, those
    that join or restart later too (Dask's nanny starts them with a 64 KiB trim threshold,
    which costs a third of the runs/s here).  Made here, where Dask is imported."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class KeepFreedMemory(WorkerPlugin):  # type: ignore[misc]
        name = "stand-keep-freed-memory"
        idempotent = True

        def setup(self, worker: Any) -> None:
            keep_freed_memory()

    return KeepFreedMemory()


def probe(address: str, timeout_s: float) -> None:
    """Refuse a ``tcp://`` scheduler that does not say hello within ``timeout_s``: a Dask
    server sends its handshake as soon as it accepts, and Dask's own client waits for it
    without a timeout (a port that accepts and stays silent would hold the command
    forever).  Other schemes (``tls://`` ...) are left to the client."""
    if not address.startswith("tcp://"):
        return
    host, _, port = address.removeprefix("tcp://").rstrip("/").rpartition(":")
    try:
        number = int(port)
        with socket.create_connection((host.strip("[]"), number), timeout=timeout_s) as s:
            s.settimeout(timeout_s)
            if not s.recv(1):
                raise ConnectionError("it closed the connection")
    except ValueError as exc:
        raise ClusterError("not an address tcp://HOST:PORT", address=address) from exc
    except (OSError, TimeoutError) as exc:
        raise ClusterError(f"did not answer within {timeout_s:g} s ({exc})",
                           address=address) from exc  # fmt: skip


class DaskEngine:
    """The workers of a Dask distributed scheduler (``tcp://HOST:PORT``).  ``keep_memory``:
    each worker keeps freed memory for the next run (:func:`keep_memory_plugin`)."""

    def __init__(
        self, address: str, timeout_s: float = CONNECT_TIMEOUT_S, *, keep_memory: bool = True
    ):
        try:
            from distributed import Client
        except ImportError as exc:
            raise UsageError(f"--scheduler needs Dask distributed: {INSTALL}") from exc
        self.address = address
        probe(address, timeout_s)
        try:
            self.client = Client(address, timeout=f"{timeout_s}s", set_as_default=False)
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise ClusterError(f"did not answer within {timeout_s:g} s ({exc})",
                               address=address) from exc  # fmt: skip
        try:
            versions = self.client.run(_software)
        except Exception as exc:  # a worker that cannot even load this software
            self.close()
            raise ClusterError(f"its workers cannot run stand ({exc}): install this "
                               "project on every worker", address=address) from exc  # fmt: skip
        other = {v for v in versions.values() if v != __version__}
        if other:
            self.close()
            raise ClusterError(
                f"its workers run stand {', '.join(sorted(other))}, this is "
                f"{__version__}: one version on every worker",
                address=address,
            )
        if not versions:
            self.close()
            raise ClusterError("it has no worker", address=address)
        self.workers = len(versions)
        if keep_memory:
            self.client.register_plugin(keep_memory_plugin())
        services = self.client.scheduler_info().get("services", {})
        self.dashboard: str | None = self.client.dashboard_link if "dashboard" in services else None

    def run(self, work: list[list[Item]], config: ConfigText | None) -> Iterator[list[Any]]:
        """Each task's outcomes, as it finishes; a task that failed on every try (a run
        that kills its workers) raises ClusterError after the others are given."""
        finished: queue.Queue[Any] = queue.Queue()
        futures = [self.client.submit(rejudge_chunk, chunk, config, pure=False) for chunk in work]
        for f in futures:
            f.add_done_callback(finished.put)
        failed: list[str] = []
        try:
            for _ in futures:
                f = self._next(finished)
                try:
                    yield f.result()
                except Exception as exc:  # KilledWorker and the like: left for a re-run
                    failed.append(f"{type(exc).__name__}: {exc}")
        finally:
            self.client.cancel([f for f in futures if not f.done()])
        if failed:
            raise ClusterError(
                f"{len(failed)} of {len(work)} tasks failed ({failed[0]}); "
                "run the same command again to finish them",
                address=self.address,
            )

    def _next(self, finished: queue.Queue[Any]) -> Any:
        """The next finished task; ClusterError if the scheduler is gone meanwhile."""
        while True:
            try:
                return finished.get(timeout=POLL_S)
            except queue.Empty:
                if self.client.status != "running":
                    raise ClusterError("lost the connection to it: the runs written so far "
                                       "stay; run the same command again to finish",
                                       address=self.address) from None  # fmt: skip

    def close(self) -> None:
        self.client.close()
