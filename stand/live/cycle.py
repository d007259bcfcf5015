"""The stand's own cycle with a drive: guard closed? -> run-up within the drive's torque ->
steady -> measure until precise -> brake -> the correction place stopped at the operator's
mark (then plane 2's, on request).

The product supervises; the guard interlock and the emergency stop are hardware that cuts
the drive's power by itself.  Before the run-up the cycle refuses a guard open, an
emergency stop pressed or a drive in fault; while the rotor turns, a supervisor reads the
drive every :data:`POLL_S` and quick-stops on a guard opened, an emergency stop, a fault,
an over-speed of :data:`OVERSPEED` or a drive that stops answering, and the measurement on
a support's 1x over ``[drive] runup_limit_m_s2``.  The run is kept in every case; an
aborted cycle is one :class:`~stand.errors.CycleAbortedError` naming why and the run file.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from stand.config import Config
from stand.config.drive import DriveChoice
from stand.core.motor import floors
from stand.drivers.drive import Drive, DriveContext, DriveState
from stand.errors import CycleAbortedError, DriveError, StandError, UsageError
from stand.sim.shaft import SimShaft
from stand.solve import Result
from stand.solve.result import CycleInfo, IndexStop

POLL_S = 0.02
"""The supervisor's period [s]: at 1500 rpm half a revolution between two readings."""
OVERSPEED = 1.02
"""A measured speed this much over the set point stops the rotor."""
RUNUP_ALLOWANCE = (2.0, 2.0)
"""The set point must be reached within twice the run-up the torque allows, plus 2 s (a
real drive's own ramp and its speed loop's settling): else the rotor is stopped."""
RPM = math.pi / 30.0


@dataclass
class DriveLink:
    """The drive a live source commands: the config's choice, where the config is (its
    description files are relative to it), the stand's CAN bus, and, for a scene, the
    simulated drive that serves it (started by :func:`connected`)."""

    choice: DriveChoice
    base: Path = Path(".")
    source: str = "the config"
    bus: dict[str, Any] | None = None
    sim: SimShaft | None = None
    rpm: float | None = None
    """The set point chosen where the source was made (a scene's speed) [rpm]."""


@contextmanager
def connected(link: DriveLink) -> Iterator[Drive]:
    """The drive, connected (a scene's simulated drive served first); closed (a drive
    still turning quick-stopped) on the way out."""
    d = link.choice.drive
    with ExitStack() as stack:
        table, bus = link.choice.table, link.bus
        if link.sim is not None:
            table, bus = stack.enter_context(link.sim.serve(table, bus))  # type: ignore[attr-defined]
        ctx = DriveContext(d.timeout_s, link.base, link.source, bus, d.motor())
        drive = link.choice.family.connect(table, ctx)
        stack.callback(drive.close)
        yield drive


def set_point(link: DriveLink, cfg: Config, rpm: float | None) -> float:
    """The measuring speed the drive is set to [rad/s]: ``--rpm``, else ``[drive]
    speed_rpm``; never above the rotor's maximum speed."""
    d = link.choice.drive
    chosen = next((x for x in (rpm, link.rpm, d.speed_rpm) if x is not None), None)
    if chosen is None:
        raise UsageError("a drive needs a speed: give --rpm, or [drive] speed_rpm")
    limit = d.max_speed_rpm or (cfg.tolerance.max_speed_rpm if cfg.tolerance else None)
    if limit is not None and chosen > limit:
        raise UsageError(f"{chosen:g} rpm is over the rotor's maximum speed {limit:g} rpm "
                         "([drive] max_speed_rpm, else [tolerance]'s): the drive is not "
                         "started")  # fmt: skip
    return chosen * RPM


def check_ready(drive: Drive) -> DriveState:
    """The drive's state before a run-up; refused when it may not start."""
    st = drive.read()
    if st.fault_code:
        raise DriveError(f"in fault (code {st.fault_code}): clear the fault, then start again",
                         where=drive.where)  # fmt: skip
    if not st.estop_clear:
        raise DriveError("the emergency stop is pressed: release it, then start again",
                         where=drive.where)  # fmt: skip
    if not st.guard_closed:
        raise DriveError("the guard is open: close it, then start again", where=drive.where)
    if not st.standstill:
        raise DriveError(f"the rotor still turns ({st.speed_rad_s / RPM:.0f} rpm): wait for "
                         "it to stop", where=drive.where)  # fmt: skip
    return st


StateSink = Callable[[str, DriveState], None]
"""Told the cycle's phase (``run-up``, ``measuring``, ``braking``, ``turning``) and the
drive's latest state, about every :data:`SHOW_S`: a screen's drive line."""
SHOW_S = 0.25


