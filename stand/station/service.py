"""The station's one measurement, shared by every screen (no interface code here).

:class:`Station` runs the operator's loop on the application layer: a live
run measured until precise (:func:`stand.live.loop.measure_live`, in a thread),
the report beside the run, the run archived; on a simulated stand the
correction applied (:func:`stand.solve.recordings.correction_masses`, as
``--apply`` does) and the check run against the run before
(:func:`stand.solve.check.with_check`).  Screens read :meth:`Station.snapshot`, a
frozen picture of the state; only one measurement runs at a time, whichever
screen starts it (:class:`~stand.errors.StationBusyError`).
"""

from __future__ import annotations

import datetime as dt
import logging
import re
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from stand.actions import config_seen
from stand.archive import drift_rows
from stand.archive.query import serials_starting
from stand.config import default_stand_id, load_config, rotor_types_in
from stand.config.serials import next_serial, rule_prefix
from stand.drivers.bus import ALLOW_URL
from stand.errors import StandError, StationBusyError, UsageError
from stand.health import with_drift
from stand.i18n.language import N_, Language, language
from stand.live import live_source, measure_live
from stand.sim import Mass, shipped_scenes
from stand.solve import Job, with_check
from stand.solve.pipeline import SolveOptions, load_config_text
from stand.solve.recordings import correction_masses
from stand.solve.verdict import tolerance_of
from stand.station.archive_side import ArchiveSide
from stand.station.drive_side import DriveSide
from stand.station.sessions import Sessions
from stand.station.snapshot import BUS, Snapshot

log = logging.getLogger(__name__)

UPDATE_S = 0.4
"""The live estimate is renewed at least this often [s]: 2.5 a second, above the 2 the
screen must show (a 0.1 s read can delay one)."""
MAX_SECONDS = 120.0
"""A station run ends after this long even when not yet precise [s]."""
SILENCE_S = 2.0
"""No frame for this long ends a run (the bus is gone) [s]."""


