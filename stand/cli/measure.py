"""Measure live until the unbalance is precise enough (or a time limit), recording the run."""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from stand import __version__
from stand.cli.common import (
    UsageError,
    add_bus_arguments,
    add_live_arguments,
    bus_kwargs,
    print_warnings,
)
from stand.cli.solve import (
    add_measure_arguments,
    corrections,
    result,
    show,
)
from stand.errors import BusError

DEFAULT_TARGET_PCT = 5.0
CHECK_EVERY_S = 1.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--scene",
        metavar="SCENE",
        help="measure the simulated stand: a shipped scene or a scene file, "
        "played in real time on a private virtual bus",
    )
    p.add_argument("--config", metavar="CFG", help="stand configuration with its [bus] table")
    tgt = p.add_mutually_exclusive_group()
    tgt.add_argument(
        "--target-pct",
        type=float,
        help=f"stop when each plane's 95 %% interval is below this %% of its "
        f"unbalance (default {DEFAULT_TARGET_PCT:g})",
    )
    tgt.add_argument(
        "--target-g-mm",
        type=float,
        help="stop when each plane's 95 %% interval is below this [g mm]",
    )
    p.add_argument(
        "--max-seconds",
        type=float,
        default=60.0,
        help="stop after this long in any case (default 60)",
    )
    p.add_argument(
        "--out", metavar="RUN.h5", help="run file to record into (default run-YYYYmmdd-HHMMSS.h5)"
    )
    add_live_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_measure_arguments(p)
    add_bus_arguments(p)


def _source(args: argparse.Namespace, command: str) -> tuple[Any, Any, dict[str, Any], Any]:
    """Config, parameters, bus options and (for a scene) the frames to play."""
    from stand.config import load_config

    if args.scene:
        from stand.sim import load_scene, simulate

        scene, params, _ = load_scene(args.scene)
        frames = simulate(scene, params).frames
        channel = f"stand-measure-{os.getpid()}-{time.monotonic_ns()}"
        return scene.config(), params, {"interface": "virtual", "channel": channel}, frames
    if not args.config:
        raise UsageError(f"stand {command}: give --config CFG (with its [bus] table) or --scene")
    cfg, params = load_config(args.config)
    return cfg, params, bus_kwargs(args, cfg.bus), None


@dataclass
class Live:
    """A live measurement's outcome."""

    cfg: Any
    params: Any
    final: Any
    warnings: list[Any]
    stopped_by: str
    elapsed_s: float
    run_file: str