class Supervisor:
    """Reads the drive every :data:`POLL_S` while the rotor runs up and is measured; on a
    fault, or ``outside`` set (the operator's Stop), quick-stops it, sets ``stop`` and
    keeps the reason; hands the state to ``show`` now and then."""

    def __init__(self, drive: Drive, omega_rad_s: float, t0: float,
                 outside: threading.Event | None = None, show: StateSink | None = None,
                 runup_s: float = math.inf) -> None:  # fmt: skip
        self.drive, self.omega, self.t0 = drive, omega_rad_s, t0
        self.runup_s = runup_s
        """The longest run-up allowed [s] (:data:`RUNUP_ALLOWANCE` of the torque's)."""
        self.outside, self.show, self._shown = outside, show, 0.0
        self.stop = threading.Event()
        self.reason: str | None = None
        self.at_speed_s: float | None = None
        self.speeds: list[float] = []
        self._done = threading.Event()
        self._lock = threading.Lock()
        self._io = threading.RLock()
        self._thread = threading.Thread(target=self._watch, daemon=True, name="drive-watch")

    def __enter__(self) -> Supervisor:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        self._thread.join(5.0)

    def abort(self, why: str) -> None:
        """Quick stop, once, for this reason."""
        with self._lock:
            if self.reason is not None:
                return
            self.reason = f"{why} at {time.monotonic() - self.t0:.1f} s"
        self.stop.set()
        try:
            with self._io:  # one exchange at a time: neither link is thread-safe
                self.drive.quick_stop()
        except DriveError:
            pass  # silent: its own watchdog and the hardware stop it

    def _watch(self) -> None:
        while not self._done.wait(POLL_S):
            try:
                with self._io:
                    st = self.drive.read()
            except DriveError as exc:
                return self.abort(f"the drive stopped answering ({exc})")
            why = self._why(st)
            if why:
                return self.abort(why)
            now = time.monotonic()
            if self.show is not None and now - self._shown >= SHOW_S:
                self._shown = now
                self.show("measuring" if self.at_speed_s is not None else "run-up", st)
            if st.at_speed:
                if self.at_speed_s is None:
                    self.at_speed_s = time.monotonic() - self.t0
                self.speeds.append(st.speed_rad_s)

    def _why(self, st: DriveState) -> str | None:
        if self.outside is not None and self.outside.is_set():
            return "stopped by the operator"
        if not st.guard_closed:
            return "guard opened"
        if not st.estop_clear:
            return "emergency stop"
        if st.fault_code:
            return f"drive fault (code {st.fault_code})"
        if st.speed_rad_s > OVERSPEED * self.omega:
            return (f"over-speed ({st.speed_rad_s / RPM:.0f} rpm, set point "
                    f"{self.omega / RPM:.0f} rpm)")  # fmt: skip
        late = time.monotonic() - self.t0
        if self.at_speed_s is None and not st.at_speed and late > self.runup_s:
            return (f"the set point {self.omega / RPM:.0f} rpm was not reached ("
                    f"{st.speed_rad_s / RPM:.0f} rpm after {late:.1f} s; the torque allows "
                    f"a run-up of {self.runup_s:.1f} s with its allowance)")  # fmt: skip
        return None


Measure = Callable[[threading.Event, Callable[[float], None] | None, Callable[[Any], None]], Result]
"""``measure(stop, on_play, watch)``: the live measurement, stopped when ``stop`` is set,
telling a simulated drive the scene's time 0, each progress handed to ``watch``."""


def run_cycle(link: DriveLink, cfg: Config, measure: Measure, *, run_path: str,
              rpm: float | None, plane2: Callable[[], bool] = lambda: False,
              stop: threading.Event | None = None, show: StateSink | None = None
              ) -> Result:  # fmt: skip
    """The whole cycle; the measurement's result with its :class:`CycleInfo`.  ``stop``
    set (a screen's Stop) is a quick stop; ``show`` is told the drive's state.

    Raises
    ------
    DriveError
        The drive refused to start, never answered, or its speed disagrees with the
        reference mark's (both figures named).
    CycleAbortedError
        The supervisor stopped the rotor (the run is kept; its file named).
    """
    omega = set_point(link, cfg, rpm)
    d = link.choice.drive
    with connected(link) as drive:
        check_ready(drive)
        t0 = time.monotonic()
        drive.run(omega)
        motor = d.motor()
        allowed = RUNUP_ALLOWANCE[0] * omega / motor.accel_rad_s2 + RUNUP_ALLOWANCE[1]
        with Supervisor(drive, omega, t0, stop, show, allowed) as sup:
            result = _measured(sup, measure, link, d.runup_limit_m_s2, run_path)
        t_measured = time.monotonic() - t0
        if sup.reason is not None:
            raise CycleAbortedError(sup.reason, run_file=run_path)
        _speeds_agree(drive, sup, result, d.speed_agree_pct)
        if show is not None:
            show("braking", drive.read())
        stops = [index_plane(drive, result, 1, d.index_mark_deg, omega)]
        total = time.monotonic() - t0  # the cycle: run-up to plane 1 at the mark
        if plane2():
            stops.append(index_plane(drive, result, 2, d.index_mark_deg, 0.0))
        drive.disable()
    info = _cycle_info(link, result, sup, stops, t_measured, total, omega)
    return replace(result, cycle=info)


