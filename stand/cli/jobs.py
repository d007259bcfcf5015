"""The job orders a line's MES sent the stand over OPC UA (OPC 40001-3), as the archive
keeps them: each one's rotor, state and latest run (``stand balance --job ID`` runs one)."""

from __future__ import annotations

import argparse

from stand.archive import Archive, url_for
from stand.archive.jobs import JOB_STATES, jobs_of
from stand.cli.common import add_archive_argument
from stand.cli.format import dump_json
from stand.config import default_stand_id, load_config

COLUMNS = ("job_id", "state", "rotor_type", "serial", "order", "operator", "stored_at",
           "run_id", "verdict")  # fmt: skip


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", metavar="CFG", help="the stand's config: its [stand] id, archive")
    p.add_argument("--stand", metavar="ID", help="this stand's job orders (default: the "
                   "config's [stand] id, else this host's name)")  # fmt: skip
    p.add_argument("--state", choices=JOB_STATES, help="only the job orders in this state")
    add_archive_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    cfg = load_config(args.config)[0] if args.config else None
    stand = args.stand or (cfg.stand.stand_id() if cfg is not None else default_stand_id())
    with Archive(url_for(args.archive, cfg)) as archive:
        found = jobs_of(archive, stand, (args.state,) if args.state else None)
    if args.json:
        dump_json({"stand": stand, "jobs": found})
        return 0
    if not found:
        print(f"stand {stand}: no job orders" + (f" {args.state}" if args.state else ""))
        return 0
    print(f"stand {stand}: {len(found)} job order{'s' if len(found) != 1 else ''}")
    print("  ".join(COLUMNS))
    for j in found:
        print("  ".join("-" if j[c] is None else str(j[c]) for c in COLUMNS))
    return 0
