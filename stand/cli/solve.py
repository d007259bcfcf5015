"""Solve recorded runs: the unbalance of both planes, with its 95 % interval.

Several runs (``--jobs N``, ``--summary FILE``) are one batch: a progress bar on
stderr, a line per run on stdout, a ``.csv`` or ``.json`` summary.
"""

from __future__ import annotations

import argparse
import csv
import io
import sys
from pathlib import Path
from typing import Any

from stand.cli.common import (
    add_across_speeds_arguments,
    add_force_argument,
    add_language_argument,
    add_measure_arguments,
    add_uncertainty_arguments,
    solve_options,
    write_text_output,
)
from stand.cli.format import dump_json, print_speeds, show
from stand.errors import StandError, UsageError
from stand.field import balance_speeds, speeds_json
from stand.files import check_output
from stand.i18n.language import language
from stand.solve import json_text, to_json
from stand.solve.recordings import solve_many, solve_recording


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
    add_force_argument(p, "--summary")
    add_across_speeds_arguments(p)
    add_language_argument(p)


def run(args: argparse.Namespace) -> int:
    if args.jobs < 1:
        raise UsageError(f"stand solve: --jobs must be >= 1, got {args.jobs}")
    if args.summary and not args.summary.lower().endswith((".csv", ".json")):
        raise UsageError(f"stand solve: --summary must end in .csv or .json, got {args.summary!r}")
    if args.across_speeds:
        return run_across_speeds(args)
    return _run(args)


def _run(args: argparse.Namespace) -> int:
    """One run (its result) or a batch (a line a run, the summary)."""
    if args.method != "ls" or args.max_mass_g is not None:
        raise UsageError("stand solve: --method and --max-mass-g go with --across-speeds")
    options = solve_options(args)
    if args.summary:  # refuse a summary that cannot be written before solving
        check_output(
            args.summary, force=args.force, inputs=[*args.runs, *filter(None, [args.config])]
        )
    if len(args.runs) > 1 or args.summary:
        return run_batch(args, options)

    result = solve_recording(args.runs[0], args.config, options)
    show(to_json(result), args.json, language(args.lang))
    return 0


COLUMNS = [
    "run",
    "rpm",
    "plane1_g_mm",
    "plane1_deg",
    "plane1_uncertainty_g_mm",
    "plane1_verdict",
    "plane2_g_mm",
    "plane2_deg",
    "plane2_uncertainty_g_mm",
    "plane2_verdict",
    "verdict",
    "warnings",
    "error",
]


def _row(path: str, res: dict[str, Any]) -> dict[str, Any]:
    row: dict[str, Any] = {k: "" for k in COLUMNS}
    row["run"] = path
    if "error" in res:
        row["error"] = res["error"]
        return row
    row["rpm"] = res["rpm"]
    crit = res.get("tolerance", {}).get("criteria", [])
    verdict = {c["plane"]: c["verdict"] for c in crit if c["plane"] is not None}
    row["verdict"] = res["verdict"]
    for p in res["planes"]:
        i = p["plane"]
        row[f"plane{i}_g_mm"] = p["unbalance_g_mm"]
        row[f"plane{i}_deg"] = p["angle_deg"]
        row[f"plane{i}_uncertainty_g_mm"] = p["uncertainty_g_mm"]
        row[f"plane{i}_verdict"] = verdict.get(i, "")
    row["warnings"] = len(res["warnings"])
    return row


def run_batch(args: argparse.Namespace, options: Any) -> int:
    """Solve every run; a progress bar on stderr; a table on stdout; the summary file."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    runs = list(args.runs)
    results: dict[str, dict[str, Any]] = {}
    progress = Progress(
        "[progress.description]{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=False,
    )
    with progress:
        task = progress.add_task("solving", total=len(runs))
        for path, res in solve_many(
            runs, args.config, options, args.jobs, lambda: progress.advance(task)
        ):
            results[path] = {"error": str(res)} if isinstance(res, StandError) else to_json(res)
    rows = [_row(path, results[path]) for path in runs]
    if args.summary:
        if Path(args.summary).suffix.lower() == ".json":
            text = json_text({p: results[p] for p in runs}, indent=1)
        else:
            buf = io.StringIO(newline="")
            w = csv.DictWriter(buf, fieldnames=COLUMNS)
            w.writeheader()
            w.writerows(rows)
            text = buf.getvalue()
        write_text_output(args.summary, text, force=args.force, inputs=[*runs, args.config])
    if args.json:
        dump_json({p: results[p] for p in runs})
    else:
        for r in rows:
            if r["error"]:
                print(f"{r['run']}: error: {r['error']}")
            else:
                print(
                    f"{r['run']}: {r['rpm']:.1f} rpm  plane 1 {r['plane1_g_mm']:.1f} g mm at "
                    f"{r['plane1_deg']:.1f} deg  plane 2 {r['plane2_g_mm']:.1f} g mm at "
                    f"{r['plane2_deg']:.1f} deg"
                )
    failed = [r for r in rows if r["error"]]
    if failed:
        print(
            f"stand: error: {len(failed)} of {len(rows)} runs could not be solved "
            f"(first: {failed[0]['run']}: {failed[0]['error']})",
            file=sys.stderr,
        )
        return 2
    return 0


def run_across_speeds(args: argparse.Namespace) -> int:
    """One correction in N planes for the runs at several speeds; per speed, what it leaves."""

    if args.summary or args.jobs != 1:
        raise UsageError("stand solve: --across-speeds gives one answer: no --summary or --jobs")
    out = speeds_json(
        balance_speeds(
            args.runs,
            args.config,
            method=args.method,
            max_mass_g=args.max_mass_g,
            slow_roll=args.slow_roll,
        )
    )
    if args.json:
        dump_json(out)
        return 0
    print_speeds(out)
    for w in out["warnings"]:
        print(f"warning: {w}", file=sys.stderr)
    return 0