def live(
    args: argparse.Namespace,
    command: str,
    targets: Callable[[Any, Any, Any], list[float]],
) -> Live:
    """Measure live (or a scene in real time) until ``targets(cfg, params, U)`` are met.

    Records the run; shows the progress; returns the final measurement.
    """
    from drivers.bus import BusReader, describe_bus, open_bus, play
    from drivers.protocol import Frames
    from drivers.recording import RunWriter
    from drivers.streams import rebuild
    from stand.config import config_toml
    from stand.measure import MeasurementError, measure

    for name in ("target_pct", "target_g_mm", "max_seconds"):
        value = getattr(args, name)
        if value is not None and not value > 0:
            flag = "--" + name.replace("_", "-")
            raise UsageError(f"stand {command}: {flag} must be > 0, got {value}")
    cfg, params, kwargs, scene_frames = _source(args, command)
    out_path = args.out or f"run-{dt.datetime.now():%Y%m%d-%H%M%S}.h5"
    where = describe_bus(kwargs)
    writer = RunWriter(
        out_path,
        source=json.dumps(kwargs, default=str),
        config_toml=config_toml(cfg),
        software=f"stand {__version__}",
    )
    bus = open_bus(kwargs)
    player = None
    stop_player = threading.Event()
    if scene_frames is not None:
        tx = open_bus(kwargs)
        player = threading.Thread(
            target=lambda: (play(tx, scene_frames, stop=stop_player), tx.shutdown()), daemon=True
        )
    reader = BusReader(bus, channel_info=where, silence_timeout_s=args.timeout)
    if player is not None:
        player.start()
    blocks: list[Frames] = []
    stopped_by = "time limit"
    last: Any = None
    start = time.monotonic()
    next_check = start + CHECK_EVERY_S
    if not args.quiet:
        print(f"measuring on {where}, recording into {out_path} (Ctrl-C stops)", file=sys.stderr)
    try:
        while time.monotonic() - start < args.max_seconds:
            try:
                block = reader.read_block(0.1)
            except BusError as exc:
                stopped_by = "frames stopped" if reader.frames_received else "no frames"
                if not args.quiet or not reader.frames_received:
                    print(f"stand: {exc}", file=sys.stderr)
                break
            writer.append(block)
            blocks.append(block)
            if time.monotonic() < next_check:
                continue
            next_check += CHECK_EVERY_S
            elapsed = time.monotonic() - start
            try:
                m = measure(
                    rebuild(Frames.concat(blocks), strict_status=False),
                    params,
                    **cfg.measure_options(),
                    taper=args.taper,
                    gate=not args.no_gate,
                )
            except (MeasurementError, BusError, ValueError) as exc:
                if not args.quiet:
                    print(f"  {elapsed:5.1f} s  waiting: {exc}", file=sys.stderr)
                continue
            last = m
            goal = targets(cfg, params, m.solution.U_kg_m)
            short = any(w.code == "short_window" for w in m.warnings)
            if not args.quiet:
                planes = "  ".join(
                    f"plane {i + 1}: {abs(m.solution.U_kg_m[i]) * 1e6:.1f} "
                    f"+- {m.radius95_kg_m[i] * 1e6:.1f} (target {goal[i] * 1e6:.1f}) g mm"
                    for i in range(2)
                )
                amps = " ".join(f"{abs(ph.A_m_s2):.3f}" for ph in m.supports)
                print(
                    f"  {elapsed:5.1f} s  {m.rpm:7.1f} rpm  1x {amps} m/s2  {planes}",
                    file=sys.stderr,
                )
            if not short and all(m.radius95_kg_m[i] <= goal[i] for i in range(2)):
                stopped_by = "precision"
                break
    except KeyboardInterrupt:
        stopped_by = "interrupted"
    finally:
        stop_player.set()
        reader.close()
        bus.shutdown()
        frames = Frames.concat(blocks)
        writer.append(Frames.empty())
        streams = rebuild(frames, strict_status=False) if len(frames) else None
        writer.close(streams)
    elapsed = time.monotonic() - start
    if streams is None:
        raise BusError("nothing received: no result; no run recorded", channel=where)
    try:
        final = measure(
            rebuild(frames),
            params,
            **cfg.measure_options(),
            taper=args.taper,
            gate=not args.no_gate,
        )
    except MeasurementError:
        if last is None:
            raise
        final = last
    return Live(
        cfg, params, final, [*streams.warnings, *final.warnings], stopped_by, elapsed, out_path
    )


def relative_targets(args: argparse.Namespace, U: Any) -> list[float] | None:
    """The targets given on the command line [kg m], if any."""
    if args.target_g_mm is not None:
        return [args.target_g_mm * 1e-6] * 2
    if args.target_pct is not None:
        return [args.target_pct / 100 * abs(u) for u in U]
    return None


def run(args: argparse.Namespace) -> int:
    lv = live(
        args,
        "measure",
        lambda cfg, params, U: (
            relative_targets(args, U) or [DEFAULT_TARGET_PCT / 100 * abs(u) for u in U]
        ),
    )
    emit(
        args,
        lv,
        relative_targets(args, lv.final.solution.U_kg_m)
        or [DEFAULT_TARGET_PCT / 100 * abs(u) for u in lv.final.solution.U_kg_m],
    )
    return 0


def emit(
    args: argparse.Namespace, lv: Live, targets: list[float], extra: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Print the result of a live measurement (and return it)."""
    out = result(lv.final, lv.warnings)
    out.update(corrections(lv.final, lv.cfg, lv.params))
    out.update(
        {
            "stopped_by": lv.stopped_by,
            "elapsed_s": round(lv.elapsed_s, 3),
            "targets_g_mm": [round(t * 1e6, 3) for t in targets],
            "run_file": lv.run_file,
        }
    )
    out.update(extra or {})
    if show(out, args.json):
        print(f"stopped by: {lv.stopped_by} after {lv.elapsed_s:.1f} s; recorded in {lv.run_file}")
        print_warnings(lv.warnings)
    return out
