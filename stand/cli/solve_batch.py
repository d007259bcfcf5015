"""`stand solve RUN RUN ... [--jobs N] [--summary FILE]`: many runs, in parallel, one summary."""

from __future__ import annotations

import argparse
import csv
import json
import multiprocessing
import os
import sys
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

from stand.errors import StandError

COLUMNS = [
    "run",
    "rpm",
    "plane1_g_mm",
    "plane1_deg",
    "plane1_uncertainty_g_mm",
    "plane1_pass",
    "plane2_g_mm",
    "plane2_deg",
    "plane2_uncertainty_g_mm",
    "plane2_pass",
    "warnings",
    "error",
]


def _worker(path: str, config: str | None, taper: bool, gate: bool) -> dict[str, Any]:
    """One run, never raising for bad input (our errors do not cross processes whole)."""
    from stand.cli.solve import solve_one

    try:
        return solve_one(path, config, taper, gate)
    except StandError as exc:
        return {"error": str(exc)}


def _row(path: str, res: dict[str, Any]) -> dict[str, Any]:
    row: dict[str, Any] = {k: "" for k in COLUMNS}
    row["run"] = path
    if "error" in res:
        row["error"] = res["error"]
        return row
    row["rpm"] = res["rpm"]
    verdict = {p["plane"]: p["pass"] for p in res.get("tolerance", {}).get("planes", [])}
    for p in res["planes"]:
        i = p["plane"]
        row[f"plane{i}_g_mm"] = p["unbalance_g_mm"]
        row[f"plane{i}_deg"] = p["angle_deg"]
        row[f"plane{i}_uncertainty_g_mm"] = p["uncertainty_g_mm"]
        row[f"plane{i}_pass"] = verdict.get(i, "")
    row["warnings"] = len(res["warnings"])
    return row


def run_batch(args: argparse.Namespace) -> int:
    """Solve every run; a progress bar on stderr; a table on stdout; the summary file."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    runs = list(args.runs)
    results: dict[str, dict[str, Any]] = {}
    gate = not args.no_gate
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
        if args.jobs == 1:
            for path in runs:
                results[path] = _worker(path, args.config, args.taper, gate)
                progress.advance(task)
        else:
            # fresh interpreters with one BLAS thread each: N processes, not N x cores threads
            for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
                os.environ.setdefault(var, "1")
            context = multiprocessing.get_context("spawn")
            with ProcessPoolExecutor(max_workers=args.jobs, mp_context=context) as pool:
                futures: dict[Future[dict[str, Any]], str] = {
                    pool.submit(_worker, path, args.config, args.taper, gate): path for path in runs
                }
                for f in as_completed(futures):
                    results[futures[f]] = f.result()
                    progress.advance(task)
    rows = [_row(path, results[path]) for path in runs]
    if args.summary:
        dest = Path(args.summary)
        if dest.suffix.lower() == ".json":
            dest.write_text(json.dumps({p: results[p] for p in runs}, indent=1))
        else:
            with dest.open("w", newline="") as handle:
                w = csv.DictWriter(handle, fieldnames=COLUMNS)
                w.writeheader()
                w.writerows(rows)
    if args.json:
        json.dump({p: results[p] for p in runs}, sys.stdout)
        print()
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
