"""Export archived results for a plant's quality system: Q-DAS (AQDEF ``.dfq``)."""

from __future__ import annotations

import argparse
import sys

from stand.archive import url_for
from stand.archive.query import Filters
from stand.cli.common import add_archive_argument, add_date_arguments, add_revision_argument
from stand.config import load_config
from stand.errors import UsageError
from stand.plant import export_qdas
from stand.plant.qdas.evaluations import FIGURES, export_evaluations


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("format", choices=("qdas",), help="qdas: the Q-DAS ASCII transfer format")
    target = p.add_mutually_exclusive_group(required=True)
    target.add_argument("--rotor-type", metavar="TYPE", help="the rotor type")
    target.add_argument(
        "--evaluations", action="store_true",
        help="the stand's machine evaluations (ISO 21940-21, stand evaluate) instead of rotors",
    )  # fmt: skip
    add_date_arguments(p)
    add_revision_argument(p)
    p.add_argument("--stand", metavar="ID", help="this stand's runs only")
    add_archive_argument(p)
    p.add_argument("-o", "--out", metavar="FILE.dfq", required=True, help="the file to write")
    p.add_argument("--force", action="store_true", help="replace FILE if it exists")
    p.add_argument(
        "--runs", action="store_true",
        help="one value line per run (each labelled first or check), not one per rotor",
    )  # fmt: skip
    p.add_argument(
        "--config", metavar="CFG", help="the stand's config: its [plant] qdas_timezone, archive"
    )
    p.add_argument(
        "--timezone", metavar="ZONE",
        help="IANA time zone of the dates (default: the config's [plant] qdas_timezone, else "
        "this machine's)",
    )  # fmt: skip


def run(args: argparse.Namespace) -> int:

    cfg = load_config(args.config)[0] if args.config else None
    zone = args.timezone  # "" is a zone named wrongly, refused: never the machine's in silence
    if zone is None and cfg is not None and cfg.plant is not None:
        zone = cfg.plant.qdas_timezone
    if args.evaluations:
        if args.runs or args.since or args.until or args.revision:
            raise UsageError("export qdas --evaluations: every evaluation of one stand; no "
                             "--runs, --since, --until or --revision")  # fmt: skip
        _, n = export_evaluations(url_for(args.archive, cfg), args.stand, args.out,
                                  force=args.force, timezone=zone)  # fmt: skip
        print(f"wrote {args.out}: {n} machine evaluations (Q-DAS, {len(FIGURES)} characteristics)")
        return 0
    f = Filters(since=args.since, until=args.until, stand=args.stand, revision=args.revision)
    done = export_qdas(url_for(args.archive, cfg), args.rotor_type, f, args.out,
                       force=args.force, runs=args.runs, timezone=zone)  # fmt: skip
    what = "runs" if args.runs else "rotors"
    print(f"wrote {args.out}: {done.lines} {what} of rotor type {args.rotor_type} (Q-DAS, 8 "
          "characteristics)")  # fmt: skip
    if done.without_serial:
        print(f"left out {done.without_serial} {what} without a serial: a Q-DAS part is known by "
              "its serial (K0014)", file=sys.stderr)  # fmt: skip
    return 0
