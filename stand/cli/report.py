"""Write the balancing report of a run: one self-contained HTML file."""

from __future__ import annotations

import argparse

from stand.cli.common import add_measure_arguments, add_uncertainty_arguments, solve_options


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


def run(args: argparse.Namespace) -> int:
    from stand.pipeline import solve_recording
    from stand.report import write_report

    write_report(solve_recording(args.run, args.config, solve_options(args, traces=True)), args.out)
    print(f"wrote {args.out}")
    return 0
