"""The station's side of the stand's drive: Start runs the cycle (:mod:`stand.live.cycle`)
when the rotor type's config has a ``[drive]``, Stop is its quick stop, the Measure screen
reads the drive's line, the Correct screen turns a plane's correction place to the mark;
an aborted cycle is journaled (:func:`stand.actions.journal_abort`)."""

from __future__ import annotations

import logging
import threading

from stand.actions import Actor, journal_abort
from stand.config import Config
from stand.core import rad_s_to_rpm
from stand.drivers.drive import DriveState
from stand.errors import CycleAbortedError, StandError, UsageError
from stand.i18n.language import N_, Language
from stand.live.cycle import DriveLink, Measure, run_cycle, turn_to_mark
from stand.solve import Result
from stand.solve.result import IndexStop

log = logging.getLogger(__name__)

PHASES = {"run-up": N_("run-up"), "measuring": N_("measuring"), "braking": N_("braking"),
          "turning": N_("turning to the mark")}  # fmt: skip
"""The cycle's phases as the screens name them."""


class DriveSide:
    """The drive of the last run (None: the operator spins the rotor) and its latest line."""

    def __init__(self, archive_url: str) -> None:
        self.archive_url = archive_url
        self.link: DriveLink | None = None
        self.result: Result | None = None
        self.state: tuple[str, DriveState] | None = None
        self.at_mark: IndexStop | None = None
        """The plane whose correction place is at the mark now (the last stop made)."""
        self._lock = threading.Lock()

    def show(self, phase: str, st: DriveState) -> None:
        self.state = (phase, st)

    def run(self, link: DriveLink, cfg: Config, measure: Measure, run_path: str,
            stop: threading.Event, actor: Actor) -> Result:  # fmt: skip
        """The cycle, Stop its quick stop; an abort journaled, then raised."""
        self.link, self.result, self.state, self.at_mark = link, None, None, None
        try:
            result = run_cycle(link, cfg, measure, run_path=run_path, rpm=None, stop=stop,
                               show=self.show)  # fmt: skip
        except CycleAbortedError as exc:
            try:
                journal_abort(self.archive_url, actor, exc.reason, exc.run_file)
            except StandError as err:
                log.warning("the abort is not journaled: %s", err)
            raise
        self.result = result
        self.at_mark = result.cycle.index[-1] if result.cycle and result.cycle.index else None
        return result

    def turn(self, plane: int) -> IndexStop:
        """Turn ``plane``'s correction place to the mark (one turn at a time)."""
        if self.link is None or self.result is None:
            raise UsageError("no drive ran the last run: turn the rotor by hand")
        if not self._lock.acquire(blocking=False):
            raise UsageError("the rotor is turning already")
        try:
            self.state, self.at_mark = None, None
            self.at_mark = turn_to_mark(self.link, self.result, plane)
            return self.at_mark
        finally:
            self._lock.release()

    @property
    def turning(self) -> bool:
        """A plane is being turned to the mark now (the machine executes)."""
        return self._lock.locked()

    def line(self, _: Language) -> str:
        """The drive's state in words: phase, speed, guard."""
        if self.state is None:
            return ""
        phase, st = self.state
        guard = _("guard closed") if st.guard_closed else _("guard OPEN")
        rpm = _.number(float(rad_s_to_rpm(st.speed_rad_s)), 0)
        return _("drive: {phase}, {rpm} rpm, {guard}").format(
            phase=_(PHASES.get(phase, phase)), rpm=rpm, guard=guard)  # fmt: skip
