"""Argument parsing and printing shared by the subcommands (units at the edge)."""

from __future__ import annotations

import argparse
import datetime as dt
import getpass
import math
import sys
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

from stand.calib import Tolerances
from stand.config import Config, read_matrix
from stand.config.typed import parse_angle, parse_date, parse_mass, parse_rpm, positive_float
from stand.drivers.bus import ALLOW_URL
from stand.errors import UsageError
from stand.files import first_line, output
from stand.i18n.language import LANGUAGES
from stand.solve import Job, job_field_problem
from stand.solve.pipeline import SolveOptions, precision_targets

if TYPE_CHECKING:  # the actions load the archive (SQLAlchemy): only when a change is made
    from stand.actions import Actor

ACCEPTANCE_EXIT = {"pass": 0, "fail": 1, "not judged": 3, "undecided": 3}
"""Every acceptance test's exit code: 0 passed, 1 judged and failed, 3 not judged or
undecided (2 is bad input)."""


def add_force_argument(p: argparse.ArgumentParser, what: str) -> None:
    """``--force``: replace ``what`` if it exists (else an existing file is never replaced)."""
    p.add_argument("--force", action="store_true", help=f"replace {what} if it exists")


def write_text_output(
    path: str, text: str, *, force: bool, inputs: Iterable[str | None] = (), newline: str = ""
) -> None:
    """Write a whole text file safely (a temporary name, published when complete; never
    over an input, a special file, or an existing file without ``force``)."""

    data = text.encode("utf-8")
    with output(path, force=force, inputs=[i for i in inputs if i], need_bytes=len(data)) as tmp:
        tmp.write_bytes(data)


def add_scene_arguments(p: argparse.ArgumentParser) -> None:
    """``--add``, ``--apply`` and ``--rpm``: change a simulated scene's rotor and speed."""
    g = p.add_argument_group("the simulated rotor (with a scene)")
    g.add_argument(
        "--add",
        action="append",
        default=[],
        type=parse_mass,
        metavar="PLANE:GRAMS@DEG[:RADIUS_MM]",
        help="put a mass on the rotor (negative grams: take material off), at an angle from "
        "the reference mark against the direction of rotation; the plane's correction radius "
        "unless given (repeatable)",
    )
    g.add_argument(
        "--apply",
        nargs="+",
        metavar="RUN",
        help="apply the correction RUN's result prescribes, as an operator would (its "
        "config's mode, positions and weights); several runs at different speeds: their "
        "correction across speeds in the config's [[rotor.planes]]",
    )
    g.add_argument(
        "--apply-slow-roll",
        metavar="RUN",
        help="with --apply of several runs: the slow-roll run taken out of them first",
    )
    g.add_argument("--rpm", type=parse_rpm, help="run the scene at this speed [rpm]; with a "
                   "[drive], the speed the drive is set to")  # fmt: skip
    g.add_argument(
        "--index",
        type=parse_angle,
        metavar="DEG",
        help="the rotor turned this far on its tooling ([effects.tooling]): 180 for the "
        "second run of `stand tooling measure`",
    )


def add_across_speeds_arguments(p: argparse.ArgumentParser, *, flag: bool = True) -> None:
    """``--across-speeds`` (unless ``flag`` is False), ``--method``, ``--max-mass-g``: one
    rotor's runs at several speeds corrected in the config's ``[[rotor.planes]]``
    (:mod:`stand.field.speeds`)."""
    g = p.add_argument_group("balancing across speeds (a bending rotor)")
    if flag:
        g.add_argument(
            "--across-speeds",
            action="store_true",
            help="the runs are one rotor at several speeds: one correction in the config's "
            "[[rotor.planes]] that keeps every speed low",
        )
    g.add_argument(
        "--method",
        choices=("ls", "wls", "minmax"),
        default="ls",
        help="across speeds: least squares of each speed's share of the tolerance "
        "(default), weighted by each reading's noise, or min-max (the smallest worst share)",
    )
    g.add_argument(
        "--max-mass-g",
        type=positive_float,
        metavar="G",
        help="across speeds: the largest correction mass in any plane [g]",
    )
    g.add_argument(
        "--slow-roll",
        metavar="RUN",
        help="across speeds: a run well below every speed (at least 3x slower): the journals' "
        "runout it reads, scaled as the speed squared, is taken out of every run first",
    )


BUS_KEYS = ("channel", "interface", "bitrate", "fd", "data_bitrate", "can_filters", "timing")
"""python-can's bus options as its own tools parse them (``can.cli``)."""


