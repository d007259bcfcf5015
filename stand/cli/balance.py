"""Balance: measure live until precise, then the correction per plane, the tolerance, the check."""

from __future__ import annotations

import argparse
import copy
import sys
from pathlib import Path

from stand.cli.common import (
    DEFAULT_TARGET_PCT,
    TOLERANCE_SHARE,
    add_across_speeds_arguments,
    add_live_measure_arguments,
    run_path,
    solve_options,
    targets_from,
    write_text_output,
)
from stand.cli.format import dump_json, print_speeds, show
from stand.cli.panel import archive_live, measure_live_from_args
from stand.config import SAME_SPEED, Config
from stand.config.typed import parse_mass, parse_rpm
from stand.core import rad_s_to_rpm
from stand.errors import ArchiveError, StandError, UsageError
from stand.field import balance_speeds, speeds_json
from stand.files import check_output
from stand.health import datum_row, with_drift
from stand.i18n.language import language
from stand.process import warm_imports
from stand.report import render, render_speeds
from stand.solve import to_json, with_check
from stand.solve.recordings import result_masses, solve_recording


def parse_masses(text: str) -> list[tuple[int, float, float, float | None]]:
    """``1:55.5@30,2:-12@200:80``: the masses put on, as ``--add`` takes each."""

    return [parse_mass(x) for x in text.split(",")]


def parse_speeds(text: str) -> list[float]:
    """``900,1500,1800``: two speeds or more [rpm], each given once."""
    speeds = [parse_rpm(x) for x in text.split(",")]
    if len(speeds) < 2 or len(set(speeds)) != len(speeds):
        raise argparse.ArgumentTypeError(
            f"expected two speeds or more, each once (e.g. 900,1500,1800), got {text!r}"
        )
    return speeds


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_live_measure_arguments(
        p,
        default_target=f"{100 * TOLERANCE_SHARE:g} %% of each plane's ISO tolerance, or "
        f"{DEFAULT_TARGET_PCT:g} %% of the unbalance without a [tolerance] table",
    )
    p.add_argument(
        "--report",
        metavar="REPORT.html",
        help="where to write the report (default: beside the run file)",
    )
    p.add_argument(
        "--check-any",
        action="store_true",
        help="--check against a run of another rotor, stand or speed anyway",
    )
    p.add_argument("--force", action="store_true", help="replace --report if it exists")
    p.add_argument(
        "--check",
        metavar="PREVIOUS_RUN",
        help="the run before the correction: show the residual unbalance and the "
        "unbalance reduction ratio per plane",
    )
    p.add_argument(
        "--speeds",
        type=parse_speeds,
        metavar="RPM,RPM,...",
        help="balance a bending rotor across speeds: a run at each speed in turn (the "
        "operator is asked to set each; a --scene runs at each), then one correction in the "
        "config's [[rotor.planes]] (as stand solve --across-speeds)",
    )
    add_across_speeds_arguments(p, flag=False)
    g = p.add_argument_group("the check as a calibration datum (stand health)")
    g.add_argument(
        "--applied",
        action="store_true",
        help="with --check: the operator confirms the correction PREVIOUS_RUN prescribed was "
        "put on as shown: the pair is stored as a calibration datum",
    )
    g.add_argument(
        "--applied-masses",
        type=parse_masses,
        metavar="PLANE:GRAMS@DEG[:RADIUS_MM],...",
        help="with --check: what was put on instead (negative grams: taken off): the pair is "
        "stored as a calibration datum with these masses",
    )


AFTER_THE_MEASUREMENT = ("stand.archive", "alembic.command", "stand.report.plots",
                         "matplotlib.pyplot")  # fmt: skip
"""What ``stand balance`` needs after its measurement (the stand's drift from the archive,
the report): imported while it measures (:func:`stand.process.warm_imports`)."""


