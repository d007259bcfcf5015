"""The archive: import runs recorded before, verify the archived run files."""

from __future__ import annotations

import argparse
import sys

from stand.actions import import_runs
from stand.archive import url_for, verify
from stand.cli.common import actor_of, add_actor_arguments, add_archive_argument
from stand.cli.format import dump_json
from stand.config import load_config
from stand.errors import UsageError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "action",
        choices=("import", "verify"),
        help="import: add runs recorded before; verify: find archived run files that are "
        "missing or altered",
    )
    p.add_argument("runs", nargs="*", metavar="RUN", help="the runs to import")
    p.add_argument(
        "--config", metavar="CFG",
        help="solve imported runs with this config (default: theirs); its [archive] url is the "
        "archive unless --archive says another",
    )  # fmt: skip
    add_archive_argument(p)
    add_actor_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:

    cfg = load_config(args.config)[0] if args.config else None
    url = url_for(args.archive, cfg)  # --archive, else the config's [archive] url
    if args.action == "import":
        if not args.runs:
            raise UsageError("stand archive import: give the runs to import")
        done = import_runs(args.runs, url, actor_of(args, url), args.config)
        if args.json:
            dump_json({"archive": args.archive or url, "runs": [
                {"run_file": p, "id": i} for p, i in done
            ]})  # fmt: skip
        else:
            for path, run_id in done:
                print(f"{path}: run {run_id}")
        return 0
    if args.runs:
        raise UsageError("stand archive verify: takes no runs (it checks every archived one)")
    checked, problems = verify(url)
    if args.json:
        dump_json({"checked": checked, "problems": problems})
    else:
        print(f"{checked} archived runs checked, {len(problems)} problem(s)")
        for p in problems:
            print(f"  run {p['id']}: {p['run_file']}: {p['problem']}", file=sys.stderr)
    return 1 if problems else 0