def add_bus_arguments(p: argparse.ArgumentParser) -> None:
    """python-can's own bus options (``can.cli.add_bus_arguments``: ``-i -c -b --fd
    --data-bitrate --timing --filter --bus-kwargs``, exactly as ``python -m can.logger``
    takes them); they override the config's ``[bus]`` table."""
    from can.cli import add_bus_arguments as python_can_bus_arguments

    python_can_bus_arguments(
        p, filter_arg=True, group_title="bus (python-can's options; they override [bus])"
    )
    p.add_argument(
        "--allow-url-channel",
        action="store_true",
        help="allow a URL as the channel (spy://, loop://, socket://, rfc2217://): serial "
        "interfaces open files and sockets for them; only the command line can allow it",
    )


def bus_kwargs(args: argparse.Namespace, table: Mapping[str, object] | None) -> dict[str, object]:
    """The ``[bus]`` table with the command-line options applied (what goes to ``can.Bus``;
    without an interface anywhere, python-can's own config file and environment)."""

    kwargs = dict(table or {})
    if ALLOW_URL in kwargs:
        raise UsageError(
            f"[bus] {ALLOW_URL}: a file cannot allow URL channels; only --allow-url-channel can"
        )
    given = vars(args)
    for key in BUS_KEYS:
        if key in given and given[key] is not None:
            kwargs[key] = given[key]
    extra = dict(given.get("bus_kwargs") or {})
    if ALLOW_URL in extra:
        raise UsageError(f"--bus-kwargs {ALLOW_URL}: say --allow-url-channel")
    kwargs.update(extra)
    if given.get("allow_url_channel"):
        kwargs[ALLOW_URL] = True
    return kwargs


def add_measure_arguments(p: argparse.ArgumentParser) -> None:
    """How a run is solved: ``--taper``, ``--no-gate``."""
    p.add_argument(
        "--taper",
        action="store_true",
        help="Hann taper against a neighbour close to 1x (costs 1.5x noise variance)",
    )
    p.add_argument(
        "--no-gate",
        action="store_true",
        help="use the whole run, not only its steady, settled part",
    )
    p.add_argument(
        "--later-check",
        action="store_true",
        help="judge as a later check by the user of a rotor balanced elsewhere (ISO 21940-14: "
        "pass if U <= limit + combined error), not as directly after balancing",
    )
    p.add_argument(
        "--matrix",
        metavar="MATRIX.json",
        help="influence mode: use a stored influence matrix (stand influence --save) in place "
        "of the stand model",
    )


def add_uncertainty_arguments(p: argparse.ArgumentParser) -> None:
    """``--uncertainty`` and the parameter tolerances it propagates."""
    g = p.add_argument_group("parameter tolerances (--uncertainty)")
    g.add_argument(
        "--uncertainty",
        action="store_true",
        help="add the spread the parameter tolerances cause (linearised and Monte Carlo)",
    )
    g.add_argument("--tol-c", type=float, default=5.0, metavar="PCT", help="C1, C2 (default 5)")
    g.add_argument(
        "--tol-m", type=float, default=2.0, metavar="PCT", help="M1, M2, M3, J3 (default 2)"
    )
    g.add_argument(
        "--tol-length-mm", type=float, default=1.0, metavar="MM", help="a, b, c, d (default 1)"
    )
    g.add_argument(
        "--tol-gain",
        type=float,
        default=1.0,
        metavar="PCT",
        help="sensor sensitivities (default 1)",
    )
    g.add_argument("--draws", type=int, default=1000, help="Monte Carlo draws (default 1000)")


def solve_options(args: argparse.Namespace, *, traces: bool = False) -> Any:
    """The :class:`stand.solve.pipeline.SolveOptions` the arguments ask for (validated)."""

    tolerances = None
    if getattr(args, "uncertainty", False):
        for name in ("tol_c", "tol_m", "tol_length_mm", "tol_gain"):
            value = getattr(args, name)
            if not (math.isfinite(value) and value >= 0):
                flag = "--" + name.replace("_", "-")
                raise UsageError(f"{flag} must be a finite number >= 0, got {value}")
        if args.draws < 10:
            raise UsageError(f"--draws must be >= 10, got {args.draws}")
        tolerances = Tolerances(
            C_rel=args.tol_c / 100,
            M_rel=args.tol_m / 100,
            length_m=args.tol_length_mm / 1000,
            gain_rel=args.tol_gain / 100,
        )
    matrix = None
    if getattr(args, "matrix", None):
        matrix = read_matrix(args.matrix)
    return SolveOptions(
        matrix=matrix,
        taper=getattr(args, "taper", False),
        gate=not getattr(args, "no_gate", False),
        tolerances=tolerances,
        draws=getattr(args, "draws", 1000),
        traces=traces,
        acceptance="later_check" if getattr(args, "later_check", False) else None,
    )