def safe_name(text: str) -> str:
    """``text`` as part of a file name (letters, digits, ``.``, ``_`` and ``-``)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("._")[:60] or "rotor"


class Station(ArchiveSide):
    """The operator's loop on one stand: start, measure, correct, check, next rotor.

    Parameters
    ----------
    config_dir
        The rotor types: one configuration file (``NAME.toml``) each.
    runs_dir
        Where run files and their reports are written (created if missing).
    archive_url
        The archive every run goes into.
    targets
        ``targets(cfg, params, U) -> (kg m, kg m)``: the precision each plane must reach.
    max_seconds
        The longest run [s].
    """

    def __init__(
        self,
        config_dir: Path,
        runs_dir: Path,
        archive_url: str,
        targets: Callable[[Any, Any, Any], tuple[float, float]],
        *,
        max_seconds: float = MAX_SECONDS,
    ) -> None:
        self.config_dir = Path(config_dir).resolve()
        self.runs_dir = Path(runs_dir).resolve()
        self.archive_url = archive_url
        self.targets = targets
        self.max_seconds = max_seconds
        self._lock = threading.Lock()
        self._printing = threading.Lock()  # one certificate printed at a time
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._state = Snapshot()
        self.sessions = Sessions(archive_url)  # who is logged in (none: a lone stand)
        self.default_language = "en"  # the screens' language where no account names one
        self._languages: dict[str, Language] = {}
        self.drive = DriveSide(archive_url)  # the stand's drive, when a rotor type has one

    # -- what there is to choose -------------------------------------------------------------
    def language(self, code: str | None) -> Language:
        """A language for the screens (its catalogue read once per station); None: the
        station's default."""
        code = code or self.default_language
        if code not in self._languages:
            self._languages[code] = language(code)
        return self._languages[code]

    def rotor_types(self) -> list[str]:
        """The rotor types: the configuration files in ``config_dir``, by name."""
        return rotor_types_in(self.config_dir)

    @staticmethod
    def rotor_types_archive(config_dir: Path) -> str | None:
        """The ``[archive] url`` the rotor types in ``config_dir`` name (the same in each
        that names one, else this is not one station's archive); None where none does.  A
        rotor type that does not load is left to the screen that chooses it (it says why
        there): the station still starts for the others."""
        urls = set()
        for path in sorted(Path(config_dir).glob("*.toml")):
            try:
                cfg = load_config(str(path))[0]
            except StandError:
                continue
            if cfg.archive is not None and cfg.archive.url:
                urls.add(str(cfg.archive.url))
        if len(urls) > 1:
            raise UsageError(f"{config_dir}: the rotor types name different archives "
                             f"({', '.join(sorted(urls))}): one station archives in one "
                             "([archive] url, or --archive)")  # fmt: skip
        return urls.pop() if urls else None

    def stand_id(self) -> str:
        """The stand id its runs are archived under: its rotor types' ``[stand] id`` (the
        same in each, else this is not one stand), else the host name; for OPC UA."""
        ids = {
            load_config(str(self.config_path(t)))[0].stand.stand_id() for t in self.rotor_types()
        }
        if len(ids) > 1:
            raise UsageError(
                f"{self.config_dir}: the rotor types name different stands "
                f"({', '.join(sorted(ids))}): one station is one stand ([stand] id)"
            )
        return ids.pop() if ids else default_stand_id()

    def config_path(self, rotor_type: str) -> Path:
        """The configuration of ``rotor_type`` (only names from :meth:`rotor_types`)."""
        if rotor_type not in self.rotor_types():
            raise UsageError(f"no rotor type {rotor_type!r} in {self.config_dir}")
        return self.config_dir / f"{rotor_type}.toml"

    def display_units(self, rotor_type: str | None) -> tuple[str, str]:
        """The units (mass, length) the rotor type's configuration shows the operator
        (``[display]``); g and mm when it names none, or the type is no longer in the
        folder, or its file no longer loads."""
        if rotor_type not in self.rotor_types():
            return "g", "mm"

        try:
            cfg, _, _ = load_config_text(str(self.config_path(str(rotor_type))))
        except StandError:
            return "g", "mm"
        return cfg.display.mass, cfg.display.length

    @staticmethod
    def sources() -> list[str]:
        """The stand's CAN bus, and the simulated scenes (training and demonstrations)."""

        return [BUS, *shipped_scenes()]

    # -- state ---------------------------------------------------------------------------
    def snapshot(self) -> Snapshot:
        """The state now (a frozen copy: safe to read from any thread)."""
        return self._state

    def _set(self, **changes: Any) -> None:
        with self._lock:
            self._state = replace(self._state, seq=self._state.seq + 1, **changes)

    # -- the loop ------------------------------------------------------------------------
    def start(self, rotor_type: str, source: str, job: Job) -> None:
        """Measure a new rotor: the initial run (nothing applied to a simulated rotor)."""
        config = self.config_path(rotor_type)
        if source not in self.sources():
            raise UsageError(f"no source {source!r}: the bus or one of the scenes")
        if not (job.serial or "").strip() and self._state.phase != "measuring":
            job = replace(job, serial=self._generated_serial(config))
        if job.job_id and self._state.phase != "measuring":
            self._take_job(job.job_id, rotor_type, self._actor(job))
        if self._state.phase != "measuring":  # a rotor type edited on disk: journaled
            try:
                config_seen(self.archive_url, self._actor(job), config)
            except StandError as exc:  # the run itself will say the archive is out of reach
                log.warning("rotor type %s not checked against the audit trail: %s",
                            rotor_type, exc)  # fmt: skip
        self._launch(
            "initial", rotor_type=rotor_type, source=source, job=job, config=config, before=None
        )

    def _generated_serial(self, config: Path) -> str:
        """The next serial of the rotor type's ``[rotor] serial_rule`` for today (local),
        after those archived; UsageError where the rotor type has no rule."""
        rule = load_config(str(config))[0].rotor.serial_rule
        if rule is None:
            raise UsageError(N_(
                "enter the rotor's serial number first (type it or scan it): without one "
                "the rotor is anonymous in the archive, Q-DAS and OPC UA (or give the rotor "
                "type a [rotor] serial_rule)"))  # fmt: skip
        day = dt.datetime.now().astimezone().date()
        return next_serial(rule, day, serials_starting(self.archive_url, rule_prefix(rule, day)))

    def latest(self) -> Any:
        """The rotor's latest finished run (the one a correction and a check start from)."""
        s = self._state
        return s.result if s.phase == "done" else s.before

    def check(self) -> None:
        """Measure the same rotor again after its correction: the check run (against the
        latest run: after a failed check, a second correction is checked against it)."""
        s, before = self._state, self.latest()
        if s.rotor_type is None or before is None:
            raise UsageError("measure the rotor first: a check needs the run before it")
        self._launch(
            "check",
            rotor_type=s.rotor_type,
            source=str(s.source),
            job=s.job,
            config=self.config_path(s.rotor_type),
            before=before,
        )

    def _launch(self, kind: str, *, config: Path, before: Any, **state: Any) -> None:
        with self._lock:
            s = self._state
            if s.phase == "measuring":
                what = f"the {s.kind} run of {s.job.serial or 'a rotor'}"
                raise StationBusyError(f"the station is measuring {what} already", running=what)
            self._stop.clear()
            fresh = Snapshot(seq=s.seq + 1, phase="measuring", kind=kind, before=before,
                             started_s=_now(), **state)  # fmt: skip
            if kind == "check":  # the masses on the simulated rotor stay on it
                fresh = replace(
                    fresh,
                    applied=s.applied,
                    applied_run=s.applied_run,
                    confirmed_run=s.confirmed_run,
                )
            self._state = fresh
        self._thread = threading.Thread(
            target=self._measure, args=(kind, config, before, self._thread), name="station-run",
            daemon=True,
        )  # fmt: skip
        self._thread.start()

    def stop(self) -> None:
        """End the running measurement by hand (its run is kept and solved)."""
        self._stop.set()

    def wait(self, timeout_s: float | None = None) -> Snapshot:
        """Wait for the running measurement to end; the state then."""
        if self._thread is not None:
            self._thread.join(timeout_s)
        return self._state

    def apply_correction(self) -> tuple[Any, ...]:
        """On a simulated stand: put the prescribed correction on the rotor, as an operator
        would (the masses ``--apply`` puts on); returns every mass applied so far."""

        s = self._state
        if s.phase != "done" or s.result is None or not s.simulated:
            raise UsageError("a correction is applied on the simulated stand, after a run")
        run, config = s.result.provenance.run_file, self.config_path(str(s.rotor_type))
        if s.applied_run == run:
            raise UsageError("this correction is on the rotor already: start the check run")
        masses = [Mass(p, g, a, r) for p, g, a, r in correction_masses(run, str(config))]
        self._set(applied=s.applied + tuple(masses), applied_run=run, confirmed_run=run)
        return self._state.applied

    def confirm_applied(self) -> None:
        """The operator confirms the correction shown was put on as shown: the check run
        after it becomes a calibration datum."""
        s = self._state
        if s.phase != "done" or s.result is None:
            raise UsageError("measure the rotor first: there is no correction to confirm")
        self._set(confirmed_run=s.result.provenance.run_file)

    def next_rotor(self) -> None:
        """Forget the rotor measured (its runs stay in the archive): back to the start."""
        with self._lock:
            if self._state.phase == "measuring":
                raise StationBusyError("stop the measurement first", running="a run")
            job = self._state.job
            self._state = Snapshot(seq=self._state.seq + 1)
        if job.job_id:
            self._end_job(job.job_id, self._actor(job))

    # -- the measuring thread ------------------------------------------------------------
    def _measure(
        self, kind: str, config: Path, before: Any, previous: threading.Thread | None
    ) -> None:
        """Measure, show the answer, then file it (report, archive, plant): the operator
        reads the answer while it is filed.  The run before, if still being filed, is filed
        first (a check is archived after the run it checks)."""
        if previous is not None:
            previous.join()
        try:
            result = self._run(kind, config, before)
        except StandError as exc:
            self._set(phase="failed", error=str(exc), progress=None)
            return
        except Exception as exc:  # the screen must say it, not die with the thread
            log.exception("station run failed")
            self._set(phase="failed", error=f"{type(exc).__name__}: {exc}", progress=None)
            return
        self._set(phase="done", result=result, run_id=None, notes=(),
                  waiting=FILING)  # fmt: skip
        run_id, notes = self._file(result, config)
        if kind == "check" and run_id is not None:
            notes = (*notes, self._datum(before, result))
        with self._lock:
            s = self._state
            if s.result is not result:  # the operator went on (next rotor) while it was filed
                log.info("run filed after the screen moved on: %s", "; ".join(notes) or "ok")
                return
            self._state = replace(s, seq=s.seq + 1, waiting="", run_id=run_id, notes=notes)
        self._other_languages(result)

    def _run(self, kind: str, config: Path, before: Any) -> Any:

        s = self._state
        scene = None if s.source == BUS else s.source
        src = live_source(scene, str(config), "station", list(s.applied), scene_hardware=True,
                          seed=None if scene is None else secrets.randbelow(2**31))  # fmt: skip
        tol = tolerance_of(src.cfg, src.params)
        self._set(tolerance_kg_m=None if tol is None else tuple(tol.per_plane_kg_m))
        kwargs = src.scene_bus if src.scene_bus is not None else _bus(src.bus_table)
        self.runs_dir.mkdir(parents=True, exist_ok=True)
        stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
        path = self.runs_dir / f"{safe_name(s.job.serial or 'rotor')}-{kind}-{stamp}.h5"

        def measure(stop: Any, on_play: Any = None, watch: Any = None) -> Any:
            def progress(p: Any) -> None:
                self._set(progress=p, waiting="")
                if watch is not None:
                    watch(p)

            result, _ = measure_live(
                src, kwargs, str(path), SolveOptions(traces=True), self.targets,
                max_seconds=self.max_seconds, silence_timeout_s=SILENCE_S, on_progress=progress,
                on_wait=lambda t, why: self._set(waiting=why), job=s.job, stop=stop,
                max_interval_s=UPDATE_S, on_play=on_play,
            )  # fmt: skip
            return result

        self.drive.link = None
        if src.drive is None:
            result = measure(self._stop)
        else:
            result = self.drive.run(src.drive, src.cfg, measure, str(path), self._stop,
                                    self._actor(s.job))  # fmt: skip
        if kind == "check":
            prev = before.provenance.run_file
            result = with_check(result, prev, src.cfg, src.params, strict=True)

        try:  # a stand that drifted from its calibration: the interval widened, and said
            result = with_drift(
                drift_rows(self.archive_url, result), result, src.cfg, src.params, SolveOptions()
            )
        except StandError as exc:
            log.warning("stand health not checked: %s", exc)
        return result


FILING = N_("writing the report and archiving the run")  # the Check screen, meanwhile


def _bus(table: dict[str, Any] | None) -> dict[str, Any]:
    """The rotor type's ``[bus]`` table as ``can.Bus`` options (a file cannot allow URL
    channels, as for ``stand measure``)."""

    kwargs = dict(table or {})
    if ALLOW_URL in kwargs:
        raise UsageError(f"[bus] {ALLOW_URL}: a file cannot allow URL channels")
    return kwargs


def _now() -> float:

    return time.monotonic()
