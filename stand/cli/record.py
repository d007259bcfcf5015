"""Record the stand's acquisition hardware from a CAN bus into an HDF5 run file, as frames
arrive (the config's ``[bus] protocol`` family; CANopen modules set up over SDO first, and
clocked by the SYNC this command sends)."""

from __future__ import annotations

import argparse
import collections
import sys
import time
from typing import Any

from stand.cli.common import add_bus_arguments, add_live_arguments, bus_kwargs, silences
from stand.cli.format import print_recording
from stand.drivers import Frames, Recording
from stand.errors import BusError, BusTimeoutError, UsageError
from stand.live import LiveSession
from stand.solve import load_config_text
from stand.solve.acquisition import Acquired, acquisition_of, default_acquisition

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


def speed_line(window: collections.deque[Any], elapsed: float, frames: int,
               acq: Acquired) -> str:  # fmt: skip
    """The speed each node saw over the last seconds (from the blocks in ``window``, read by
    the family ``acq``)."""

    builder = acq.builder()
    builder.add(Frames.concat([b for _, b in window]))
    recent = builder.streams(strict_status=False, release=True)
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


def _record(args: argparse.Namespace, session: Any, acq: Acquired) -> None:
    """Read the bus until stopped (Ctrl-C, --seconds, a failure), a speed line every
    :data:`STATUS_EVERY_S` on stderr (its streams by the family ``acq``)."""

    next_status = STATUS_EVERY_S
    window: collections.deque[tuple[float, Any]] = collections.deque()
    if not args.quiet:
        print(f"recording {session.where} into {args.out} (Ctrl-C stops)", file=sys.stderr)
    while not session.stopping and (args.seconds is None or session.elapsed_s < args.seconds):
        before = session.builder.frames
        session.read(0.1)
        now = time.monotonic()
        if session.builder.frames > before:
            window.append((now, session.builder.last_block))
        while window and window[0][0] < now - SPEED_WINDOW_S:
            window.popleft()
        if not args.quiet and session.elapsed_s >= next_status:
            next_status += STATUS_EVERY_S
            line = speed_line(window, session.elapsed_s, session.frames_received, acq)
            print(line, file=sys.stderr)


def run(args: argparse.Namespace) -> int:

    if args.seconds is not None and not args.seconds > 0:
        raise UsageError(f"stand record: --seconds must be > 0, got {args.seconds}")
    config_text, table, acq = "", None, default_acquisition()
    if args.config:
        cfg, _, config_text = load_config_text(args.config)
        table, acq = cfg.bus, acquisition_of(cfg, args.config)
    kwargs = bus_kwargs(args, table)
    with LiveSession(
        kwargs, args.out, config_toml=config_text, silence_timeout_s=silences(args)[0],
        first_frame_s=silences(args)[1],
        acquisition=acq,
    ) as session:  # fmt: skip
        _record(args, session, acq)
    streams = session.close()
    frames = session.builder.frames
    if session.stop_signal is not None and not args.quiet:
        print("interrupted: the recording is kept", file=sys.stderr)
    if streams is not None:
        w = session.writer
        meta = {
            "software": w.software,
            "start_time": w.start_time,
            "end_time": w.end_time,
            "source": w.source,
            "complete": True,
        }
        print_recording(
            Recording(args.out, Frames.empty(), meta, w.warnings), streams, as_json=args.json
        )
    failure = session.failure
    if isinstance(failure, BusTimeoutError) and frames:  # the sender stopped: a normal end
        if not args.quiet:
            print(
                f"the frames stopped (none for {failure.timeout_s:g} s): the recording ends",
                file=sys.stderr,
            )
        return 0
    if failure is not None:
        raise _reraise_with_path(failure, args.out, frames)
    if session.reader.frames_received == 0:  # stopped (--seconds, Ctrl-C) before any frame
        raise BusError(f"nothing received in {session.elapsed_s:.1f} s: no run file written",
                       channel=session.where, frames_received=0)  # fmt: skip
    return 0
