"""The live path: measuring a live session until precise, to one Result.

``stand record``, ``stand measure`` and ``stand balance`` run through one
:class:`~stand.live.session.LiveSession` (the bus or a scene, the reader,
the run file, the decoded streams, the signals).

:func:`measure_until_precise` is the live measuring loop: it estimates the
run so far, and stops when both planes are precise enough.  An estimate is a
full pass over the run (gate, fit, noise: its cost grows with the run) on a
schedule whose cost per second does not grow (see :data:`GROWTH`), and in
between an update that adds the revolutions that came since to the fit's
sums (:mod:`stand.measuring.live_fit`: its cost does not grow with the run).
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from stand.config import Config
from stand.core import Diagnostic
from stand.drivers.runs.recording import JOB_ATTR, STAND_ATTR, config_digest
from stand.drivers.v1.build import StreamBuilder
from stand.errors import (
    BusError,
    MeasurementError,
    NoStatusError,
    SensorFaultError,
    StandError,
)
from stand.i18n.words import N_, said
from stand.live.session import LiveSession
from stand.live.source import LiveSource
from stand.measuring.measure import MIN_REVS
from stand.solve.pipeline import (
    SOFTWARE,
    SolveOptions,
    build_result,
    check_matrix,
    measure_streams,
    remeasure_streams,
)
from stand.solve.recordings import job_of
from stand.solve.result import Job, LiveInfo, Provenance, Result

FIRST_CHECK_S = 1.0
"""The first solve of a live run comes after this long [s]."""
MIN_INTERVAL_S = 0.25
"""Solves are at least this far apart [s] ..."""
GROWTH = 0.10
"""... and at most ``max(1 s, GROWTH x elapsed)`` apart, unless the precision is predicted
sooner.  Full passes come at that interval too: a full pass costs time in proportion to the
run's length, so passing at intervals in proportion to it keeps the CPU a live second costs
constant (about 1 / GROWTH passes of the run so far per run length).  The estimates between
full passes are updates, whose cost does not grow."""
TAIL_REVS = 4
"""An update reads the frames of about this many revolutions before the last update's
end (its join needs the last two), plus :data:`TAIL_MARGIN_S`; twice that, then 8 times,
before it gives up for a full pass."""
TAIL_MARGIN_S = 0.2
"""[s] (frames of different nodes arrive in an order of their own)."""


@dataclass(frozen=True)
class Progress:
    """One live solve, for the display; ``waiting_for``: why the run goes on, in words
    (empty when it stops for precision)."""

    elapsed_s: float
    measurement: Any
    targets_kg_m: tuple[float, float]
    waiting_for: tuple[str, ...] = ()


def waiting_for(m: Any, goal: tuple[float, float], settled: bool) -> tuple[str, ...]:
    """Why a live run is not done: too few revolutions, a plane's interval above its goal,
    balls not settled (each the operator's words)."""
    out = []
    if any(w.code == "short_window" for w in m.warnings):
        revs = min(int(w.revolutions) for w in m.windows)
        out.append(said("more revolutions ({n} of {want})", n=revs, want=MIN_REVS))
    for i in range(2):
        if m.radius95_kg_m[i] > goal[i]:
            out.append(said("plane {plane}'s 95 % interval to shrink to its goal", plane=i + 1))
    if not settled:
        out.append(said("the ball balancer's balls to settle"))
    return tuple(out)


def _next_check(
    elapsed: float, m: Any, goal: tuple[float, float], min_revs: int, most_s: float | None
) -> float:
    """When the next solve is due [s from the start]: when precision is predicted, within
    the bounds :data:`MIN_INTERVAL_S` and ``max(1 s, GROWTH x elapsed)`` (or ``most_s``)."""
    revs = min(int(w.revolutions) for w in m.windows)
    # the 95 % radius falls as 1 / sqrt(revolutions): when will it meet the target?
    ratio = max(float(m.radius95_kg_m[i]) / max(goal[i], 1e-300) for i in range(2))
    due = elapsed * max(ratio**2, min_revs / max(revs, 1))
    most = max(1.0, GROWTH * elapsed) if most_s is None else max(most_s, MIN_INTERVAL_S)
    return float(elapsed + min(max(due - elapsed, MIN_INTERVAL_S), most))


def measure_until_precise(
    session: LiveSession,
    cfg: Config,
    params: Any,
    options: SolveOptions,
    targets: Callable[[Any], tuple[float, float]],
    *,
    max_seconds: float,
    on_progress: Callable[[Progress], None] | None = None,
    on_wait: Callable[[float, str], None] | None = None,
    stop: threading.Event | None = None,
    max_interval_s: float | None = None,
) -> Result:
    """Measure live until both planes' 95 % radii meet ``targets(U)`` [kg m] or time is up.

    Returns the result of the whole run (solved once more from its streams
    when the session has closed), with ``live`` saying what stopped it.
    ``stop`` set by another thread ends the run by hand ("stopped by hand");
    ``max_interval_s`` caps the time between solves (a screen that wants an
    estimate at least so often) [s].
    """

    stopped_by = N_("time limit")
    next_check = FIRST_CHECK_S
    last = None
    estimates = Estimates(session, cfg, params, options)
    while session.elapsed_s < max_seconds:
        session.read(0.1)
        if session.failure is not None:
            stopped_by = N_("frames stopped") if session.frames_received else N_("no frames")
            break
        if session.stop_signal is not None:
            stopped_by = N_("interrupted")
            break
        if stop is not None and stop.is_set():
            stopped_by = N_("stopped by hand")
            break
        elapsed = session.elapsed_s
        if elapsed < next_check:
            continue
        try:
            m = estimates.estimate(elapsed)
        except SensorFaultError as exc:  # more data will not cure it: stop now
            session.close()
            raise SensorFaultError(
                f"{exc} (after {elapsed:.1f} s; the run so far is kept in {session.run_path})"
            ) from exc
        except StandError as exc:  # not yet (too few edges, no STATUS yet): wait
            if on_wait:
                on_wait(elapsed, str(exc))
            next_check = elapsed + 1.0
            continue
        last = m
        goal = targets(m.solution.U_kg_m)
        why = waiting_for(m, goal, _settled(cfg, estimates.full))
        if on_progress:
            on_progress(Progress(elapsed, m, goal, why))
        if not why:
            stopped_by = N_("precision")
            break
        next_check = _next_check(elapsed, m, goal, MIN_REVS, max_interval_s)
    return _final_result(session, cfg, params, options, targets, last, stopped_by)


def _settled(cfg: Config, full: Any) -> bool:
    """A rotor with a ball balancer stops for precision only once the last full pass saw
    its balls settled (a precise average of balls on their way is not the answer)."""
    if cfg.autobalancer is None:
        return True
    return full is not None and not any(w.code == "balls_unsettled" for w in full.warnings)


class Estimates:
    """The live run so far, estimated: full passes on :data:`GROWTH`'s schedule, updates
    (:func:`stand.solve.pipeline.remeasure_streams`) in between.

    ``costs`` keeps ``(elapsed [s], seconds, "full" or "update", frames read)`` of every
    estimate (the benchmark and the tests read it).
    """

    def __init__(self, session: LiveSession, cfg: Config, params: Any, options: SolveOptions):
        self.session, self.cfg, self.params, self.options = session, cfg, params, options
        self.last: Any = None
        self.full: Any = None
        """The last full pass (an update knows no drift across the window)."""
        self.next_full = 0.0
        self.joined_at = 0  # frames received when the fits last gained a revolution
        self.costs: list[tuple[float, float, str, int]] = []
        self._read = 0

    def estimate(self, elapsed: float) -> Any:
        """The measurement of the run so far (raises as :func:`measure_streams` does)."""
        t0 = time.perf_counter()
        self._read = 0
        m = self._update(elapsed) if elapsed < self.next_full else None
        kind = "update"
        if m is None:
            kind = "full"
            frames = self.session.builder.frames
            m = measure_streams(self.session.streams(), self.cfg, self.params, self.options)
            self.next_full = elapsed + max(1.0, GROWTH * elapsed)
            self.joined_at = frames
            self._read += frames
            self.full = m
        self.last = m
        self.costs.append((elapsed, time.perf_counter() - t0, kind, self._read))
        return m

    def _update(self, elapsed: float) -> Any:
        """The last estimate with the revolutions since (None: a full pass is due)."""
        if self.last is None or self.last.fits is None:
            return None
        builder = self.session.builder
        per_s = builder.frames / max(elapsed, 1e-3)
        rev_s = 2 * math.pi / max(self.last.omega_rad_s, 1e-3)
        margin = per_s * (TAIL_REVS * rev_s + TAIL_MARGIN_S)
        for widen in (1, 2, 8):
            tails = builder.tail(int(self.joined_at - widen * margin))
            self._read += tails.frames
            m = remeasure_streams(self.last, tails, self.cfg, self.params, self.options)
            if m is not None:
                if [f.last_rev for f in m.fits] != [f.last_rev for f in self.last.fits]:
                    self.joined_at = builder.frames
                return m
        return None


class _Replay:
    """What :class:`Estimates` reads of a live session, fed from frames by hand."""

    def __init__(self) -> None:

        self.builder = StreamBuilder()

    def streams(self, *, strict_status: bool = False) -> Any:
        return self.builder.streams(strict_status=strict_status)


def replay_estimates(
    frames: Any,
    cfg: Config,
    params: Any,
    options: SolveOptions,
    every_s: float,
    block_s: float = 0.1,
) -> Estimates:
    """A recorded run's frames fed, as fast as the machine goes, to the live estimates as a
    live session would feed them (blocks of ``block_s`` of host time), with an estimate every
    ``every_s`` of the run (0.4 s: the station's pace); returns the :class:`Estimates`
    (its ``costs``, its ``last`` measurement).  For the benchmark and the tests."""
    session = _Replay()
    est = Estimates(session, cfg, params, options)  # type: ignore[arg-type]
    t = frames.t_s - frames.t_s[0]
    cut = np.searchsorted(t, np.arange(0.0, float(t[-1]) + block_s, block_s))
    due = FIRST_CHECK_S
    for k in range(len(cut) - 1):
        i0, i1 = cut[k], cut[k + 1]
        session.builder.add(frames.take(np.arange(i0, i1)))
        elapsed = block_s * (k + 1)
        if elapsed >= due:
            with contextlib.suppress(StandError):  # not yet: as the live loop, wait
                est.estimate(elapsed)
            due = elapsed + every_s
    return est


def _kept_estimate(last: Any, exc: Exception) -> Any:
    """The last estimate made while the run went on, kept as the answer because the whole
    run could not be measured again, saying so (never in silence)."""
    why = said("the whole run could not be measured again ({why}): the answer is the last "
               "estimate made while it ran", why=exc)  # fmt: skip
    note = Diagnostic("last_estimate", why, None)
    return replace(last, warnings=[*last.warnings, note])


def _final_result(
    session: LiveSession,
    cfg: Config,
    params: Any,
    options: SolveOptions,
    targets: Callable[[Any], tuple[float, float]],
    last: Any,
    stopped_by: str,
) -> Result:
    """The session closed and its whole run solved once more (or, when that fails, the last
    estimate kept), as one Result saying what stopped it."""
    elapsed = session.elapsed_s
    streams = session.close()
    if streams is None:
        raise BusError("nothing received: no result; no run recorded", channel=session.where)
    try:
        if any(w.code == "no_status" for w in streams.warnings):
            session.streams(strict_status=True)  # raises NoStatusError, naming the node
        final = measure_streams(streams, cfg, params, options)
    except (MeasurementError, NoStatusError) as exc:
        if last is None:
            raise
        final = _kept_estimate(last, exc)
    prov = Provenance(
        software=SOFTWARE,
        run_file=session.run_path,
        config_sha256=config_digest(session.config_toml),
        config_source="the stand's configuration",
        start_time=session.writer.start_time,
        source=session.where,
        frames=streams.frames,
        duration_s=streams.duration_s,
        config_toml=session.config_toml,
        matrix=None if options.matrix is None else options.matrix.path,
        job=job_of(session.run_attrs, session.run_path),
        rotor_type=cfg.rotor.type,
        stand_id=cfg.stand.stand_id(),
    )
    goal = targets(final.solution.U_kg_m)
    return build_result(
        final,
        cfg,
        params,
        stream_warnings=streams.warnings,
        provenance=prov,
        options=options,
        streams=streams,
        live=LiveInfo(stopped_by, elapsed, goal),
    )


SEED_ATTR = "scene_seed"
"""The run file's attribute naming a simulated run's noise seed."""


def measure_live(
    source: LiveSource,
    bus_kwargs: dict[str, Any],
    run_path: str,
    options: SolveOptions,
    targets: Callable[[Any, Any, Any], tuple[float, float]],
    *,
    max_seconds: float,
    silence_timeout_s: float,
    first_frame_s: float | None = None,
    on_start: Callable[[str], None] | None = None,
    on_progress: Callable[[Progress], None] | None = None,
    on_wait: Callable[[float, str], None] | None = None,
    job: Job | None = None,
    stop: threading.Event | None = None,
    max_interval_s: float | None = None,
    on_play: Callable[[float], None] | None = None,
) -> tuple[Result, LiveSession]:
    """One live session measured until precise: the result, and the session (closed).
    ``job`` (serial, order, operator, note) is recorded with the run; ``stop`` and
    ``max_interval_s`` as in :func:`measure_until_precise`; ``on_play`` is told the
    ``time.monotonic()`` of a scene's physics time 0 (a simulated drive's clock)."""

    cfg, params = source.cfg, source.params
    check_matrix(options, cfg, live=True)
    attrs = {} if options.matrix is None else options.matrix.run_attrs()
    attrs[STAND_ATTR] = cfg.stand.stand_id()
    if source.scene_seed is not None:
        attrs[SEED_ATTR] = str(source.scene_seed)
    if job:
        attrs[JOB_ATTR] = job.to_text()
    with LiveSession(
        bus_kwargs,
        run_path,
        config_toml=source.config_toml,
        scene_frames=source.scene_frames,
        silence_timeout_s=silence_timeout_s,
        first_frame_s=first_frame_s,
        run_attrs=attrs,
        acquisition=source.acquisition,
        modules=source.modules,
        on_play=on_play,
    ) as session:
        if on_start:
            on_start(session.where)
        result = measure_until_precise(
            session,
            cfg,
            params,
            options,
            lambda U: targets(cfg, params, U),
            max_seconds=max_seconds,
            on_progress=on_progress,
            on_wait=on_wait,
            stop=stop,
            max_interval_s=max_interval_s,
        )
    return result, session
