"""``stand reprocess``: archived runs re-judged from their files into a named revision."""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path
from typing import Any

from stand.archive import url_for
from stand.cli.common import add_archive_argument, add_date_arguments, write_text_output
from stand.cli.format import dump_json
from stand.errors import UsageError
from stand.files import check_output
from stand.report import render_reprocess
from stand.reprocess import (
    KINDS,
    DaskEngine,
    LocalEngine,
    Request,
    Selection,
    default_jobs,
    reprocess,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    s = p.add_argument_group("which archived runs")
    s.add_argument("--stand", metavar="ID", help="runs of this stand ([stand] id)")
    s.add_argument("--rotor-type", metavar="TYPE")
    s.add_argument("--serial", metavar="SN")
    s.add_argument("--from-run", type=int, metavar="ID", help="runs from this archive id on")
    s.add_argument(
        "--kind",
        choices=KINDS,
        default="all",
        help="production runs (checking no other), check runs, or all (default)",
    )
    add_date_arguments(p)
    add_archive_argument(p)
    p.add_argument(
        "--revision",
        metavar="NAME",
        required=True,
        help="the revision the re-judged results are stored as, beside the "
        "originals (the same command again goes on where it stopped)",
    )
    p.add_argument(
        "--config",
        metavar="NEW.toml",
        help="re-solve with this config (e.g. the corrected calibration); default: "
        "each run's own stored config (a software update's re-run)",
    )
    p.add_argument(
        "--runs-root",
        metavar="DIR",
        help="the run files lie here now (a moved or shared folder): each is looked "
        "for by its path below the selection's common folder, then by its name",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="solve again runs already in the revision; replace --report FILE",
    )
    w = p.add_argument_group("where the runs are solved")
    w.add_argument(
        "--jobs", type=int, metavar="N", help="processes on this machine (default: all its cores)"
    )
    w.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="a Dask distributed scheduler: its workers solve the runs "
        "(pip install -e '.[cluster]')",
    )
    out = p.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print one JSON object")
    out.add_argument("--report", metavar="FILE.html",
                     help="an HTML page: the recall list, the changed runs, how far each "
                     "answer moved against the tolerance")  # fmt: skip


class Progress:
    """Runs done, runs/s and the time left, on one stderr line (a line every 5 s when
    stderr is not a terminal)."""

    def __init__(self) -> None:
        self.t0 = time.monotonic()
        self.shown = 0.0
        self.tty = sys.stderr.isatty()

    def __call__(self, done: int, total: int) -> None:
        now = time.monotonic()
        if done < total and not self.tty and now - self.shown < 5.0:
            return
        self.shown = now
        rate = done / max(now - self.t0, 1e-9)
        left = (total - done) / rate if rate > 0 else float("inf")
        eta = "" if done == 0 or done == total else f", about {_duration(left)} left"
        width = 30
        bar = "#" * (width * done // max(total, 1))
        line = f"[{bar:<{width}}] {done} of {total} runs, {rate:.1f} runs/s{eta}"
        end = "\n" if done == total or not self.tty else ""
        print(("\r" if self.tty else "") + line, end=end, file=sys.stderr, flush=True)


def _duration(s: float) -> str:
    if s < 90:
        return f"{s:.0f} s"
    return f"{s / 60:.0f} min" if s < 5400 else f"{s / 3600:.1f} h"


REVISION_NAME = re.compile(r"^[^\x00-\x1f\x7f]{1,64}$")


def _check_names(revision: str, runs_root: str | None) -> None:
    """A revision named by something to read (not blank, no control characters, at most 64
    characters), a runs root that is a folder: one line each, before any run is read."""
    if not REVISION_NAME.fullmatch(revision) or not revision.strip():
        raise UsageError(f"--revision {revision[:40]!r}: a name of 1 to 64 characters, not blank "
                         "and without control characters")  # fmt: skip
    if runs_root is not None and not Path(runs_root).is_dir():
        what = "a file" if Path(runs_root).exists() else "not there"
        raise UsageError(f"--runs-root {runs_root}: {what}; the folder the run files lie in now")


def run(args: argparse.Namespace) -> int:

    if args.report:  # refuse a report that cannot be written before solving anything
        check_output(args.report, force=args.force, inputs=[args.config] if args.config else [])
    sel = Selection(stand=args.stand, rotor_type=args.rotor_type, since=args.since,
                    until=args.until, serial=args.serial, from_run=args.from_run,
                    kind=args.kind)  # fmt: skip
    _check_names(args.revision, args.runs_root)
    req = Request(sel, args.revision, args.config, args.runs_root, args.force)
    if args.scheduler and args.jobs is not None:
        raise UsageError("--jobs and --scheduler: one or the other (a cluster has its workers)")
    engine: Any = DaskEngine(args.scheduler) if args.scheduler else (
        LocalEngine(default_jobs() if args.jobs is None else args.jobs))  # fmt: skip
    try:
        if engine.dashboard:
            print(f"the cluster's dashboard: {engine.dashboard}", file=sys.stderr)
        out = reprocess(url_for(args.archive), req, engine, Progress())
    finally:
        engine.close()
    if args.report:
        write_text_output(args.report, render_reprocess(out), force=args.force)
    if args.json:
        dump_json(out)
    else:
        _text(out, args.config)
        if args.report:
            print(f"report: {args.report}")
    return 0


def _text(out: dict[str, Any], config: str | None) -> None:
    c = out["counts"]
    how = f"with {config}" if config else "each with its own stored config"
    print(
        f"revision {out['revision']}: {c['runs']} runs re-judged {how} "
        f"({c['solved_now']} solved now, {c['already_in_revision']} in it before)"
    )
    print(
        "  "
        + ", ".join(
            f"{k} {c[k]}"
            for k in ("ok", "missing", "altered", "unreadable", "refused", "pending")
            if k in c
        )
    )
    print(
        f"  verdicts changed in {c['verdicts_changed']} runs; {c['serials']} rotors, "
        f"{c['recall']} now out of tolerance, {c['cleared']} now within"
    )
    for r in out["runs"]:
        if r["status"] not in ("ok", "pending"):
            print(f"  run {r['run_id']} {r['status']}: {r.get('reason')}")
    changed = [r for r in out["runs"] if "after" in r
               and r["after"]["verdict"] != r["before"]["verdict"]]  # fmt: skip
    if changed:
        print("runs whose verdict changed (plane: archived -> new g mm, +- the new 95 %):")
        for r in changed:
            planes = "; ".join(
                f"{b['plane']}: {b['unbalance_g_mm']:.1f} -> {a['unbalance_g_mm']:.1f} "
                f"+- {a['uncertainty_g_mm']:.1f}"
                for b, a in zip(r["before"]["planes"], r["after"]["planes"], strict=False)
            )
            print(f"  run {r['run_id']:>6}  {r['serial'] or '-':<12} {r['kind']:<10} {planes}  "
                  f"{r['before']['verdict']} -> {r['after']['verdict']}")  # fmt: skip
    if out["recall"]:
        print(f"RECALL: {len(out['recall'])} rotors passed and fail or are undecided now:")
        print("  " + ", ".join(out["recall"]))
    else:
        print("recall: none (no rotor that passed is out of tolerance now)")
    if out["cleared"]:
        print("failed and within tolerance now: " + ", ".join(out["cleared"]))
