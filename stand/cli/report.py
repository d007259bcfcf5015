"""Write the balancing report of a run: one self-contained HTML file."""

from __future__ import annotations

import argparse

from stand.cli.common import (
    add_force_argument,
    add_measure_arguments,
    add_uncertainty_arguments,
    solve_options,
    write_text_output,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run", metavar="RUN", help="run file (.h5) or python-can log")
    p.add_argument("-o", "--out", required=True, metavar="REPORT.html", help="the report to write")
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration (default: the one stored in the run file)",
    )
    add_measure_arguments(p)
    add_uncertainty_arguments(p)
    add_force_argument(p, "REPORT.html")


def run(args: argparse.Namespace) -> int:
    from stand.drivers.files import check_output
    from stand.pipeline import solve_recording
    from stand.report import render

    inputs = [i for i in (args.run, args.config) if i]
    check_output(args.out, force=args.force, inputs=inputs)  # before the work
    result = solve_recording(args.run, args.config, solve_options(args, traces=True))
    write_text_output(args.out, render(result), force=args.force, inputs=inputs)
    print(f"wrote {args.out}")
    return 0
