"""Convert a run between a run file (.h5) and python-can logs (.log .asc .blf ...)."""

from __future__ import annotations

import argparse

from stand.drivers import read_recording, write_recording
from stand.files import check_output
from stand.solve import stored_streams


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", metavar="IN", help="run file (.h5) or python-can log")
    p.add_argument("dest", metavar="OUT", help="output; the format follows the extension")
    p.add_argument("--force", action="store_true", help="replace OUT if it exists")


def run(args: argparse.Namespace) -> int:

    check_output(args.dest, force=args.force, inputs=[args.source])  # before reading
    rec = read_recording(args.source)
    streams = stored_streams(rec) if len(rec.frames) else None  # its own family's
    write_recording(rec, args.dest, streams, force=args.force, inputs=[args.source])
    print(f"{args.dest}: {len(rec.frames)} frames from {args.source}")
    return 0