DEFAULT_TARGET_PCT = 5.0
"""Live precision target without a tolerance: 5 % of each plane's unbalance."""
TOLERANCE_SHARE = 0.10
"""Balancing's precision target: the 95 % interval within 10 % of each plane's ISO
tolerance (``stand balance`` and the station)."""


def add_language_argument(p: argparse.ArgumentParser) -> None:
    """``--lang``: the operator's text (and the certificate) in one of the shipped
    languages; the JSON stays as it is."""
    p.add_argument(
        "--lang",
        choices=list(LANGUAGES),
        metavar="CODE",
        help="the operator's text and the certificate in this language: "
        f"{', '.join(LANGUAGES)} (default en; --json stays English)",
    )


def add_live_measure_arguments(p: argparse.ArgumentParser, *, default_target: str) -> None:
    """``stand measure`` and ``stand balance``: the source, the precision target, the limits,
    the run file."""
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--scene",
        metavar="SCENE",
        help="measure the simulated stand: a shipped scene or a scene file, "
        "played in real time on a private virtual bus",
    )
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration with its [bus] table; with --scene, what the software "
        "believes (calibration, correction, tolerance) about the simulated stand",
    )
    add_scene_arguments(p)
    tgt = p.add_mutually_exclusive_group()
    tgt.add_argument(
        "--target-pct",
        type=float,
        help=f"stop when each plane's 95 %% interval is below this %% of its unbalance "
        f"(default: {default_target})",
    )
    tgt.add_argument(
        "--target-g-mm",
        type=float,
        help="stop when each plane's 95 %% interval is below this [g mm]",
    )
    p.add_argument(
        "--max-seconds",
        type=float,
        default=60.0,
        help="stop after this long in any case (default 60)",
    )
    p.add_argument(
        "--out", metavar="RUN.h5", help="run file to record into (default run-YYYYmmdd-HHMMSS.h5)"
    )
    add_live_arguments(p)
    add_language_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_measure_arguments(p)
    add_job_arguments(p, live=True)
    add_archive_argument(p)
    add_actor_arguments(p)
    p.add_argument("--no-archive", action="store_true", help="do not archive the run")
    p.add_argument("--index-both", action="store_true", help="with a [drive]: after plane 1, "
                   "turn plane 2's correction place to the mark too, without asking")  # fmt: skip
    add_bus_arguments(p)


