"""The live display of ``stand measure`` and ``stand balance``: one fixed panel (rich).

On a terminal the panel is redrawn in place at each live solve: speed, each
plane's unbalance and angle, its 95 % interval against the precision goal,
its tolerance, the supports' 1x; what the measurement is waiting for.
Elsewhere (a pipe, a log file) the same figures go out as one line per
solve (:func:`progress_line`).  :func:`measure_live_from_args` runs the live
measurement the options of ``stand measure`` and ``stand balance`` ask for,
with this display; :func:`scene_masses` the masses they put on a simulated rotor and
:func:`archive_live` the archiving of their run (kept out of :mod:`stand.cli.common`, so
that ``stand solve`` loads neither the simulator nor the database).  :class:`ProgressLine`
is the same display's plain cousin for long offline work (a simulation, a series): a line
on stderr now and then, none for a job done within a few seconds.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from typing import Any, TextIO

from stand.cli.common import (
    actor_of,
    bus_kwargs,
    check_live_arguments,
    job_from,
    run_path,
    silences,
)
from stand.config import Config
from stand.core import rad_s_to_rpm, unbalance_to_polar
from stand.errors import ArchiveError, CycleAbortedError, StandError, UsageError
from stand.field.speeds import correction_masses_across_speeds
from stand.i18n import Display
from stand.i18n.language import ENGLISH, N_, Language, language
from stand.live import live_source, measure_live
from stand.live.cycle import run_cycle
from stand.sim import Mass
from stand.solve import Job
from stand.solve.recordings import correction_masses
from stand.solve.result import job_field_problem
from stand.solve.verdict import tolerance_of

ANGLE_HELP = N_("angles from the reference mark, against the direction of rotation")


def progress_line(p: Any, units: Display | None = None, _: Language = ENGLISH) -> str:
    """One line of the live display (when stderr is not a terminal)."""
    u = units or Display()
    m = p.measurement
    planes = "  ".join(
        _("plane {plane}: {unbalance} +- {r95} (precision goal +- {goal})").format(
            plane=i + 1, unbalance=u.unbalance(abs(m.solution.U_kg_m[i]) * 1e6),
            r95=u.number(m.radius95_kg_m[i] * 1e6), goal=u.number(p.targets_kg_m[i] * 1e6))
        for i in range(2)
    )  # fmt: skip
    amps = " ".join(u.decimals(f"{abs(ph.A_m_s2):.3f}") for ph in m.supports)
    rpm = float(rad_s_to_rpm(m.omega_rad_s))
    more = "".join(f"  ({w})" for w in _waits(p, "", _))
    speed = _("{rpm} rpm").format(rpm=f"{rpm:7.1f}")
    took = _("{seconds} s").format(seconds=f"{p.elapsed_s:5.1f}")
    return u.decimals(f"  {took}  {speed}") + f"  1x {amps} m/s2  {planes}{more}"


def panel(
    where: str,
    run_path: str,
    progress: Any | None,
    *,
    tolerance_kg_m: tuple[float, float] | None,
    units: Display,
    waiting: str = "",
    elapsed_s: float = 0.0,
    _: Language = ENGLISH,
) -> Any:
    """The panel for the latest solve (``progress``; None before the first)."""
    from rich.console import Group
    from rich.panel import Panel
    from rich.table import Table
    from rich.text import Text

    u = units
    t = elapsed_s if progress is None else progress.elapsed_s
    head = Text("")
    if progress is not None:
        rpm = float(rad_s_to_rpm(progress.measurement.omega_rad_s))
        head.append(_("{rpm} rpm").format(rpm=u.decimals(f"{rpm:.1f}")) + "   ",
                    style="bold cyan")  # fmt: skip
    head.append(_("{seconds} s").format(seconds=u.decimals(f"{t:.1f}")) + "   ")
    head.append(_("measuring on {where}").format(where=_(where)), style="dim")
    table = Table(box=None, expand=False, pad_edge=False, header_style="bold")
    for name, justify, width in (
        (_("plane"), "center", 5),
        (_("unbalance") + f"\n[{u.unbalance_unit}]", "right", 9),
        (_("angle") + f"\n[{_('deg')}]", "right", 5),
        (_("95 %\ninterval"), "right", 8),
        (_("precision\ngoal"), "right", 9),
        (_("tolerance") + f"\n[{u.unbalance_unit}]", "right", 9),
        ("", "left", 14),
    ):
        table.add_column(Text(name), justify=justify, no_wrap=True, min_width=width)  # type: ignore[arg-type]
    rows: list[Any] = []
    if progress is not None:
        m = progress.measurement
        for i in range(2):
            U, r95, goal = abs(m.solution.U_kg_m[i]), m.radius95_kg_m[i], progress.targets_kg_m[i]
            per = None if tolerance_kg_m is None else tolerance_kg_m[i]
            angle = float(unbalance_to_polar([m.solution.U_kg_m[i]])[1][0])
            precise = r95 <= goal
            state = (Text(_("precise"), style="green") if precise
                     else Text(_("measuring"), style="yellow"))  # fmt: skip
            if per is not None and U + r95 <= per:
                state = Text(_("within tolerance"), style="bold green")
            elif per is not None and U - r95 > per:
                state.append("\n" + _("over tolerance"), style="red")
            rows.append(
                (
                    str(i + 1),
                    Text(u.number(U * 1e6), style="bold"),
                    "-" if U <= r95 else u.decimals(f"{angle:.1f}"),
                    f"± {u.number(r95 * 1e6)}",
                    f"± {u.number(goal * 1e6)}",
                    "-" if per is None else u.number(per * 1e6),
                    state,
                )
            )
        amps = _(" and ").join(u.decimals(f"{abs(ph.A_m_s2):.4f}") for ph in m.supports)
    for row in rows or [("1", "", "", "", "", "", ""), ("2", "", "", "", "", "", "")]:
        table.add_row(*row)
    recording = _("recording into {run} (Ctrl-C stops)").format(run=run_path)
    parts: list[Any] = [head, Text(recording, style="dim"), table]
    if progress is not None:
        parts.append(Text(_("1x at supports 1 and 2: {amps} m/s²").format(amps=amps) + "\n"
                          + _(ANGLE_HELP), style="dim"))  # fmt: skip
    parts += [Text(line, style="yellow") for line in _waits(progress, waiting, _)]
    return Panel(Group(*parts), title="stand", title_align="left")


def _waits(progress: Any | None, waiting: str, _: Language = ENGLISH) -> list[str]:
    """What the run waits for, in words: what the estimate still lacks, and the bus."""
    why = getattr(progress, "waiting_for", ())
    out = ([_("still measuring: waiting for {what}").format(what=_(" and ").join(map(_, why)))]
           if why else [])  # fmt: skip
    return out + ([_("waiting: {why}").format(why=_(waiting))] if waiting else [])


class LiveDisplay:
    """The live progress: :func:`panel` redrawn in place on a terminal,
    one line per solve elsewhere, nothing with ``--quiet``."""

    def __init__(self, source: Any, path: str, *, quiet: bool, words: Language = ENGLISH) -> None:

        tol = tolerance_of(source.cfg, source.params)
        self.tolerance = None if tol is None else tol.per_plane_kg_m
        self.units = Display.speaking(words, source.cfg.display.mass, source.cfg.display.length)
        self._ = words
        self.path, self.quiet = path, quiet
        self.where, self.last, self.waiting, self.elapsed = "", None, "", 0.0
        self.live: Any = None
        if not quiet and sys.stderr.isatty():
            from rich.console import Console
            from rich.live import Live

            self.live = Live(console=Console(stderr=True), auto_refresh=False)

    def __enter__(self) -> LiveDisplay:
        if self.live is not None:
            self.live.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.live is not None:
            self.live.__exit__(*exc)

    def _redraw(self) -> None:
        view = panel(
            self.where, self.path, self.last, tolerance_kg_m=self.tolerance, units=self.units,
            waiting=self.waiting, elapsed_s=self.elapsed, _=self._,
        )  # fmt: skip
        self.live.update(view, refresh=True)

    def _say(self, text: str) -> None:
        if not self.quiet:
            print(text, file=sys.stderr)

    def start(self, where: str) -> None:
        self.where = where
        if self.live is not None:
            return self._redraw()
        self._say(self._("measuring on {where}, recording into {run} (Ctrl-C stops)").format(
            where=self._(where), run=self.path))  # fmt: skip

    def progress(self, p: Any) -> None:
        self.last, self.waiting = p, ""
        if self.live is not None:
            return self._redraw()
        self._say(progress_line(p, self.units, self._))

    def wait(self, elapsed: float, why: str) -> None:
        self.waiting, self.elapsed = why, elapsed
        if self.live is not None:
            return self._redraw()
        self._say(self.units.decimals(f"  {elapsed:5.1f} s  ")
                  + self._("waiting: {why}").format(why=self._(why)))  # fmt: skip


def mes_job(args: argparse.Namespace, cfg: Config) -> Job:
    """``--job ID``: the MES's job order of this stand (OPC 40001-3), now Running: the
    run's serial, order and operator are the job's (UsageError when there is no such job
    order waiting or running, when it is for another rotor type, or when the options name
    the job's fields too)."""
    from stand.actions import start_job  # SQLAlchemy: only when a job is named
    from stand.archive import url_for

    if problem := job_field_problem("job_id", args.job):  # "" is no job order: refused
        raise UsageError(f"--job: {problem.partition(': ')[2]}")
    given = [f"--{name}" for name in ("serial", "order", "operator") if getattr(args, name, None)]
    if given:
        raise UsageError(f"--job takes the serial, order and operator from the job order: "
                         f"leave out {', '.join(given)}")  # fmt: skip
    stand = cfg.stand.stand_id()
    url = url_for(getattr(args, "archive", None), cfg)
    job = start_job(url, actor_of(args, url), stand, args.job)
    if job is None:
        raise UsageError(f"--job {args.job[:64]!r}: stand {stand} has no such job order "
                         "waiting or running (stand jobs lists them)")  # fmt: skip
    if cfg.rotor.type and job["rotor_type"] != cfg.rotor.type:
        raise UsageError(f"--job {args.job!r} is for rotor type {job['rotor_type']!r}, the "
                         f"config is {cfg.rotor.type!r}")  # fmt: skip
    return Job(serial=job["serial"], order=job["order"], operator=job["operator"],
               note=getattr(args, "note", None), job_id=job["job_id"])  # fmt: skip


def measure_live_from_args(
    args: argparse.Namespace, command: str, targets: Any, options: Any
) -> tuple[Any, Any, Any]:
    """``stand measure`` and ``stand balance``: the live run the options ask for, with its
    progress on stderr (a fixed panel on a terminal, else a line per solve); returns the
    :class:`stand.solve.result.Result`, config and parameters."""

    check_live_arguments(args, command)
    source = live_source(
        args.scene, args.config, command, scene_masses(args), getattr(args, "rpm", None),
        getattr(args, "index", None),
    )  # fmt: skip
    kwargs = source.scene_bus
    if kwargs is None:
        kwargs = bus_kwargs(args, source.bus_table)
    path = run_path(args)
    job = mes_job(args, source.cfg) if getattr(args, "job", None) is not None else job_from(args)
    show = LiveDisplay(source, path, quiet=args.quiet, words=language(getattr(args, "lang", None)))
    silence, first = silences(args)

    def measure(stop: Any = None, on_play: Any = None, watch: Any = None) -> Any:
        def progress(p: Any) -> None:
            show.progress(p)
            if watch is not None:
                watch(p)

        result, session = measure_live(
            source, kwargs, path, options, targets, max_seconds=args.max_seconds,
            silence_timeout_s=silence, first_frame_s=first, on_start=show.start,
            on_progress=progress, on_wait=show.wait, job=job, stop=stop, on_play=on_play,
        )  # fmt: skip
        if session.failure is not None and not args.quiet:
            print(f"stand: {session.failure}", file=sys.stderr)
        return result

    with show:
        if source.drive is None:
            result = measure()
        else:
            try:
                result = run_cycle(source.drive, source.cfg, measure, run_path=path,
                                   rpm=getattr(args, "rpm", None),
                                   plane2=lambda: ask_plane2(args))  # fmt: skip
            except CycleAbortedError as exc:
                journal_aborted(args, source.cfg, exc)
                raise
    return result, source.cfg, source.params


def ask_plane2(args: argparse.Namespace) -> bool:
    """Turn plane 2's correction place to the mark too: ``--index-both``, or the operator
    says so at a terminal."""
    if getattr(args, "index_both", False):
        return True
    if args.json or not sys.stdin.isatty():
        return False
    _ = language(getattr(args, "lang", None))
    print(_("plane 1's correction place is at the mark; Enter turns plane 2's there, "
            "q and Enter ends"), file=sys.stderr)  # fmt: skip
    return input().strip().lower() != "q"


def scene_masses(args: argparse.Namespace) -> list[Any]:
    """The masses ``--add`` and ``--apply`` put on the simulated rotor."""

    masses = [Mass(p, g, a, None if r is None else r * 1e-3) for p, g, a, r in args.add]
    runs = getattr(args, "apply", None) or []
    if len(runs) == 1:
        masses += [Mass(p, g, a, r) for p, g, a, r in correction_masses(runs[0])]
    elif runs:
        slow = getattr(args, "apply_slow_roll", None)
        masses += [
            Mass(p, g, a, r, x)
            for p, g, a, r, x in correction_masses_across_speeds(runs, slow_roll=slow)
        ]
    return masses


def journal_aborted(args: argparse.Namespace, cfg: Config, exc: CycleAbortedError) -> None:
    """An aborted cycle into the audit trail (unless ``--no-archive``); an archive out of
    reach is said, and the abort still reported."""
    if args.no_archive:
        return
    from stand.actions import journal_abort
    from stand.archive import url_for

    url = url_for(args.archive, cfg)
    try:
        journal_abort(url, actor_of(args, url), exc.reason, exc.run_file)
    except StandError as err:
        print(f"stand: the abort is not journaled: {err}", file=sys.stderr)


def archive_live(args: argparse.Namespace, result: Any, cfg: Config) -> None:
    """Archive a live run (unless ``--no-archive``); say where on stderr."""
    if args.no_archive or not result.provenance.run_file:
        return
    from stand.actions import archive_run, config_seen  # after the answer: SQLAlchemy
    from stand.archive import url_for
    from stand.plant import publish_archived

    url = url_for(args.archive, cfg)
    actor = actor_of(args, url)
    try:
        if args.config:  # a rotor type's file edited since it was last used: journaled
            config_seen(url, actor, args.config)
        run_id = archive_run(result, url, actor, config=args.config)
    except ArchiveError as exc:
        raise ArchiveError(
            f"{str(exc).split(': ', 1)[1]} (the run is kept in {result.provenance.run_file}: "
            "stand archive import it later)",
            url=exc.url,
        ) from exc
    _ = language(getattr(args, "lang", None))
    if not args.quiet:
        print(_("archived as run {id}").format(id=run_id), file=sys.stderr)

    said = publish_archived(result, run_id, cfg, url)
    if said and (not args.quiet or said.startswith("not")):
        print(said, file=sys.stderr)


AFTER_S = 3.0
"""No line before the work has run this long [s]."""
EVERY_S = 3.0
"""At most one line this often [s]."""


class ProgressLine:
    """Throttled progress lines ``"<what>: <how far> (<n> s)"`` on a stream.

    Parameters
    ----------
    what
        What runs (``"simulating demo-balls"``).
    stream
        Where the lines go (default stderr: stdout stays the answer).
    clock
        Seconds from any origin (default :func:`time.monotonic`).
    """

    def __init__(self, what: str, *, stream: TextIO | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:  # fmt: skip
        self.what = what
        self.stream = stream
        self.clock = clock
        self.start = clock()
        self.last = -float("inf")
        self.lines = 0

    def say(self, how_far: str) -> None:
        """Print ``how_far`` if the work has run :data:`AFTER_S` and no line came within
        :data:`EVERY_S`."""
        now = self.clock()
        if now - self.start < AFTER_S or now - self.last < EVERY_S:
            return
        self.last = now
        self.lines += 1
        print(f"{self.what}: {how_far} ({now - self.start:.0f} s)",
              file=self.stream or sys.stderr, flush=True)  # fmt: skip

    def simulated(self, t_s: float, end_s: float) -> None:
        """A simulation's physics time reached of its end [s] (a ``simulate`` progress)."""
        self.say(f"{min(max(t_s, 0.0), end_s):.0f} of {end_s:.0f} s simulated")

    def count(self, done: int, total: int, noun: str) -> None:
        """``done`` of ``total`` things (``"rotor"``) finished."""
        self.say(f"{noun} {done} of {total} done")
