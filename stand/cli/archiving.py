"""The CLI's archive options: ``--archive URL`` and what a measuring command does with a
result there (archived, then published over MQTT when the config says so).  Apart from
:mod:`stand.cli.common` so that a command that never archives (``stand solve``) does not
load the database layer (SQLAlchemy: about 0.16 s)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from stand.archive import archive_result, url_for
from stand.errors import ArchiveError
from stand.plant import publish_archived


def archive_live(args: argparse.Namespace, result: Any, cfg: Any) -> None:
    """Archive a live run (unless ``--no-archive``); say where on stderr."""
    if args.no_archive or not result.provenance.run_file:
        return
    url = archive_url(args, cfg)
    try:
        run_id = archive_result(result, url, config=args.config)
    except ArchiveError as exc:
        raise ArchiveError(
            f"{str(exc).split(': ', 1)[1]} (the run is kept in {result.provenance.run_file}: "
            "stand archive import it later)",
            url=exc.url,
        ) from exc
    if not args.quiet:
        print(f"archived as run {run_id}", file=sys.stderr)

    said = publish_archived(result, cfg)
    if said and (not args.quiet or said.startswith("not")):
        print(said, file=sys.stderr)


def archive_url(args: argparse.Namespace, cfg: Any = None) -> str:
    """The archive the options (or the config) name."""
    return url_for(getattr(args, "archive", None), cfg)
