"""Solve recorded runs: the unbalance of both planes, with its 95 % interval."""

from __future__ import annotations

import argparse

from stand.cli.common import add_measure_arguments, add_uncertainty_arguments, solve_options
from stand.errors import UsageError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("runs", nargs="+", metavar="RUN", help="run files (.h5) or python-can logs")
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration (default: the one stored in the run file)",
    )
    add_measure_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object (one run)")
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        metavar="N",
        help="solve several runs in N processes (default 1)",
    )
    p.add_argument("--summary", metavar="FILE", help="write a summary of all runs: .csv or .json")
    add_uncertainty_arguments(p)


def run(args: argparse.Namespace) -> int:
    if args.jobs < 1:
        raise UsageError(f"stand solve: --jobs must be >= 1, got {args.jobs}")
    if args.summary and not args.summary.lower().endswith((".csv", ".json")):
        raise UsageError(f"stand solve: --summary must end in .csv or .json, got {args.summary!r}")
    options = solve_options(args)
    if len(args.runs) > 1 or args.summary:
        from stand.cli.solve_batch import run_batch

        return run_batch(args, options)
    from stand.cli.format import show
    from stand.pipeline import solve_recording
    from stand.result import to_json

    show(to_json(solve_recording(args.runs[0], args.config, options)), args.json)
    return 0