def _measured(sup: Supervisor, measure: Measure, link: DriveLink, limit: float | None,
              run_path: str) -> Result:  # fmt: skip
    """The measurement under the supervisor; a 1x over ``limit`` before the set point is
    reached aborts it.  A measurement cut short by an abort is the abort; one that fails
    by itself quick-stops the rotor and says its own error."""

    def watch(progress: Any) -> None:
        amps = [abs(ph.A_m_s2) for ph in progress.measurement.supports]
        if limit is not None and sup.at_speed_s is None and max(amps) > limit:
            sup.abort(f"1x {max(amps):.3g} m/s2 during run-up, over the limit {limit:g} m/s2")

    on_play = None if link.sim is None else link.sim.start_clock
    try:
        return measure(sup.stop, on_play, watch)
    except StandError as exc:
        if sup.reason is not None:
            raise CycleAbortedError(sup.reason, run_file=run_path) from exc
        sup.abort("the measurement failed")
        raise


def _speeds_agree(drive: Drive, sup: Supervisor, result: Result, pct: float) -> None:
    """The drive's speed at the set point against the reference mark's: a map with a wrong
    scaling is refused, both figures named (the rotor brought to rest first)."""
    speeds = sup.speeds or [drive.read().speed_rad_s]  # never at speed: as it is now
    said = sum(speeds) / len(speeds)
    mark = result.omega_rad_s
    if abs(said / mark - 1) > pct / 100:
        drive.quick_stop()
        raise DriveError(
            f"reports {said / RPM:.1f} rpm, the reference mark gives {mark / RPM:.1f} rpm: "
            f"they differ by more than {pct:g} % (the register map's speed scaling?); the "
            f"rotor was stopped, the run is kept in {result.provenance.run_file}",
            where=drive.where,
        )


def turn_to_mark(link: DriveLink, result: Result, plane: int) -> IndexStop:
    """After a cycle, from rest: turn ``plane``'s correction place to the mark (a screen's
    button, on request)."""
    with connected(link) as drive:
        check_ready(drive)
        stop = index_plane(drive, result, plane, link.choice.drive.index_mark_deg, 0.0)
        drive.disable()
    return stop


def correction_place_deg(result: Result, plane: int) -> float:
    """Where plane ``plane``'s correction goes, from the reference mark against the
    direction of rotation [deg] (the first weight or hole; the unbalance's angle when none
    is prescribed)."""
    c = result.corrections[plane - 1]
    if c.weights:
        return float(c.weights[0].angle_deg)
    if c.holes:
        return float(c.holes[0].angle_deg)
    U = complex(result.U_kg_m[plane - 1])
    return float(-math.degrees(math.atan2(U.imag, U.real)) % 360.0)


def index_plane(drive: Drive, result: Result, plane: int, mark_deg: float,
                omega: float) -> IndexStop:  # fmt: skip
    """Stop (or turn) the rotor so that the plane's correction place is at the mark: the
    drive's angle ``mark + place`` (a place ``b`` against the rotation from the reference
    mark faces the reference sensor's ``b`` ahead, so the mark's ``m`` ahead at ``m + b``)."""
    target = (mark_deg + correction_place_deg(result, plane)) % 360.0
    t0 = time.monotonic()
    drive.stop_at(math.radians(target))
    limit = t0 + 10.0 + (omega / 10.0 if omega > 0 else 0.0)
    while time.monotonic() < limit:
        st = drive.read()
        if st.in_position and st.standstill:
            stopped = math.degrees(st.angle_rad or 0.0) % 360.0
            return IndexStop(plane, target, stopped, time.monotonic() - t0)
        if not st.guard_closed or st.fault_code:
            drive.quick_stop()
            raise DriveError("the guard opened or the drive faulted while it turned plane "
                             f"{plane} to the mark: stopped", where=drive.where)  # fmt: skip
        time.sleep(0.005)
    drive.quick_stop()
    raise DriveError(f"plane {plane} not at the mark within the time braking allows: stopped",
                     where=drive.where)  # fmt: skip


def _cycle_info(link: DriveLink, result: Result, sup: Supervisor, stops: list[IndexStop],
                t_measured: float, total: float, omega: float) -> CycleInfo:  # fmt: skip
    """Each phase's seconds: run-up to the drive's at-speed, the measurement's window (its
    revolutions at the measured speed), the settling between, the brake to rest with plane
    1's place at the mark (its wait for the angle included); ``total`` up to there; plane
    2's turn (on request) apart, as ``index``."""
    d = link.choice.drive
    revs = max((w.revolutions for w in result.measurement.windows), default=0)
    measure_s = revs * 2 * math.pi / result.omega_rad_s
    runup = sup.at_speed_s if sup.at_speed_s is not None else t_measured - measure_s
    settle = max(0.0, t_measured - runup - measure_s)
    f = floors(d.motor(), omega)
    brake = stops[0].seconds if stops else 0.0
    return CycleInfo(
        drive=link.choice.family.name, runup_s=runup, settle_s=settle, measure_s=measure_s,
        brake_s=brake, index_s=sum(s.seconds for s in stops[1:]), total_s=total,
        floor_s=f.runup_s + measure_s + f.brake_s + f.index_s, index=tuple(stops),
    )  # fmt: skip
