"""What the station's screens show at one moment: a frozen :class:`Snapshot` of the
operator's loop (:class:`stand.station.service.Station` makes a new one at every change)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from stand.solve import Job

BUS = "bus"
"""The source that reads the stand's CAN bus (the rotor type's ``[bus]`` table)."""


@dataclass(frozen=True)
class Snapshot:
    """What the screens show, at one moment.

    ``phase`` is ``idle``, ``measuring``, ``done`` or ``failed``; ``kind`` is
    ``initial`` (the first run of a rotor) or ``check`` (after the correction).
    ``progress`` is the latest live estimate (:class:`stand.live.loop.Progress`),
    ``result`` the finished run's :class:`stand.solve.result.Result` and ``before`` the
    initial run's while a check is made.  ``seq`` grows with every change.
    """

    seq: int = 0
    phase: str = "idle"
    kind: str = "initial"
    rotor_type: str | None = None
    source: str | None = None
    job: Job = field(default_factory=Job)
    started_s: float = 0.0
    progress: Any = None
    waiting: str = ""
    result: Any = None
    before: Any = None
    error: str = ""
    notes: tuple[str, ...] = ()
    applied: tuple[Any, ...] = ()
    applied_run: str | None = None
    """The run whose correction was put on the simulated rotor last (once only)."""
    confirmed_run: str | None = None
    """The run whose correction the operator confirmed as put on as shown: its check is a
    calibration datum (:mod:`stand.health.monitor`)."""
    run_id: int | None = None
    tolerance_kg_m: tuple[float, float] | None = None

    @property
    def simulated(self) -> bool:
        return self.source not in (None, BUS)
