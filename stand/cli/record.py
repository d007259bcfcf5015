"""Record the sensor nodes from a CAN bus into an HDF5 run file, as frames arrive."""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path
from typing import Any

from stand import __version__
from stand.cli.common import UsageError, add_bus_arguments, add_live_arguments, bus_kwargs
from stand.core import Diagnostic
from stand.errors import BusError, BusTimeoutError

STATUS_EVERY_S = 1.0
SPEED_WINDOW_S = 2.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, metavar="RUN.h5", help="run file to create")
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration (its [bus] table, and it is stored in the run)",
    )
    p.add_argument("--seconds", type=float, help="stop after this long [s] (default: Ctrl-C)")
    add_live_arguments(p)
    p.add_argument("--json", action="store_true", help="print the run's summary as JSON")
    add_bus_arguments(p)


def speed_line(window: collections.deque[Any], elapsed: float, frames: int) -> str:
    from drivers.protocol import Frames
    from drivers.streams import rebuild

    recent = rebuild(Frames.concat([b for _, b in window]), strict_status=False)
    nodes = []
    for n, s in sorted(recent.nodes.items()):
        rpm = s.rpm()
        nodes.append(f"node {n}: " + ("no speed" if rpm is None else f"{rpm:.1f} rpm"))
    return f"  {elapsed:7.1f} s  {frames:>9} frames  " + "  ".join(nodes or ["no sensor node yet"])


def _reraise_with_path(failure: BusError, path: str, frames: int) -> BusError:
    """The bus failure, saying what was kept."""
    what = str(failure).split(": ", 1)[-1]
    if frames:
        message = f"{what}; the {frames} frames received are kept in {path}"
    else:
        message = f"{what} (nothing received, no run file written)"
    if isinstance(failure, BusTimeoutError):
        return BusTimeoutError(
            message, channel=failure.channel, timeout_s=failure.timeout_s, frames_received=frames
        )
    return BusError(message, channel=failure.channel, frames_received=frames)


def run(args: argparse.Namespace) -> int:
    from drivers.bus import BusReader, describe_bus, open_bus
    from drivers.recording import RunWriter, read_run
    from drivers.streams import rebuild
    from stand.cli.inspect import report
    from stand.config import config_from_dict, read_toml

    if args.seconds is not None and not args.seconds > 0:
        raise UsageError(f"stand record: --seconds must be > 0, got {args.seconds}")
    config_text, table = "", None
    if args.config:
        config_text, data = read_toml(args.config)
        cfg, _ = config_from_dict(data, source=args.config)
        table = cfg.bus
    kwargs = bus_kwargs(args, table)
    where = describe_bus(kwargs)
    writer = RunWriter(
        args.out,
        source=json.dumps(kwargs, default=str),
        config_toml=config_text,
        software=f"stand {__version__}",
    )
    failure: BusError | None = None
    interrupted = False
    try:
        bus = open_bus(kwargs)
    except BusError:
        writer.close()
        Path(args.out).unlink()  # nothing was received: leave no empty run behind
        raise
    reader = BusReader(bus, channel_info=where, silence_timeout_s=args.timeout)
    try:
        start = time.monotonic()
        next_status = start + STATUS_EVERY_S
        window: collections.deque[tuple[float, Any]] = collections.deque()
        if not args.quiet:
            print(f"recording {where} into {args.out} (Ctrl-C stops)", file=sys.stderr)
        while args.seconds is None or time.monotonic() - start < args.seconds:
            try:
                block = reader.read_block(0.1)
            except BusError as exc:
                failure = exc
                break
            writer.append(block)
            now = time.monotonic()
            if len(block):
                window.append((now, block))
            while window and window[0][0] < now - SPEED_WINDOW_S:
                window.popleft()
            if not args.quiet and now >= next_status:
                next_status += STATUS_EVERY_S
                print(speed_line(window, now - start, reader.frames_received), file=sys.stderr)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        reader.close()
        bus.shutdown()
        try:
            writer.append(reader.read_block(0.0))  # what came while stopping
        except BusError:
            pass
        notes = []
        if reader.overruns:
            notes.append(
                Diagnostic(
                    "host_overrun",
                    f"{reader.overruns} frames dropped: the host did not keep up",
                    float(reader.overruns),
                )
            )
        if failure is not None:
            notes.append(Diagnostic("bus_error", str(failure), float("nan")))
        writer.warn(notes)
        writer.flush()
        rec = read_run(args.out)
        streams = rebuild(rec.frames, strict_status=False) if len(rec.frames) else None
        writer.close(streams)
    if interrupted and not args.quiet:
        print("interrupted: the recording is kept", file=sys.stderr)
    rec = read_run(args.out)
    if streams is not None:
        report(rec, streams, as_json=args.json)
    if failure is not None:
        if len(rec.frames) == 0:
            Path(args.out).unlink()
        raise _reraise_with_path(failure, args.out, len(rec.frames))
    return 0
