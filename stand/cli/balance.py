"""Balance: measure live until precise, then the correction per plane, the tolerance, the check."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from stand.cli.common import DEFAULT_TARGET_PCT, TOLERANCE_SHARE, add_live_measure_arguments


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


def run(args: argparse.Namespace) -> int:
    from stand.check import with_check
    from stand.cli.common import (
        archive_live,
        solve_options,
        targets_from,
    )
    from stand.cli.format import show
    from stand.cli.panel import measure_live_from_args
    from stand.result import to_json

    if args.report:  # refuse a report path that cannot be written before measuring
        from stand.drivers.files import check_output

        check_output(
            args.report, force=args.force, inputs=[i for i in (args.check, args.config) if i]
        )
    options = solve_options(args, traces=True)
    result, cfg, params = measure_live_from_args(
        args, "balance", targets_from(args, TOLERANCE_SHARE), options
    )
    if args.check:
        result = with_check(
            result, args.check, cfg, params, strict=not args.check_any, matrix=options.matrix
        )
    report = args.report or str(Path(result.provenance.run_file or "run").with_suffix(".html"))
    out = to_json(result)
    out["report"] = report
    show(out, args.json)  # the answer first: the report takes a moment
    sys.stdout.flush()
    from stand.cli.common import write_text_output
    from stand.report import render

    inputs = [i for i in (result.provenance.run_file, args.check, args.config) if i]
    write_text_output(report, render(result), force=args.force, inputs=inputs)
    if not args.json:
        print(f"report: {report}")
    archive_live(args, result, cfg)  # last: an archive that fails loses neither run nor report
    return 0