def add_archive_argument(p: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """``--archive URL``: the archive's database."""
    p.add_argument(
        "--archive",
        metavar="URL",
        help="the archive's database (default: the config's [archive] url, else one SQLite "
        "file in the user's data directory)",
    )


def add_revision_argument(p: argparse.ArgumentParser) -> None:
    """``--revision NAME``: the runs as a ``stand reprocess`` revision re-judged them."""
    p.add_argument(
        "--revision",
        metavar="NAME",
        help="the runs as this revision (stand reprocess) re-judged them: its verdicts and "
        "unbalances in place of the archived ones, only the runs it re-solved",
    )


JOB_FIELDS = ("serial", "order", "operator", "note")


def add_reason_argument(p: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """``--reason TEXT``: why a change is made, for the audit trail (``stand audit``)."""
    p.add_argument("--reason", metavar="TEXT", help="why: recorded in the audit trail")


def add_date_arguments(p: argparse.ArgumentParser) -> None:
    """``--since`` and ``--until``: the archive's runs of these days (UTC), inclusive."""
    p.add_argument(
        "--since", type=parse_date, metavar="YYYY-MM-DD", help="runs from this date on (UTC)"
    )
    p.add_argument(
        "--until", type=parse_date, metavar="YYYY-MM-DD", help="runs up to this date (UTC)"
    )


def add_job_arguments(p: argparse.ArgumentParser, *, live: bool = False) -> None:
    """``--serial``, ``--order``, ``--operator``, ``--note``: the job, recorded with the run."""
    g = p.add_argument_group("the job (recorded with the run and archived)")
    g.add_argument("--serial", metavar="SN", help="the rotor's serial number")
    g.add_argument("--order", metavar="ORDER", help="the order or batch it belongs to")
    g.add_argument("--operator", metavar="NAME", help="who balances it")
    g.add_argument("--note", metavar="TEXT", help="a free note")
    if live:
        g.add_argument(
            "--job",
            metavar="ID",
            help="run under the MES's job order ID (sent over "
            "OPC UA; stand jobs lists them): its serial, order and operator",
        )


def job_from(args: argparse.Namespace) -> Any:
    """The :class:`stand.solve.result.Job` the options give (UsageError for unusable text)."""

    values = {}
    for name in JOB_FIELDS:
        value = getattr(args, name, None)
        problem = None if value is None else job_field_problem(name, value)
        if problem is not None:
            raise UsageError(f"--{problem}")
        values[name] = value
    return Job(**values)


def targets_from(args: argparse.Namespace, tolerance_share: float | None = None) -> Any:
    """``targets(cfg, params, U) -> (kg m, kg m)``: the precision the options ask for."""

    abs_kg_m = None if args.target_g_mm is None else args.target_g_mm * 1e-6

    def targets(cfg: Config, params: Any, U: Any) -> tuple[float, float]:
        return precision_targets(
            cfg, params, U,
            pct=args.target_pct,
            abs_kg_m=abs_kg_m,
            tolerance_share=tolerance_share,
            default_pct=DEFAULT_TARGET_PCT,
        )  # fmt: skip

    return targets


def run_path(args: argparse.Namespace) -> str:
    """The run file: ``--out`` or a timestamped name."""
    return str(args.out or f"run-{dt.datetime.now():%Y%m%d-%H%M%S}.h5")


def add_actor_arguments(p: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """``--as NAME`` and ``--as-password-file FILE``: who makes a change."""
    p.add_argument(
        "--as",
        dest="as_account",
        metavar="NAME",
        help="the account that makes the change (required once the archive has "
        "accounts; its password asked for, or read from --as-password-file)",
    )
    p.add_argument(
        "--as-password-file",
        metavar="FILE",
        help="--as: the account's password (the file's first line), for scripts",
    )


def actor_of(args: argparse.Namespace, url: str) -> Actor:
    """Who runs this command: the account ``--as`` names once its password checks
    (:func:`stand.actions.account_actor`), else the operating system's user (which only a
    lone stand, an archive without accounts, lets make changes)."""
    from stand.actions import account_actor, os_actor

    name = getattr(args, "as_account", None)
    if not name:
        if getattr(args, "as_password_file", None):
            raise UsageError("--as-password-file goes with --as NAME")
        return os_actor("cli")
    if args.as_password_file:
        password = first_line(args.as_password_file, "a password")
    elif sys.stdin.isatty():
        password = getpass.getpass(f"password of {name}: ")
    else:
        raise UsageError(f"--as {name}: give --as-password-file FILE (no terminal to ask on)")
    return account_actor(url, name, password, "cli")


FIRST_FRAME_S = 30.0
"""How long a live command waits for the first frame by default [s]."""
SILENCE_S = 2.0
"""How long a live command lets the bus be silent once frames came, by default [s]."""


def add_live_arguments(p: argparse.ArgumentParser) -> None:
    """Options of every command that reads a live bus."""
    p.add_argument(
        "--timeout",
        type=float,
        default=None,
        metavar="S",
        help=f"end after S seconds without any frame (default {SILENCE_S:g})",
    )
    p.add_argument(
        "--wait",
        type=float,
        default=None,
        metavar="S",
        help=f"wait up to S seconds for the first frame (default {FIRST_FRAME_S:g}, time to "
        "start the rotor or the simulator in another terminal; with --timeout, that)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines")


def silences(args: argparse.Namespace) -> tuple[float, float]:
    """The silence a live command ends after, and the wait for its first frame [s]:
    ``--timeout`` (:data:`SILENCE_S`) and ``--wait`` (:data:`FIRST_FRAME_S`, or the
    ``--timeout`` given: a script that asked for a short one keeps it)."""
    silence = SILENCE_S if args.timeout is None else args.timeout
    if args.wait is not None:
        return silence, args.wait
    return silence, FIRST_FRAME_S if args.timeout is None else args.timeout


def check_live_arguments(args: argparse.Namespace, command: str) -> None:
    """Refuse targets and limits that are not positive."""
    for name in ("target_pct", "target_g_mm", "max_seconds", "timeout", "wait"):
        value = getattr(args, name)
        if value is not None and not value > 0:
            flag = "--" + name.replace("_", "-")
            raise UsageError(f"stand {command}: {flag} must be > 0, got {value}")
