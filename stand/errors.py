"""The project's one exception tree.

Every error the software raises on purpose derives from :class:`StandError`.
Each subclass also inherits the standard-library type it resembles, so a
caller that only knows ``ValueError`` or ``TimeoutError`` still catches it,
and carries the figures that explain it as attributes.

The CLI turns any :class:`StandError` into one line on stderr and exit code 2.
An error that wraps a library's error chains it (``raise ... from exc``).

Every class pickles whole, figures included (batch workers return them to
the parent process): :meth:`StandError.__reduce__` restores the message and
the attributes without calling ``__init__`` again.
"""

from __future__ import annotations

from typing import Any


def _restore(cls: type[StandError], args: tuple[Any, ...], state: dict[str, Any]) -> StandError:
    try:
        err = cls.__new__(cls)
    except TypeError:  # MemoryError's own __new__ refuses a subclass made this way
        err = BaseException.__new__(cls)
    Exception.__init__(err, *args)
    err.__dict__.update(state)
    return err


class StandError(Exception):
    """Base of every error raised on purpose by this project."""

    def __reduce__(self) -> tuple[Any, ...]:
        return (_restore, (type(self), self.args, dict(self.__dict__)))


class UsageError(StandError, ValueError):
    """A command-line argument is missing or malformed."""


class JobOrderError(UsageError):
    """A job order (or a command on one) the stand refuses (OPC 40001-3).

    Parameters
    ----------
    message
        Why, in one line.
    bits
        The ISA-95 ReturnStatus bits that say it (OPC 10031-4, Annex B).
    """

    def __init__(self, message: str, *, bits: int):
        self.bits = bits
        super().__init__(message)


class MeasurementError(StandError, ValueError):
    """The data cannot give an unbalance (a node missing, no reference edges ...)."""


class SensorFaultError(MeasurementError):
    """The data show a fault that more data will not cure: a dead, stuck or saturated
    sensor, a scale of 0, two nodes whose clocks disagree, a shaft too fast for the
    sample rate.  A live measurement stops at once on it (a plain
    :class:`MeasurementError`, e.g. too few edges yet, is waited out).
    """


class ConfigError(StandError, ValueError):
    """A configuration file (or value) is missing, malformed or physically refused.

    Parameters
    ----------
    message
        What was expected and what came.
    source
        The file (or other origin) the bad value came from, if any.
    key
        The dotted key of the bad value, e.g. ``"rotor.b"``, if any.
    """

    def __init__(self, message: str, *, source: str | None = None, key: str | None = None):
        self.source = source
        self.key = key
        where = ": ".join(p for p in (source, f"[{key}]" if key else None) if p)
        super().__init__(f"{where}: {message}" if where else message)


class ModelError(StandError, ValueError):
    """The stand model cannot answer for these inputs (bad speed, shapes, ...)."""


class ParameterError(ModelError):
    """A stand or rotor parameter is physically refused.

    Attributes
    ----------
    key : str
        The parameter's name (the seed's symbol, e.g. ``"C1"``).
    """

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(f"{key}: {message}")


class PlanesTooCloseError(ModelError):
    """The two-plane split is too ill-conditioned to be trusted.

    The static resultant (``U1 + U2``, i.e. the unbalance a single plane
    would correct) is still well determined and is carried here.

    Attributes
    ----------
    split_condition : float
        2-norm condition number of the plane split (dimensionless; inf when
        the planes coincide).
    limit : float
        The largest split condition number accepted.
    separation_m : float
        Distance between the correction planes, ``b + c`` [m].
    static_unbalance_kg_m : complex
        The static resultant ``q1 R1 e^{-i phi1} + q2 R2 e^{-i phi2}`` [kg m].
    """

    def __init__(
        self,
        *,
        split_condition: float,
        limit: float,
        separation_m: float,
        static_unbalance_kg_m: complex,
    ):
        self.split_condition = split_condition
        self.limit = limit
        self.separation_m = separation_m
        self.static_unbalance_kg_m = static_unbalance_kg_m
        super().__init__(
            f"correction planes {separation_m * 1e3:.4g} mm apart: the two-plane split has "
            f"condition number {split_condition:.3g} (limit {limit:.3g}); "
            f"static resultant is {abs(static_unbalance_kg_m) * 1e6:.6g} g mm"
        )


class NoStatusError(StandError, ValueError):
    """A node's samples cannot be scaled: no STATUS frame came in time.

    Attributes
    ----------
    node : int
        The node id.
    frame : int
        Index of the node's first frame in the run.
    """

    def __init__(self, message: str, *, node: int, frame: int):
        self.node = node
        self.frame = frame
        super().__init__(message)


class RecordingError(StandError, ValueError):
    """A run file or CAN log cannot be read (corrupt, truncated, garbage, no protocol frames).

    Attributes
    ----------
    path : str
        The file.
    line : int or None
        The 1-based line (text logs) or frame index where it went wrong, if known.
    """

    def __init__(self, message: str, *, path: str, line: int | None = None):
        self.path = path
        self.line = line
        where = f"{path}:{line}" if line is not None else path
        super().__init__(f"{where}: {message}")


class WriteError(StandError, OSError):
    """A file cannot be written: it exists (and ``--force`` was not given), it is an input
    or a special file, or the disk refused the bytes.

    Attributes
    ----------
    path : str
        The file that was to be written.
    """

    def __init__(self, message: str, *, path: str):
        self.path = path
        super().__init__(f"{path}: {message}")


