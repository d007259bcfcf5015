"""Archived runs by serial, rotor type, order, operator, date and verdict."""

from __future__ import annotations

import argparse
import csv
import io
import sys
from typing import Any

from stand.archive import url_for
from stand.archive.query import Filters, history
from stand.cli.common import (
    add_archive_argument,
    add_date_arguments,
    add_revision_argument,
    write_text_output,
)
from stand.cli.format import dump_json
from stand.errors import UsageError

CSV_COLUMNS = (
    "id", "start_time", "serial", "order", "operator", "rotor_type", "rpm", "verdict",
    "plane1_g_mm", "plane1_angle_deg", "plane2_g_mm", "plane2_angle_deg",
    "urr1", "urr2", "checks_run", "run_file", "kind",
)  # fmt: skip


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--serial", metavar="SN")
    p.add_argument("--rotor-type", metavar="TYPE")
    p.add_argument("--order", metavar="ORDER")
    p.add_argument("--operator", metavar="NAME")
    add_date_arguments(p)
    add_revision_argument(p)
    p.add_argument("--verdict", choices=("pass", "fail", "undecided", "none"))
    p.add_argument("--stand", metavar="ID", help="runs of this stand ([stand] id)")
    p.add_argument("--limit", type=int, metavar="N", help="the newest N runs (listed oldest first)")
    add_archive_argument(p)
    out = p.add_mutually_exclusive_group()
    out.add_argument("--json", action="store_true", help="print one JSON object")
    out.add_argument("--csv", metavar="FILE", help="write a CSV table ('-': stdout)")
    p.add_argument("--force", action="store_true", help="replace --csv FILE if it exists")


def run(args: argparse.Namespace) -> int:

    if args.limit is not None and args.limit < 1:
        raise UsageError(f"--limit must be >= 1, got {args.limit}")
    f = Filters(
        serial=args.serial,
        rotor_type=args.rotor_type,
        order=args.order,
        operator=args.operator,
        since=args.since,
        until=args.until,
        verdict=args.verdict,
        limit=args.limit,
        stand=args.stand,
        revision=args.revision,
    )
    found = history(url_for(args.archive), f)
    if args.json:
        dump_json({"runs": found})
    elif args.csv:
        _csv(found, args.csv, args.force)
    else:
        _table(found)
        if args.revision:
            print(f"(verdicts and unbalances as the revision {args.revision} re-judged them: "
                  "only the runs it re-solved; URR not recomputed)")  # fmt: skip
    return 0


def _row(r: dict[str, Any]) -> list[Any]:
    p1, p2 = (r["planes"] + [{}, {}])[:2]
    return [
        r["id"], r["start_time"], r["serial"], r["order"], r["operator"], r["rotor_type"],
        r["rpm"], r["verdict"], p1.get("unbalance_g_mm"), p1.get("angle_deg"),
        p2.get("unbalance_g_mm"), p2.get("angle_deg"), p1.get("urr"), p2.get("urr"),
        r["checks_run"], r["run_file"], r["kind"],
    ]  # fmt: skip


def _csv(found: list[dict[str, Any]], path: str, force: bool) -> None:

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    w.writerows(["" if v is None else v for v in _row(r)] for r in found)
    if path == "-":
        sys.stdout.write(buf.getvalue())
    else:
        write_text_output(path, buf.getvalue(), force=force)


def _table(found: list[dict[str, Any]]) -> None:
    if not found:
        print("no archived run matches")
        return
    print(
        f"{'run':>5}  {'time (UTC)':16}  {'serial':12} {'rotor type':12} {'rpm':>7}  "
        f"{'plane 1 [g mm]':>15} {'plane 2 [g mm]':>15}  verdict  URR 1 / 2        checks"
    )
    for r in found:
        p1, p2 = (r["planes"] + [{}, {}])[:2]
        urr = (
            f"{100 * p1['urr']:.1f} / {100 * p2['urr']:.1f} %"
            if p1.get("urr") is not None and p2.get("urr") is not None
            else "-"
        )
        print(
            f"{r['id']:>5}  {r['start_time'][:16].replace('T', ' '):16}  "
            f"{(r['serial'] or '-')[:12]:12} {(r['rotor_type'] or '-')[:12]:12} "
            f"{r['rpm']:7.1f}  {p1.get('unbalance_g_mm', 0):9.1f} {p1.get('angle_deg', 0):5.0f}° "
            f"{p2.get('unbalance_g_mm', 0):9.1f} {p2.get('angle_deg', 0):5.0f}°  "
            f"{r['verdict']:7}  {urr:16} {r['checks_run'] or '-'}"
            + ("  (tooling index run)" if r["kind"] == "tooling" else "")
        )
