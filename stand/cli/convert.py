"""Convert a run between a run file (.h5) and python-can logs (.log .asc .blf ...)."""

from __future__ import annotations

import argparse
from pathlib import Path

from stand.errors import RecordingError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", metavar="IN", help="run file (.h5) or python-can log")
    p.add_argument("dest", metavar="OUT", help="output; the format follows the extension")
    p.add_argument("--force", action="store_true", help="replace OUT if it exists")


def run(args: argparse.Namespace) -> int:
    from stand.drivers.recording import read_recording, write_recording
    from stand.drivers.streams import rebuild

    if Path(args.dest).exists() and not args.force:
        raise RecordingError("exists already (use --force to replace it)", path=args.dest)
    if Path(args.dest).resolve() == Path(args.source).resolve():
        raise RecordingError("is both input and output", path=args.dest)
    rec = read_recording(args.source)
    if Path(args.dest).exists():
        Path(args.dest).unlink()
    streams = rebuild(rec.frames, strict_status=False) if len(rec.frames) else None
    write_recording(rec, args.dest, streams)
    print(f"{args.dest}: {len(rec.frames)} frames from {args.source}")
    return 0