class DiskFullError(WriteError):
    """The disk (or the process's file-size limit) has no room for the next write.

    Attributes
    ----------
    needed_bytes : int
        What the write needed [B].
    free_bytes : int
        What the disk (or the limit) had left [B].
    """

    def __init__(self, message: str, *, path: str, needed_bytes: int, free_bytes: int):
        self.needed_bytes = needed_bytes
        self.free_bytes = free_bytes
        super().__init__(message, path=path)


class UnusualLogError(RecordingError):
    """A candump block the fast reader cannot take (caught inside: the file is then read
    the slow way, which names any bad line)."""

    def __init__(self, path: str):
        super().__init__("unusual lines for the fast reader", path=path)


class BusError(StandError, ConnectionError):
    """The CAN interface failed: cannot open, bus-off, interface gone.

    Attributes
    ----------
    channel : str
        The interface and channel, e.g. ``"socketcan:can0"``.
    frames_received : int
        Frames received (and kept) before the failure.
    """

    def __init__(self, message: str, *, channel: str, frames_received: int = 0):
        self.channel = channel
        self.frames_received = frames_received
        super().__init__(f"{channel}: {message}")


class BusTimeoutError(BusError, TimeoutError):
    """No frames (or not the frames waited for) within the time allowed.

    Attributes
    ----------
    timeout_s : float
        The time waited [s].
    """

    def __init__(self, message: str, *, channel: str, timeout_s: float, frames_received: int = 0):
        self.timeout_s = timeout_s
        super().__init__(message, channel=channel, frames_received=frames_received)


class ArchiveError(StandError, OSError):
    """The archive (its database) cannot be opened, read or written.

    Attributes
    ----------
    url : str
        The archive's address, its password left out.
    """

    def __init__(self, message: str, *, url: str):
        self.url = url
        super().__init__(f"archive {url}: {message}")


class ArchiveRowError(ArchiveError, ValueError):
    """A row read from the archive holds what no run of this software wrote (another
    program, another version, a damaged database): refused, the row named.

    Attributes
    ----------
    table, row, column : str
        Where: the table, the row (``run 17``), the column.
    """

    def __init__(self, message: str, *, url: str, table: str, row: str, column: str):
        self.table, self.row, self.column = table, row, column
        super().__init__(f"table {table}, {row}, column {column}: {message}", url=url)


class ClusterError(StandError, ConnectionError):
    """A compute cluster (a Dask scheduler) cannot be reached, or is not usable.

    Attributes
    ----------
    address : str
        The scheduler's address, as given.
    """

    def __init__(self, message: str, *, address: str):
        self.address = address
        super().__init__(f"scheduler {address}: {message}")


class StationBusyError(StandError, RuntimeError):
    """The station measures already: one measurement at a time, whichever screen asks.

    Attributes
    ----------
    running : str
        What is being measured (the job and the kind of run).
    """

    def __init__(self, message: str, *, running: str):
        self.running = running
        super().__init__(message)


class TooLargeError(StandError, MemoryError):
    """An input whose work would need more memory than this machine has: refused before
    anything is allocated.

    Attributes
    ----------
    what : str
        The file or scene.
    needed_bytes, available_bytes : int
        The estimate, and what the machine has free for it.
    """

    def __init__(self, message: str, *, what: str, needed_bytes: int, available_bytes: int):
        self.what, self.needed_bytes, self.available_bytes = what, needed_bytes, available_bytes
        super().__init__(
            f"{what}: {message}: it would need about {needed_bytes / 1e9:.3g} GB of memory, "
            f"this machine has {available_bytes / 1e9:.3g} GB free"
        )


class RefusedError(StandError, PermissionError):
    """An action its account (or the operating system's user, on a stand with accounts)
    may not take: refused before anything changed, and the refusal journaled.

    Attributes
    ----------
    who : str
        The account, or ``os:USER``.
    right : str
        The right the action takes (``accounts``, ``calibrate`` ...).
    """

    def __init__(self, message: str, *, who: str, right: str):
        self.who, self.right = who, right
        super().__init__(message)


class ThrottledError(RefusedError):
    """A log-in tried before the wait its earlier failures set has passed: not checked at
    all (a guess costs the guesser time, never the stand)."""


class KeyFileError(StandError, OSError):
    """The stand's signing key (or the journal's anchor beside it) cannot be made or
    read, or is not what this software wrote.

    Attributes
    ----------
    path : str
        The file.
    """

    def __init__(self, message: str, *, path: str):
        self.path = path
        super().__init__(f"{path}: {message}")


class DriveError(StandError, ConnectionError):
    """The stand's drive does not answer, answers nonsense, or refuses the cycle (guard
    open, emergency stop, a fault of its own): the rotor is brought to rest where the drive
    still answers, and the run, if any, is kept.

    Attributes
    ----------
    where : str
        The drive, named for a person (family and address).
    """

    def __init__(self, message: str, *, where: str):
        self.where = where
        super().__init__(f"drive {where}: {message}")


class CycleAbortedError(StandError, RuntimeError):
    """The stand's cycle was stopped by its supervision (guard opened, emergency stop, a
    fault, over-speed, a 1x over its limit during run-up): the rotor quick-stopped, the
    run kept and marked aborted.  The CLI exits with ``EXIT_ABORTED``.

    Attributes
    ----------
    reason : str
        Why, with the time into the cycle.
    run_file : str
        The run kept ("" when nothing was recorded).
    """

    def __init__(self, reason: str, *, run_file: str):
        self.reason, self.run_file = reason, run_file
        kept = f"; the run so far is kept in {run_file}" if run_file else ""
        super().__init__(f"cycle aborted: {reason} (quick stop){kept}")
