"""What a run file or CAN log holds: nodes, frames, losses, speed, warnings; and the
configuration a run file carries (``--config-out``), to recalibrate or reprocess with."""

from __future__ import annotations

import argparse

from stand.cli.common import write_text_output
from stand.cli.format import print_recording
from stand.drivers import read_recording
from stand.errors import RecordingError
from stand.solve import stored_streams


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "path", metavar="RUN", help="run file (.h5) or python-can log (.log .asc .blf ...)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--config-out",
        metavar="CFG.toml",
        help="write the configuration the run file carries (the one it was solved with) "
        "to this file",
    )
    p.add_argument("--force", action="store_true", help="replace --config-out if it exists")


def run(args: argparse.Namespace) -> int:

    rec = read_recording(args.path)
    if args.config_out:
        text = str(rec.meta.get("config_toml") or "")
        if not text:
            raise RecordingError("carries no configuration", path=args.path)
        write_text_output(args.config_out, text, force=args.force, inputs=[args.path])
        print(f"wrote {args.config_out}")
        return 0
    if len(rec.frames) == 0:
        raise RecordingError("no frames in the file", path=args.path)
    streams = stored_streams(rec)  # as the configuration it carries reads its frames
    if not streams.nodes:
        raise RecordingError(
            f"no sensor-node frames: {len(rec.frames)} frames, none with a protocol id "
            "(0x101-0x10F, 0x141-0x14F, 0x181-0x18F, DLC 8), nor of the stored "
            "configuration's [bus] protocol",
            path=args.path,
        )
    print_recording(rec, streams, as_json=args.json)
    return 0