def run(args: argparse.Namespace) -> int:

    if args.speeds:
        return _across_speeds(args)
    if (args.applied or args.applied_masses) and not args.check:
        raise UsageError("stand balance: --applied and --applied-masses go with --check")
    if args.report:  # refuse a report path that cannot be written before measuring
        check_output(
            args.report, force=args.force, inputs=[i for i in (args.check, args.config) if i]
        )
    options = solve_options(args, traces=True)
    warm_imports(AFTER_THE_MEASUREMENT)  # while the physics runs, not after it
    result, cfg, params = measure_live_from_args(
        args, "balance", targets_from(args, TOLERANCE_SHARE), options
    )
    from stand.archive import drift_rows, url_for

    if args.check:
        result = with_check(
            result, args.check, cfg, params, strict=not args.check_any, matrix=options.matrix
        )
    if not args.no_archive:  # a stand that drifted from its calibration says so, widened
        try:
            result = with_drift(
                drift_rows(url_for(args.archive, cfg), result), result, cfg, params, options
            )
        except ArchiveError:  # an archive out of reach is said once, when the run goes in
            pass
        except StandError as exc:
            print(f"stand health not checked: {exc}", file=sys.stderr)
    report = args.report or str(Path(result.provenance.run_file or "run").with_suffix(".html"))
    out = to_json(result)
    out["report"] = report
    _ = language(args.lang)
    show(out, args.json, _)  # the answer first: the report takes a moment
    sys.stdout.flush()

    inputs = [i for i in (result.provenance.run_file, args.check, args.config) if i]
    write_text_output(report, render(result, _), force=args.force, inputs=inputs)
    if not args.json:
        print(_("report: {path}").format(path=report))
    archive_live(args, result, cfg)  # last: an archive that fails loses neither run nor report
    if args.check:
        _store_datum(args, result, cfg, params)
    return 0


def _store_datum(args: argparse.Namespace, result: object, cfg: Config, params: object) -> None:
    """A check after a confirmed correction: the pair into the archive (stand health)."""

    if not (args.applied or args.applied_masses):
        print(
            "not a calibration datum: confirm the correction was put on as shown with "
            "--applied (or --applied-masses)",
            file=sys.stderr,
        )
        return
    if args.no_archive:
        print("not stored as a calibration datum: --no-archive", file=sys.stderr)
        return
    from stand.archive import Archive, file_digest, url_for

    run_file = result.provenance.run_file  # type: ignore[attr-defined]
    before = solve_recording(args.check)
    if args.applied_masses:
        R = (params.R1, params.R2)  # type: ignore[attr-defined]
        masses = [
            (p, g, a, R[p - 1] if r is None else r * 1e-3) for p, g, a, r in args.applied_masses
        ]
    else:
        masses = result_masses(before)
    row = datum_row(
        before,
        result,
        masses,
        initial_sha256=file_digest(args.check),
        check_sha256=file_digest(run_file),
        confirmed_by=args.operator,
        applied="typed" if args.applied_masses else "as shown",
    )
    with Archive(url_for(args.archive, cfg)) as a:
        a.add_correction(row)
    if not args.quiet:
        print("stored as a calibration datum (stand health)", file=sys.stderr)


def _across_speeds(args: argparse.Namespace) -> int:
    """A run at each of ``--speeds`` (recorded as RUN-<rpm>rpm.h5), then the correction
    across them, its report beside the runs."""

    if args.check or args.rpm:
        raise UsageError("stand balance: --speeds sets the speeds: no --check or --rpm")
    stem = Path(run_path(args)).with_suffix("")
    report = args.report or f"{stem}-speeds.html"
    runs = []
    for rpm in args.speeds:
        one = copy.copy(args)
        one.out, one.rpm = f"{stem}-{rpm:g}rpm.h5", rpm
        if not args.scene:  # a real stand: the operator sets the speed
            print(language(args.lang)("set the rotor to {rpm} rpm, then press Enter").format(
                rpm=f"{rpm:g}"), file=sys.stderr)  # fmt: skip
            input()
        result, cfg, _ = measure_live_from_args(
            one, "balance", targets_from(one, TOLERANCE_SHARE), solve_options(one)
        )
        got = float(rad_s_to_rpm(result.omega_rad_s))
        if abs(got / rpm - 1) > SAME_SPEED:
            raise UsageError(f"the run at {rpm:g} rpm went at {got:.0f} rpm: set the speed again")
        archive_live(one, result, cfg)
        runs.append(one.out)
    out = speeds_json(
        balance_speeds(
            runs,
            args.config,
            method=args.method,
            max_mass_g=args.max_mass_g,
            slow_roll=args.slow_roll,
        )
    )
    out["report"] = report
    if args.json:
        dump_json(out)
    else:
        print_speeds(out)
        print(f"report: {report}")

    write_text_output(report, render_speeds(out), force=args.force, inputs=runs)
    return 0
